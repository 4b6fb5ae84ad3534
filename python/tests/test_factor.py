"""NavState, predict, ImuFactor and CombinedImuFactor from Python, checked against numpy.

Expected values come from independent numpy computations: a closed-form scene (constant body
rate ω and constant body-frame specific force f, whose true states have a closed form), the
Forster residual and prediction written out in numpy from the measurement's deltas, and central
differences on the manifold with the retraction written in numpy (R Exp(δφ), p + R δp, v + δv;
bias additive).
"""

import pickle

import numpy as np
import pytest

import preint

G = np.array([0.0, 0.0, -9.81])
MODES = ("logmap", "component")


# ----------------------------------------------------------------------------- SO(3) in numpy
def hat(w):
    return np.array([[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]])


def so3_exp(w):
    th = np.linalg.norm(w)
    k = hat(w)
    if th < 1e-12:
        return np.eye(3) + k + 0.5 * k @ k
    return np.eye(3) + np.sin(th) / th * k + (1 - np.cos(th)) / th**2 * k @ k


def so3_log(r):
    c = np.clip((np.trace(r) - 1) / 2, -1.0, 1.0)
    th = np.arccos(c)
    v = np.array([r[2, 1] - r[1, 2], r[0, 2] - r[2, 0], r[1, 0] - r[0, 1]])
    if th < 1e-12:
        return 0.5 * v
    return th / (2 * np.sin(th)) * v


def jl_inv(w):
    th = np.linalg.norm(w)
    k = hat(w)
    if th < 1e-8:
        return np.eye(3) - 0.5 * k + k @ k / 12
    return np.eye(3) - 0.5 * k + (1 / th**2 - (1 + np.cos(th)) / (2 * th * np.sin(th))) * k @ k


def random_rotation(rng):
    return so3_exp(rng.normal(size=3))


# ----------------------------------------------------------------------------- the scene
W_BODY = np.array([0.3, -0.2, 0.5])  # rad/s, body frame
F_BODY = np.array([0.4, -0.3, 9.9])  # m/s², specific force, body frame
BG = np.array([0.002, -0.001, 0.003])  # rad/s
BA = np.array([0.05, -0.02, 0.04])  # m/s²
RATE_HZ = 1000
T_S = 1.0


def scene_samples():
    """Samples of the scene: gyro ω + b_g, accelerometer f + b_a (constant)."""
    n = int(T_S * RATE_HZ) + 1
    t_ns = np.arange(n, dtype=np.int64) * (1_000_000_000 // RATE_HZ)
    gyro = np.tile(W_BODY + BG, (n, 1))
    acc = np.tile(F_BODY + BA, (n, 1))
    return t_ns, gyro, acc


def scene_truth(r0, p0, v0, t):
    """Closed-form state at t: R = R0 Exp(ωt), v = v0 + gt + R0 ∫Exp(ωs)ds f,
    p = p0 + v0 t + ½gt² + R0 ∫∫Exp(ωu)du ds f."""
    th = np.linalg.norm(W_BODY)
    k = hat(W_BODY / th)
    i1 = t * np.eye(3) + (1 - np.cos(th * t)) / th * k + (t - np.sin(th * t) / th) * k @ k
    i2 = (
        0.5 * t * t * np.eye(3)
        + (t - np.sin(th * t) / th) / th * k
        + (0.5 * t * t - (1 - np.cos(th * t)) / th**2) * k @ k
    )
    r = r0 @ so3_exp(W_BODY * t)
    v = v0 + G * t + r0 @ i1 @ F_BODY
    p = p0 + v0 * t + 0.5 * G * t * t + r0 @ i2 @ F_BODY
    return r, p, v


def params(level="combined", scheme="hermite4"):
    p = preint.Params(preint.Noise(1.7e-4, 1.9e-5, 2.0e-3, 3.0e-3, float(RATE_HZ)), level=level)
    p.scheme = scheme
    p.gravity = G
    return p


def measurement(level="combined", scheme="hermite4", bias_hat=None):
    t_ns, gyro, acc = scene_samples()
    return preint.preintegrate(
        params(level, scheme), t_ns, gyro, acc, int(t_ns[0]), int(t_ns[-1]), bias_hat
    )


TRUE_BIAS = preint.ImuBias(BG, BA)


@pytest.fixture(scope="module")
def pim():
    return measurement(bias_hat=TRUE_BIAS)


@pytest.fixture(scope="module")
def states():
    """Random states i, j off the prediction, biases off the estimate."""
    rng = np.random.default_rng(7)
    ri = random_rotation(rng)
    xi = preint.NavState(ri, rng.normal(size=3), rng.normal(size=3))
    rj = ri @ so3_exp(rng.normal(size=3))
    xj = preint.NavState(rj, rng.normal(size=3) * 2, rng.normal(size=3))
    bi = preint.ImuBias(BG + rng.normal(size=3) * 0.01, BA + rng.normal(size=3) * 0.1)
    bj = preint.ImuBias(bi.gyro + rng.normal(size=3) * 1e-3, bi.acc + rng.normal(size=3) * 1e-2)
    return xi, xj, bi, bj


def retract_np(x, d):
    """NavState ⊕ [δφ, δp, δv] in numpy (the documented chart)."""
    r = x.rotation
    return preint.NavState(r @ so3_exp(d[0:3]), x.position + r @ d[3:6], x.velocity + d[6:9])


def bias_plus(b, d):
    return preint.ImuBias(b.gyro + d[0:3], b.acc + d[3:6])


def assert_close(a, b, rtol, what=""):
    a, b = np.asarray(a), np.asarray(b)
    err = np.abs(a - b).max() / (1.0 + np.abs(b).max())
    assert err <= rtol, f"{what}: relative error {err:.2e} > {rtol:.0e}\nours {a}\nexpected {b}"


# ----------------------------------------------------------------------------- NavState
def test_navstate_retract_local_match_numpy_chart(states):
    xi, xj, _, _ = states
    d = np.array([0.1, -0.2, 0.3, 1.0, 2.0, -1.0, 0.5, 0.1, -0.3])
    got = xi.retract(d)
    want = retract_np(xi, d)
    assert_close(got.rotation, want.rotation, 1e-15, "R")
    assert_close(got.position, want.position, 1e-15, "p")
    assert_close(got.velocity, want.velocity, 1e-15, "v")
    # local = [Log(Rᵀ R_o), Rᵀ (p_o − p), v_o − v]
    loc = xi.local(xj)
    r = xi.rotation
    want_loc = np.concatenate(
        [
            so3_log(r.T @ xj.rotation),
            r.T @ (xj.position - xi.position),
            xj.velocity - xi.velocity,
        ]
    )
    assert_close(loc, want_loc, 1e-12, "local")
    back = xi.retract(loc)
    assert_close(back.rotation, xj.rotation, 1e-12, "retract(local)")
    assert_close(back.position, xj.position, 1e-12, "retract(local)")
    assert preint.NavState.TANGENT_ORDER == ("dphi", "dp", "dv")


def test_navstate_quaternion_and_matrix_agree():
    q = np.array([0.9, 0.1, -0.3, 0.2])
    q /= np.linalg.norm(q)
    w, x, y, z = q
    r = np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )
    assert_close(preint.NavState(q, [1, 2, 3], [4, 5, 6]).rotation, r, 1e-14, "quaternion")
    s = preint.NavState(r, [1, 2, 3], [4, 5, 6])
    assert_close(s.position, [1, 2, 3], 0, "p")
    assert_close(s.velocity, [4, 5, 6], 0, "v")
    assert "NavState(" in repr(s)


def test_navstate_pickles_exactly(states):
    xi, _, _, _ = states
    y = pickle.loads(pickle.dumps(xi))
    assert y == xi
    assert np.array_equal(y.rotation, xi.rotation)
    assert np.array_equal(y.position, xi.position)
    assert y != xi.retract(np.full(9, 1e-9))


# ----------------------------------------------------------------------------- predict
def test_predict_reaches_closed_form_truth(pim):
    r0, p0, v0 = random_rotation(np.random.default_rng(3)), np.array([1.0, -2.0, 0.5]), np.array(
        [0.3, 0.1, -0.2]
    )
    xj = preint.predict(pim, preint.NavState(r0, p0, v0), TRUE_BIAS)
    r, p, v = scene_truth(r0, p0, v0, T_S)
    # hermite4 at 1 kHz on a constant-rate scene: integration error far below these bounds
    assert np.linalg.norm(so3_log(r.T @ xj.rotation)) < 1e-12
    assert np.abs(xj.velocity - v).max() < 1e-9
    assert np.abs(xj.position - p).max() < 1e-9


def test_predict_matches_numpy_forster_eq33(pim, states):
    xi, _, bi, _ = states
    dr, dv, dp = pim.corrected(bi)
    dt = pim.delta_t
    ri = xi.rotation
    got = preint.predict(pim, xi, bi)
    assert_close(got.rotation, ri @ dr, 1e-14, "R")
    assert_close(got.velocity, xi.velocity + G * dt + ri @ dv, 1e-14, "v")
    assert_close(
        got.position, xi.position + xi.velocity * dt + 0.5 * G * dt * dt + ri @ dp, 1e-14, "p"
    )
    # bias_i=None is the measurement's own estimate
    assert preint.predict(pim, xi) == preint.predict(pim, xi, pim.bias_hat)
    assert preint.predict(pim, xi) != got


# ----------------------------------------------------------------------------- residual
@pytest.mark.parametrize("mode", MODES)
def test_residual_zero_at_true_states(pim, mode):
    r0, p0, v0 = random_rotation(np.random.default_rng(5)), np.array([3.0, 1.0, -1.0]), np.array(
        [1.0, 0.5, 0.0]
    )
    r1, p1, v1 = scene_truth(r0, p0, v0, T_S)
    xi, xj = preint.NavState(r0, p0, v0), preint.NavState(r1, p1, v1)
    r = preint.ImuFactor(pim, mode).residual(xi, xj, TRUE_BIAS)
    assert np.abs(r).max() < 1e-9
    rc = preint.CombinedImuFactor(pim, mode).residual(xi, xj, TRUE_BIAS, TRUE_BIAS)
    assert np.abs(rc).max() < 1e-9
    # a 1 cm position error at j shows in r_p (component) with that size
    off = preint.NavState(r1, p1 + r1 @ np.array([0.01, 0, 0]), v1)
    r_off = preint.ImuFactor(pim, "component").residual(xi, off, TRUE_BIAS)
    assert_close(r_off[6:9], r0.T @ r1 @ np.array([0.01, 0, 0]), 1e-8, "r_p")


def residual_np(pim, xi, xj, b, mode):
    """Forster eq. 45 (component) or its SE₂(3) Logmap form, from the corrected deltas."""
    dr, dv, dp = pim.corrected(b)
    dt = pim.delta_t
    ri = xi.rotation
    r_phi = so3_log(dr.T @ ri.T @ xj.rotation)
    r_v = ri.T @ (xj.velocity - xi.velocity - G * dt) - dv
    r_p = ri.T @ (xj.position - xi.position - xi.velocity * dt - 0.5 * G * dt * dt) - dp
    if mode == "logmap":
        ji = jl_inv(r_phi)
        r_v, r_p = ji @ dr.T @ r_v, ji @ dr.T @ r_p
    return np.concatenate([r_phi, r_v, r_p])


@pytest.mark.parametrize("mode", MODES)
def test_residual_matches_numpy_formula(pim, states, mode):
    xi, xj, bi, bj = states
    want = residual_np(pim, xi, xj, bi, mode)
    assert np.abs(want).max() > 0.1  # a non-trivial residual
    assert_close(preint.ImuFactor(pim, mode).residual(xi, xj, bi), want, 1e-12, "9")
    rc = preint.CombinedImuFactor(pim, mode).residual(xi, xj, bi, bj)
    assert_close(rc[:9], want, 1e-12, "15: first nine")
    assert_close(rc[9:12], bj.gyro - bi.gyro, 1e-15, "r_bg")
    assert_close(rc[12:15], bj.acc - bi.acc, 1e-15, "r_ba")


# ----------------------------------------------------------------------------- Jacobians
def numeric_jacobians(fn, xi, xj, bi, bj, h=1e-6):
    """Central differences of fn(xi, xj, bi, bj) on the manifold, per variable."""

    def diff(perturb, dim):
        cols = []
        for k in range(dim):
            d = np.zeros(dim)
            d[k] = h
            cols.append((fn(*perturb(d)) - fn(*perturb(-d))) / (2 * h))
        return np.stack(cols, axis=1)

    return {
        "state_i": diff(lambda d: (retract_np(xi, d), xj, bi, bj), 9),
        "state_j": diff(lambda d: (xi, retract_np(xj, d), bi, bj), 9),
        "bias_i": diff(lambda d: (xi, xj, bias_plus(bi, d), bj), 6),
        "bias_j": diff(lambda d: (xi, xj, bi, bias_plus(bj, d)), 6),
    }


@pytest.fixture(scope="module")
def pim_rotating():
    """The scene's measurement in a navigation frame rotating at ω_n (Coriolis mode "exact")."""
    p = params()
    p.omega_coriolis = [0.0, 0.02, 0.05]
    t_ns, gyro, acc = scene_samples()
    return preint.preintegrate(p, t_ns, gyro, acc, int(t_ns[0]), int(t_ns[-1]), TRUE_BIAS)


@pytest.mark.parametrize("frame", ["inertial", "rotating"])
@pytest.mark.parametrize("mode", MODES)
def test_imu_factor_jacobians_match_central_differences(request, states, mode, frame):
    pim = request.getfixturevalue("pim" if frame == "inertial" else "pim_rotating")
    xi, xj, bi, bj = states
    f = preint.ImuFactor(pim, mode)
    r, jac = f.evaluate(xi, xj, bi)
    assert_close(r, f.residual(xi, xj, bi), 0, "evaluate residual")
    assert sorted(jac) == ["bias_i", "state_i", "state_j"]
    num = numeric_jacobians(lambda a, b, c, _d: f.residual(a, b, c), xi, xj, bi, bj)
    for name in jac:
        assert jac[name].shape == num[name].shape
        assert_close(jac[name], num[name], 1e-7, f"{mode} {name}")


@pytest.mark.parametrize("frame", ["inertial", "rotating"])
@pytest.mark.parametrize("mode", MODES)
def test_combined_factor_jacobians_match_central_differences(request, states, mode, frame):
    pim = request.getfixturevalue("pim" if frame == "inertial" else "pim_rotating")
    xi, xj, bi, bj = states
    f = preint.CombinedImuFactor(pim, mode)
    _, jac = f.evaluate(xi, xj, bi, bj)
    assert sorted(jac) == ["bias_i", "bias_j", "state_i", "state_j"]
    num = numeric_jacobians(f.residual, xi, xj, bi, bj)
    for name in jac:
        assert jac[name].shape == (15, 9 if name.startswith("state") else 6)
        assert_close(jac[name], num[name], 1e-7, f"{mode} {name}")


# ----------------------------------------------------------------------------- whitening, χ²
@pytest.mark.parametrize("mode", MODES)
@pytest.mark.parametrize("combined", [False, True])
def test_whitening_and_chi2(pim, states, mode, combined):
    xi, xj, bi, bj = states
    f = preint.CombinedImuFactor(pim, mode) if combined else preint.ImuFactor(pim, mode)
    args = (xi, xj, bi, bj) if combined else (xi, xj, bi)
    n = 15 if combined else 9
    u, cov = f.sqrt_information, f.residual_covariance
    assert u.shape == cov.shape == (n, n)
    assert np.allclose(u, np.triu(u), rtol=0, atol=0) and (np.diag(u) > 0).all()
    assert_close(u.T @ u @ cov, np.eye(n), 1e-8, "UᵀU = Σ⁻¹")
    r, jac = f.evaluate(*args)
    rw, jw = f.evaluate_whitened(*args)
    assert_close(rw, u @ r, 1e-12, "U r")
    for name in jac:
        assert_close(jw[name], u @ jac[name], 1e-12, f"U J {name}")
    chi2 = f.chi2(*args)
    assert chi2 == pytest.approx(rw @ rw, rel=1e-12)
    assert chi2 == pytest.approx(r @ np.linalg.solve(cov, r), rel=1e-8)
    assert f.cost(*args) == pytest.approx(0.5 * chi2, rel=1e-15)


def test_residual_covariance_in_each_mode(pim):
    """component: pim.cov (9) / pim.residual_cov15() (15); logmap: T Σ Tᵀ, T = diag(I, ΔRᵀ, ΔRᵀ)."""
    t = np.eye(15)
    t[3:6, 3:6] = t[6:9, 6:9] = pim.delta_R.T
    assert_close(preint.ImuFactor(pim, "component").residual_covariance, pim.cov, 0, "cov")
    assert_close(
        preint.ImuFactor(pim, "logmap").residual_covariance, t[:9, :9] @ pim.cov @ t[:9, :9].T,
        1e-14, "T cov Tᵀ",
    )
    c15 = pim.residual_cov15()
    assert_close(preint.CombinedImuFactor(pim, "component").residual_covariance, c15, 0, "c15")
    assert_close(
        preint.CombinedImuFactor(pim).residual_covariance, t @ c15 @ t.T, 1e-14, "logmap 15"
    )


# ----------------------------------------------------------------------------- modes, pickle
def test_residual_mode_names(pim):
    assert preint.ImuFactor(pim).residual_mode == "logmap"
    assert preint.ImuFactor(pim, "ComponentWise").residual_mode == "component"
    assert preint.CombinedImuFactor(pim, "component").residual_mode == "component"
    assert preint.ImuFactor.RESIDUAL_ORDER == ("r_phi", "r_v", "r_p")
    with pytest.raises(preint.ShapeError, match="unknown residual"):
        preint.ImuFactor(pim, "legacy")


@pytest.mark.parametrize("cls", [preint.ImuFactor, preint.CombinedImuFactor])
@pytest.mark.parametrize("mode", MODES)
def test_factors_pickle_exactly(pim, states, cls, mode):
    xi, xj, bi, _ = states
    f = cls(pim, mode)
    g = pickle.loads(pickle.dumps(f))
    assert g == f and g.residual_mode == mode
    assert np.array_equal(g.sqrt_information, f.sqrt_information)
    assert np.array_equal(g.residual(xi, xj, bi), f.residual(xi, xj, bi))
    assert g.pim == pim
    other = cls(pim, "component" if mode == "logmap" else "logmap")
    assert other != f


@pytest.mark.parametrize("mode", MODES)
def test_in_window_drift_weight_pickles_and_needs_the_combined_level(pim, states, mode):
    """``ImuFactor(pim, in_window_drift=True)`` weights by ``pim.cov15[:9, :9]`` (component
    form), which exceeds ``pim.cov``; it pickles as itself, not as the plain factor; a
    level-"covariance" measurement and a ``CombinedImuFactor`` refuse it."""
    xi, xj, bi, _ = states
    f = preint.ImuFactor(pim, mode, in_window_drift=True)
    plain = preint.ImuFactor(pim, mode)
    assert f.in_window_drift and not plain.in_window_drift and f != plain
    if mode == "component":
        assert np.array_equal(f.residual_covariance, pim.cov15[:9, :9])
    assert np.trace(f.residual_covariance) > np.trace(plain.residual_covariance)
    assert f.chi2(xi, xj, bi) < plain.chi2(xi, xj, bi)
    g = pickle.loads(pickle.dumps(f))
    assert g == f and g.in_window_drift and g.residual_mode == mode
    assert np.array_equal(g.sqrt_information, f.sqrt_information)
    with pytest.raises(preint.FactorError) as e:
        preint.ImuFactor(measurement(level="covariance"), mode, in_window_drift=True)
    assert e.value.kind == "LevelTooLow"
    with pytest.raises(preint.FactorError) as e:
        preint.CombinedImuFactor(pim, mode, in_window_drift=True)
    assert e.value.kind == "InWindowDrift"
    assert preint.CombinedImuFactor(pim, mode).in_window_drift


# ----------------------------------------------------------------------------- errors
def test_factor_errors_are_typed(pim):
    with pytest.raises(preint.FactorError) as e:
        preint.ImuFactor(measurement(level="deltas"))
    assert e.value.kind == "LevelTooLow" and isinstance(e.value, ValueError)
    with pytest.raises(preint.FactorError) as e:
        preint.CombinedImuFactor(measurement(level="covariance"))
    assert e.value.kind == "LevelTooLow"
    # zero noise (covariances set to 0; a Noise refuses zero densities): no square-root
    # information
    p = preint.Params()
    for name in ("gyroscope_covariance", "accelerometer_covariance", "bias_gyro_covariance", "bias_acc_covariance"):
        setattr(p, name, 0.0)
    t_ns, gyro, acc = scene_samples()
    zero = preint.preintegrate(p, t_ns, gyro, acc, int(t_ns[0]), int(t_ns[-1]))
    with pytest.raises(preint.FactorError) as e:
        preint.ImuFactor(zero)
    assert e.value.kind == "CovarianceNotPositiveDefinite"
    assert "positive definite" in str(e.value)
    # a zero bias random walk leaves cov15 singular
    p = preint.Params(preint.Noise(1.7e-4, 0.0, 2.0e-3, 0.0, float(RATE_HZ)))
    no_rw = preint.preintegrate(p, t_ns, gyro, acc, int(t_ns[0]), int(t_ns[-1]))
    preint.ImuFactor(no_rw)  # 9-dim is fine
    with pytest.raises(preint.FactorError):
        preint.CombinedImuFactor(no_rw)


def test_navstate_errors_are_typed():
    with pytest.raises(preint.ShapeError, match="rotation"):
        preint.NavState(np.diag([1.0, 1.0, -1.0]))
    with pytest.raises(preint.ShapeError, match="unit norm"):
        preint.NavState([1.0, 1.0, 0.0, 0.0])
    with pytest.raises(preint.ShapeError, match="position"):
        preint.NavState(np.eye(3), [1.0, 2.0])
    with pytest.raises(preint.ShapeError, match="nine"):
        preint.NavState().retract(np.zeros(6))


def test_bias_defaults_and_non_finite_states(pim, states):
    xi, xj, _, _ = states
    f = preint.ImuFactor(pim)
    assert np.array_equal(f.residual(xi, xj), f.residual(xi, xj, pim.bias_hat))
    c = preint.CombinedImuFactor(pim)
    b = preint.ImuBias([0.01, 0, 0], [0, 0.1, 0])
    assert np.array_equal(c.residual(xi, xj, b), c.residual(xi, xj, b, b))
    assert np.abs(c.residual(xi, xj, b)[9:]).max() == 0.0
    # a non-finite state cannot be made (so no factor sees one)
    with pytest.raises(preint.PreintError, match=r"position\[0\] must be finite") as e:
        preint.NavState(xj.rotation, [np.nan, 0.0, 0.0], xj.velocity)
    assert e.value.kind == "InvalidParameter"
