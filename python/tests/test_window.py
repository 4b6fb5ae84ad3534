"""Inside a window: deltas at query times, the truncation-error estimate and inflation.

Expected values come from independent numpy closed forms (constant rate and specific force:
ΔR = Exp(ωt), Δv = Jl(ωt) a t, Δp = N(ωt) a t² with the series of the integrals) or from
preintegrate over the shorter window, never from the function under test.
"""

import numpy as np
import pytest

import preint


def hat(w):
    return np.array([[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]])


def exp_so3(phi):
    th = np.linalg.norm(phi)
    if th == 0.0:
        return np.eye(3)
    k = hat(phi)
    return np.eye(3) + np.sin(th) / th * k + (1 - np.cos(th)) / th**2 * k @ k


def held_truth(w, a, t):
    """Exact deltas of a constant body rate w [rad/s] and specific force a [m/s²] over t [s]:
    Δv = ∫0^t Exp(ws) a ds, Δp = ∫0^t Δv(s) ds, integrated by a fine composite Simpson rule
    on the closed-form Exp (independent of preint)."""
    n = 20001
    s = np.linspace(0.0, t, n)
    u = np.array([exp_so3(w * si) @ a if si > 0 else a for si in s])
    h = s[1] - s[0]
    wts = np.ones(n)
    wts[1:-1:2] = 4
    wts[2:-1:2] = 2
    dv = (wts[:, None] * u).sum(0) * h / 3
    # Δp = ∫ (t − s) u(s) ds.
    dp = (wts[:, None] * (t - s)[:, None] * u).sum(0) * h / 3
    return exp_so3(w * t), dv, dp


def stream(rate_hz, seconds, w, a):
    n = int(round(rate_hz * seconds)) + 1
    t = (np.arange(n, dtype=np.int64) * int(round(1e9 / rate_hz))).astype(np.int64)
    return t, np.tile(w, (n, 1)).astype(float), np.tile(a, (n, 1)).astype(float)


W = np.array([1.2, -0.8, 2.0])
A = np.array([2.0, -1.0, 0.5])


@pytest.mark.parametrize("scheme", ["euler", "midpoint", "hermite4"])
def test_deltas_at_equal_the_shorter_windows(scheme):
    p = preint.Params(scheme=scheme, level="deltas")
    t, g, a = stream(200.0, 1.0, W, A)
    q = np.array([12_345_678, 500_000_000, 777_777_777, 1_000_000_000], dtype=np.int64)
    d = preint.deltas_at(p, t, g, a, 0, 1_000_000_000, q)
    assert d["delta_R"].shape == (4, 3, 3) and d["delta_v"].shape == (4, 3)
    assert np.array_equal(d["t_ns"], q)
    for k, tq in enumerate(q):
        m = preint.preintegrate(p, t, g, a, 0, int(tq))
        # The same deltas, computed by a different pass over the samples: equal to round-off.
        assert np.abs(d["delta_R"][k] - m.delta_R).max() < 1e-13
        assert np.linalg.norm(d["delta_v"][k] - m.delta_v) < 1e-13 * np.linalg.norm(m.delta_v)
        assert np.linalg.norm(d["delta_p"][k] - m.delta_p) < 1e-13 * np.linalg.norm(m.delta_p)
        assert d["delta_t"][k] == m.delta_t


def test_deltas_at_refuses_unsorted_and_outside_queries():
    p = preint.Params(level="deltas")
    t, g, a = stream(200.0, 1.0, W, A)
    with pytest.raises(preint.PreintError) as e:
        preint.deltas_at(p, t, g, a, 0, 10**9, np.array([5 * 10**8, 10**8], dtype=np.int64))
    assert e.value.kind == "QueryNotSorted" and "query 1" in str(e.value)
    with pytest.raises(preint.PreintError) as e:
        preint.deltas_at(p, t, g, a, 0, 10**9, np.array([2 * 10**9], dtype=np.int64))
    assert e.value.kind == "QueryOutsideWindow"


@pytest.mark.parametrize("scheme", ["euler", "midpoint"])
def test_truncation_estimate_tracks_the_true_error(scheme):
    # 20 Hz, the held-input stress motion of GTSAM's experiment: Euler's and midpoint's
    # discretisation error is large and the 4th-order companion nearly exact.
    p = preint.Params(scheme=scheme, level="covariance")
    t, g, a = stream(20.0, 1.0, W, A)
    m = preint.preintegrate(p, t, g, a, 0, 10**9)
    r, dv, dp = held_truth(W, A, 1.0)
    true_err = np.concatenate(
        [
            # Log(Rᵀ ΔR) for small angles: vee of the skew part.
            0.5 * np.array(
                [
                    (r.T @ m.delta_R)[2, 1] - (r.T @ m.delta_R)[1, 2],
                    (r.T @ m.delta_R)[0, 2] - (r.T @ m.delta_R)[2, 0],
                    (r.T @ m.delta_R)[1, 0] - (r.T @ m.delta_R)[0, 1],
                ]
            ),
            m.delta_v - dv,
            m.delta_p - dp,
        ]
    )
    est, method, cov_c = preint.truncation_estimate(p, t, g, a, m)
    assert cov_c.shape == (9, 9) and np.all(np.diag(cov_c) > 0)
    assert method == "hermite4 companion"
    # The velocity and position errors are what matter at 20 Hz (cm/s … dm/s).
    for blk in (slice(3, 6), slice(6, 9)):
        assert np.linalg.norm(true_err[blk]) > 1e-3
        assert np.linalg.norm(est[blk] - true_err[blk]) < 0.02 * np.linalg.norm(true_err[blk])


def test_inflate_adds_the_outer_product():
    p = preint.Params(scheme="euler")
    t, g, a = stream(100.0, 0.5, W, A)
    m = preint.preintegrate(p, t, g, a, 0, 5 * 10**8)
    e = np.arange(1.0, 10.0) * 1e-3
    m2 = preint.inflate(m, e, residual="component")
    assert np.allclose(m2.cov - m.cov, np.outer(e, e), rtol=0, atol=1e-15)
    assert np.allclose(m2.cov15[:9, :9] - m.cov15[:9, :9], np.outer(e, e), rtol=0, atol=1e-15)
    assert np.array_equal(m2.cov15[9:, 9:], m.cov15[9:, 9:])
    with pytest.raises(preint.ShapeError):
        preint.inflate(m, [1.0, 2.0])
    with pytest.raises(preint.ShapeError):
        preint.inflate(m, [np.nan] * 9)
    with pytest.raises(preint.ShapeError):
        preint.inflate(m, e, residual="tangent")
    # The companion's covariance replaces the measurement's under the outer product.
    c = 2.0 * m.cov
    m3 = preint.inflate(m, e, residual="component", companion_cov=c)
    assert np.allclose(m3.cov, c + np.outer(e, e), rtol=0, atol=1e-15)
    assert np.allclose(m3.cov15[:9, :9] - m.cov15[:9, :9], m.cov + np.outer(e, e), rtol=0, atol=1e-15)
    with pytest.raises(preint.ShapeError):
        preint.inflate(m, e, companion_cov=np.triu(np.ones((9, 9))))


def jl_inv(phi):
    """SO(3) inverse left Jacobian, closed form (Barfoot 2017 eq. 7.45)."""
    th = np.linalg.norm(phi)
    k = hat(phi)
    return np.eye(3) - 0.5 * k + (1 / th**2 - (1 + np.cos(th)) / (2 * th * np.sin(th))) * k @ k


def test_inflate_for_the_logmap_residual_uses_the_offsets_exact_image():
    # The Logmap factor sees r_L = Log(D⁻¹ D_e) with D_e = (ΔR Exp(−e_φ), Δv − e_v, Δp − e_p),
    # weighted by T cov Tᵀ, T = diag(I, ΔRᵀ, ΔRᵀ): the vector added is u = −T⁻¹ r_L.
    p = preint.Params(scheme="euler")
    t, g, a = stream(100.0, 0.5, W, A)
    m = preint.preintegrate(p, t, g, a, 0, 5 * 10**8)
    e = np.array([0.02, -0.01, 0.015, 0.5, -0.3, 0.2, 0.1, 0.05, -0.08])
    r = m.delta_R
    shear = r @ jl_inv(-e[:3]) @ r.T
    u = np.concatenate([e[:3], shear @ e[3:6], shear @ e[6:9]])
    m2 = preint.inflate(m, e)  # the default residual, "logmap"
    assert np.allclose(m2.cov - m.cov, np.outer(u, u), rtol=0, atol=1e-14)
    # Second order: it differs from the first-order image e by about ½|e_φ||e_v|.
    assert np.abs(u - e).max() > 1e-3


def test_second_order_term_equals_the_command_lines(preint_cli, tmp_path):
    import json
    import subprocess

    from conftest import REPO, read_euroc_imu

    out = tmp_path / "sim"
    noise = tmp_path / "noise.yaml"
    noise.write_text(
        "gyroscope_noise_density: 0.015\naccelerometer_noise_density: 0.019\n"
        "gyroscope_random_walk: 1.9393e-05\naccelerometer_random_walk: 3.0e-03\nupdate_rate: 200.0\n"
    )
    sim = subprocess.run([*preint_cli, "simulate", "--scene", "aggressive", "--duration", "6",
                          "--noise", str(noise), "--out", str(out)], cwd=REPO, capture_output=True, text=True)
    assert sim.returncode == 0, sim.stderr
    ti, tj = 500_000_000, 5_500_000_000
    run = subprocess.run([*preint_cli, "integrate", "--imu", str(out / "imu.csv"), "--noise", str(noise),
                          "--scheme", "hermite4", "--from", str(ti), "--to", str(tj), "--second-order", "--json"],
                         cwd=REPO, capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    rust = json.loads(run.stdout)
    t, g, a = read_euroc_imu(out / "imu.csv")
    prm = preint.Params(preint.Noise(0.015, 1.9393e-05, 0.019, 3.0e-03), scheme="hermite4", level="combined")
    m = preint.preintegrate(prm, t, g, a, ti, tj)
    term = preint.second_order_covariance(prm, t, g, a, m)
    assert term.shape == (9, 9)
    assert term.tobytes() == np.asarray(rust["second_order"]["covariance"], dtype=np.float64).tobytes()
    assert np.linalg.eigvalsh(term).min() > -1e-12 * np.abs(term).max()
    inc = np.trace(np.linalg.solve(m.cov, term))
    assert inc == pytest.approx(rust["second_order"]["chi2_increase"], rel=1e-9)
    assert 0.02 < inc < 1.0
    m2 = preint.add_covariance(m, term)
    assert np.array_equal(m2.cov, m.cov + term)
    assert np.array_equal(m2.cov15[:9, :9], m.cov15[:9, :9] + term)
    with pytest.raises(preint.ShapeError):
        preint.add_covariance(m, np.triu(np.ones((9, 9))))
    with pytest.raises(preint.ShapeError):
        preint.add_covariance(m, np.eye(3))


def test_states_at_start_and_end():
    p = preint.Params(scheme="hermite4")
    t, g, a = stream(200.0, 1.0, W, A + np.array([0.0, 0.0, 9.81]))
    x0 = preint.NavState([1.0, 0.0, 0.0, 0.0], [1.0, 2.0, 3.0], [0.5, -0.2, 0.1])
    q = np.array([0, 400_000_000, 10**9], dtype=np.int64)
    s = preint.states_at(p, t, g, a, 0, 10**9, x0, q)
    assert s["rotation"].shape == (3, 3, 3) and s["position"].shape == (3, 3)
    # At t_i: the initial state itself.
    assert np.array_equal(s["rotation"][0], x0.rotation)
    assert np.array_equal(s["position"][0], x0.position)
    assert np.array_equal(s["velocity"][0], x0.velocity)
    # At t_j: the prediction of the whole window, to round-off.
    xj = preint.predict(preint.preintegrate(p, t, g, a, 0, 10**9), x0)
    assert np.abs(s["rotation"][2] - xj.rotation).max() < 1e-13
    assert np.linalg.norm(s["position"][2] - xj.position) < 1e-12
    assert np.linalg.norm(s["velocity"][2] - xj.velocity) < 1e-12


@pytest.mark.parametrize("target", ["start", "end"])
def test_deskew_points_of_a_spinning_sensor(target):
    # A body spinning at a constant rate in place (no gravity, no specific force): a point
    # fixed in the world, seen at time t in the body frame at t, is x(t) = Exp(ωt)ᵀ R_iᵀ (P − p_i);
    # deskewed to the start it is R_iᵀ (P − p_i) for every t, to the end Exp(ωT)ᵀ of that.
    p = preint.Params(scheme="hermite4")
    p.gravity = [0.0, 0.0, 0.0]
    t, g, a = stream(200.0, 0.1, W, np.zeros(3))
    x0 = preint.NavState(exp_so3(np.array([0.3, -0.1, 0.2])), [1.0, 2.0, 3.0], [0.0, 0.0, 0.0])
    world = np.array([4.0, -1.0, 2.5])
    local = x0.rotation.T @ (world - x0.position)
    tp = np.linspace(0, 100_000_000, 37).astype(np.int64)
    pts = np.array([exp_so3(W * (k * 1e-9)).T @ local for k in tp])
    out = preint.deskew_points(p, t, g, a, 0, 100_000_000, x0, tp, pts, target=target)
    want = local if target == "start" else exp_so3(W * 0.1).T @ local
    assert np.abs(out - want).max() < 1e-12
    with pytest.raises(preint.ShapeError):
        preint.deskew_points(p, t, g, a, 0, 100_000_000, x0, tp, pts[:3], target=target)
    bad = pts.copy()
    bad[4, 1] = np.nan
    with pytest.raises(preint.PreintError) as e:
        preint.deskew_points(p, t, g, a, 0, 100_000_000, x0, tp, bad, target=target)
    assert e.value.kind == "NonFinitePoint" and "point 4" in str(e.value)


@pytest.mark.parametrize("scheme", ["euler", "hermite4"])
def test_a_window_of_long_arrays_equals_the_window_of_its_neighbourhood(scheme):
    # Only the window's samples and a margin are converted: the results on 10⁴-sample arrays
    # equal, bit for bit, those on a slice holding the window and a few samples either side,
    # and a bad sample's index counts from the start of the caller's arrays.
    rng = np.random.default_rng(7)
    n = 10_000
    t = np.arange(n, dtype=np.int64) * 5_000_000
    g = W + 0.1 * rng.normal(size=(n, 3))
    a = A + 0.1 * rng.normal(size=(n, 3))
    p = preint.Params(scheme=scheme)
    t_i, t_j = int(t[5000]) + 1_234_567, int(t[5200]) + 2_000_000
    lo, hi = 5000 - 12, 5202 + 12
    sl = (t[lo:hi], g[lo:hi], a[lo:hi])
    q = np.array([t_i, t_i + 300_000_000, t_j], dtype=np.int64)
    x0 = preint.NavState(np.eye(3), [0.0, 0.0, 0.0], [1.0, 0.0, 0.0])
    d_long = preint.deltas_at(p, t, g, a, t_i, t_j, q)
    d_near = preint.deltas_at(p, *sl, t_i, t_j, q)
    for k in ("delta_R", "delta_v", "delta_p"):
        assert np.array_equal(d_long[k], d_near[k])
    s_long = preint.states_at(p, t, g, a, t_i, t_j, x0, q)
    s_near = preint.states_at(p, *sl, t_i, t_j, x0, q)
    for k in ("rotation", "position", "velocity"):
        assert np.array_equal(s_long[k], s_near[k])
    m = preint.preintegrate(p, t, g, a, t_i, t_j)
    e_long, _, c_long = preint.truncation_estimate(p, t, g, a, m)
    e_near, _, c_near = preint.truncation_estimate(p, *sl, m)
    assert np.array_equal(e_long, e_near)
    assert np.array_equal(c_long, c_near)
    bad = g.copy()
    bad[5100, 2] = np.inf
    with pytest.raises(preint.PreintError) as e:
        preint.deltas_at(p, t, bad, a, t_i, t_j, q)
    assert e.value.kind == "NonFinite" and "sample 5100" in str(e.value)
