"""ImuFactor, CombinedImuFactor and predict against GTSAM 4.3 (the PyPI wheel), live.

Both sides integrate the same samples: ours with the "euler" scheme, GTSAM with
`PreintegratedImuMeasurementsManifold` / `PreintegratedCombinedMeasurementsManifold` (Forster's
discretisation, sample k held over interval k), which is the same scheme.

GTSAM's `ImuFactor` / `CombinedImuFactor` accept only the wheel's tangent preintegration, so the
factors' error is evaluated with GTSAM's own formula on the manifold preintegration
(`e = Xj.logmap(pim.predict(Xi, b_i))` or `Xj.localCoordinates(...)`, chained Jacobians,
`[e, b_i − b_j]` for the combined one), and that formula is first asserted equal to the real
factors' `evaluateError` (residual and every Jacobian) on a tangent preintegration of the same
samples (`test_gtsam_formula_is_the_factors_evaluate_error`).

Mapping (preint's Rust `preint::ImuFactor` and `preint::ResidualMode` docs): GTSAM orders the
residual [rot, pos, vel(, b_a, b_g)], the pose perturbation [dw, dt] (= our [δφ, δp] to first
order, so the Jacobians are equal), velocity in the world frame (= our δv) and the bias
[acc, gyro]; our residual is [r_φ, r_v, r_p(, r_bg, r_ba)] with bias columns [gyro, acc].

- Logmap: `e = −Q r` and `∂e/∂x = −Q ∂r/∂x` exactly (`Q` the reordering), and GTSAM's
  `residualCovariance()` is `Q Σ Qᵀ` (Σ our `residual_covariance`), so the χ² are equal.
- ComponentWise (`M = R_jᵀR_i`): `e = [−r_φ, −M r_p, −M r_v(, −r_ba, −r_bg)]`; Jacobians the
  same map, plus `M [r_{p,v}]×` in the δφ_i columns and `−[M r_{p,v}]×` in the δφ_j columns.
"""

import numpy as np
import pytest

import preint

gtsam = pytest.importorskip("gtsam")

SG, SBG, SA, SBA = 1.6968e-4, 1.9393e-5, 2.0e-3, 3.0e-3  # EuRoC densities
BG_HAT = np.array([0.001, -0.002, 0.0005])
BA_HAT = np.array([0.02, -0.01, 0.03])
MODES = ("Logmap", "ComponentWise")
OURS = {"Logmap": "logmap", "ComponentWise": "component"}
TOL = 1e-9  # relative, as the issue asks


# ----------------------------------------------------------------------------- helpers
def hat(w):
    return np.array([[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]])


def jl_inv(w):
    th = np.linalg.norm(w)
    k = hat(w)
    if th < 1e-8:
        return np.eye(3) - 0.5 * k + k @ k / 12
    return np.eye(3) - 0.5 * k + (1 / th**2 - (1 + np.cos(th)) / (2 * th * np.sin(th))) * k @ k


def rel(a, b):
    """max |a − b| / max |b| (b not all zero)."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    assert a.shape == b.shape and np.abs(b).max() > 0
    return np.abs(a - b).max() / np.abs(b).max()


def stream(rate_hz=200, seconds=2.0):
    """A smooth, rotating stream (rad/s, m/s²) sampled at rate_hz."""
    step = 1_000_000_000 // rate_hz
    n = int(seconds * rate_hz) + 1
    t_ns = 1_403_636_579_758_555_392 + np.arange(n, dtype=np.int64) * step
    t = np.arange(n) * step * 1e-9
    gyro = np.stack(
        [
            0.3 * np.sin(2 * np.pi * 0.5 * t),
            0.2 * np.cos(2 * np.pi * 0.3 * t),
            0.5 * np.sin(2 * np.pi * 0.2 * t) + 0.1,
        ],
        axis=1,
    )
    acc = np.stack(
        [
            0.5 * np.sin(2 * np.pi * 0.7 * t),
            0.3 * np.cos(2 * np.pi * 0.4 * t),
            9.81 + 0.2 * np.sin(2 * np.pi * 0.9 * t),
        ],
        axis=1,
    )
    return t_ns, gyro, acc


def gtsam_params(mode, combined, omega=None):
    cls = gtsam.PreintegrationCombinedParams if combined else gtsam.PreintegrationParams
    p = cls.MakeSharedU(9.81)
    p.setGyroscopeCovariance(SG**2 * np.eye(3))
    p.setAccelerometerCovariance(SA**2 * np.eye(3))
    p.setIntegrationCovariance(np.zeros((3, 3)))
    if combined:
        p.setBiasOmegaCovariance(SBG**2 * np.eye(3))
        p.setBiasAccCovariance(SBA**2 * np.eye(3))
    if omega is not None:
        p.setOmegaCoriolis(np.asarray(omega, float))
    # The error mode is a field of the parameters (GTSAM 4.3).
    p.setImuFactorErrorMode(getattr(gtsam.ImuFactorErrorMode, mode))
    return p


def gtsam_pim(cls, params, t_ns, gyro, acc):
    pim = cls(params, gtsam.imuBias.ConstantBias(BA_HAT, BG_HAT))  # (acc, gyro)
    for k in range(len(t_ns) - 1):
        pim.integrateMeasurement(acc[k], gyro[k], (int(t_ns[k + 1]) - int(t_ns[k])) * 1e-9)
    return pim


def our_pim(t_ns, gyro, acc, omega=None):
    p = preint.Params(preint.Noise(SG, SBG, SA, SBA), scheme="euler", level="combined")
    p.gravity = [0.0, 0.0, -9.81]
    if omega is not None:
        p.omega_coriolis = omega
    return preint.preintegrate(
        p, t_ns, gyro, acc, int(t_ns[0]), int(t_ns[-1]), preint.ImuBias(BG_HAT, BA_HAT)
    )


def to_gtsam_state(x):
    return gtsam.NavState(gtsam.Rot3(x.rotation), x.position, x.velocity)


def to_gtsam_bias(b):
    return gtsam.imuBias.ConstantBias(b.acc, b.gyro)


def gtsam_formula(pim, mode, xi, xj, bi, bj=None):
    """GTSAM's (Combined)ImuFactor error and Jacobians [H_pose_i, H_vel_i, H_pose_j, H_vel_j,
    H_bias_i(, H_bias_j)] from pim.predict; velocity columns world frame."""
    h1, h2 = np.zeros((9, 9)), np.zeros((9, 6))
    pred = pim.predict(xi, bi, h1, h2)
    hj, hpred = np.zeros((9, 9)), np.zeros((9, 9))
    if mode == "Logmap":
        e9 = xj.logmap(pred, hj, hpred)
    else:
        e9 = xj.localCoordinates(pred, hj, hpred)
    hi, hb = hpred @ h1, hpred @ h2
    ri, rj = xi.attitude().matrix(), xj.attitude().matrix()
    h9 = [hi[:, :6], hi[:, 6:] @ ri.T, hj[:, :6], hj[:, 6:] @ rj.T, hb]
    if bj is None:
        return e9, h9
    h = [np.vstack([m, np.zeros((6, m.shape[1]))]) for m in h9]
    h[4][9:] = np.eye(6)
    h.append(np.vstack([np.zeros((9, 6)), -np.eye(6)]))
    return np.concatenate([e9, bi.vector() - bj.vector()]), h


# ----------------------------------------------------------------------------- scene
@pytest.fixture(scope="module")
def scene():
    t_ns, gyro, acc = stream()
    rng = np.random.default_rng(21)
    ours = our_pim(t_ns, gyro, acc)
    q = rng.normal(size=4)
    q /= np.linalg.norm(q)
    xi = preint.NavState(q, rng.normal(size=3), rng.normal(size=3))
    bi = preint.ImuBias(BG_HAT + rng.normal(size=3) * 0.002, BA_HAT + rng.normal(size=3) * 0.02)
    bj = preint.ImuBias(bi.gyro + rng.normal(size=3) * 1e-4, bi.acc + rng.normal(size=3) * 1e-2)
    pred = preint.predict(ours, xi, bi)
    # state j: the prediction moved by 0.03 rad, 5 cm and 5 cm/s
    xj = pred.retract(np.concatenate([rng.normal(size=3) * 0.03, rng.normal(size=6) * 0.05]))
    return {"t_ns": t_ns, "gyro": gyro, "acc": acc, "pim": ours,
            "xi": xi, "xj": xj, "bi": bi, "bj": bj}


def map_to_gtsam(r, jac, xi, xj, mode):
    """Our residual and Jacobian dict → GTSAM's error and [H_pose_i, H_vel_i, H_pose_j,
    H_vel_j, H_bias_i(, H_bias_j)] (module docs)."""
    n = r.size
    rows = [0, 1, 2, 6, 7, 8, 3, 4, 5] + ([12, 13, 14, 9, 10, 11] if n == 15 else [])
    m = xj.rotation.T @ xi.rotation
    big_m = np.eye(n)
    if mode == "ComponentWise":
        big_m[3:6, 3:6] = big_m[6:9, 6:9] = m

    def rowmap(b):
        return -(big_m @ b[rows])

    e = rowmap(r)
    s_i, s_j = rowmap(jac["state_i"]), rowmap(jac["state_j"])
    if mode == "ComponentWise":
        rv, rp = r[3:6], r[6:9]
        s_i[3:6, 0:3] += m @ hat(rp)
        s_i[6:9, 0:3] += m @ hat(rv)
        s_j[3:6, 0:3] -= hat(m @ rp)
        s_j[6:9, 0:3] -= hat(m @ rv)
    bias_cols = [3, 4, 5, 0, 1, 2]  # ours [gyro, acc] → GTSAM [acc, gyro]
    h = [s_i[:, 0:6], s_i[:, 6:9], s_j[:, 0:6], s_j[:, 6:9], rowmap(jac["bias_i"])[:, bias_cols]]
    if "bias_j" in jac:
        h.append(rowmap(jac["bias_j"])[:, bias_cols])
    return e, h


H_NAMES = ["H_pose_i", "H_vel_i", "H_pose_j", "H_vel_j", "H_bias_i", "H_bias_j"]


# ----------------------------------------------------------------------------- tests
@pytest.mark.parametrize("mode", MODES)
@pytest.mark.parametrize("combined", [False, True])
def test_gtsam_formula_is_the_factors_evaluate_error(scene, mode, combined):
    """The formula used below equals gtsam.(Combined)ImuFactor.evaluateError (tangent pim)."""
    s = scene
    if combined:
        params = gtsam_params(mode, True)
        pim = gtsam_pim(gtsam.PreintegratedCombinedMeasurements, params,
                        s["t_ns"], s["gyro"], s["acc"])
        fac = gtsam.CombinedImuFactor(0, 1, 2, 3, 4, 5, pim)
        shapes = [(15, 6), (15, 3), (15, 6), (15, 3), (15, 6), (15, 6)]
    else:
        pim = gtsam_pim(gtsam.PreintegratedImuMeasurements, gtsam_params(mode, False),
                        s["t_ns"], s["gyro"], s["acc"])
        fac = gtsam.ImuFactor(0, 1, 2, 3, 4, pim)
        shapes = [(9, 6), (9, 3), (9, 6), (9, 3), (9, 6)]
    xi, xj = to_gtsam_state(s["xi"]), to_gtsam_state(s["xj"])
    bi, bj = to_gtsam_bias(s["bi"]), to_gtsam_bias(s["bj"])
    hf = [np.zeros(sh) for sh in shapes]
    extra = (bj,) if combined else ()
    ef = fac.evaluateError(xi.pose(), xi.velocity(), xj.pose(), xj.velocity(), bi, *extra, *hf)
    e, h = gtsam_formula(pim, mode, xi, xj, bi, bj if combined else None)
    assert np.abs(ef).max() > 1e-3
    assert rel(e, ef) <= TOL
    for name, ours, theirs in zip(H_NAMES, h, hf):
        assert rel(ours, theirs) <= TOL, name


def test_error_mode_is_set_by_the_params():
    p = gtsam_params("ComponentWise", False)
    assert p.getImuFactorErrorMode() == gtsam.ImuFactorErrorMode.ComponentWise
    assert gtsam_params("Logmap", True).getImuFactorErrorMode() == gtsam.ImuFactorErrorMode.Logmap


@pytest.mark.parametrize("mode", MODES)
def test_imu_factor_matches_gtsam(scene, mode):
    s = scene
    pim_g = gtsam_pim(gtsam.PreintegratedImuMeasurementsManifold, gtsam_params(mode, False),
                      s["t_ns"], s["gyro"], s["acc"])
    xi, xj, bi = s["xi"], s["xj"], s["bi"]
    e_g, h_g = gtsam_formula(pim_g, mode, to_gtsam_state(xi), to_gtsam_state(xj),
                             to_gtsam_bias(bi))
    f = preint.ImuFactor(s["pim"], OURS[mode])
    r, jac = f.evaluate(xi, xj, bi)
    e, h = map_to_gtsam(r, jac, xi, xj, mode)
    assert np.abs(e_g[3:]).max() > 1e-3  # non-trivial position and velocity errors
    assert rel(e, e_g) <= TOL, (e, e_g)
    for name, ours, theirs in zip(H_NAMES, h, h_g):
        assert rel(ours, theirs) <= TOL, (name, ours, theirs)
    chi2_g = e_g @ np.linalg.solve(pim_g.residualCovariance(), e_g)
    if mode == "Logmap":
        # GTSAM's weight is ours reordered, so the χ² are equal.
        q = [0, 1, 2, 6, 7, 8, 3, 4, 5]
        assert rel(f.residual_covariance[np.ix_(q, q)], pim_g.residualCovariance()) <= TOL
        assert f.chi2(xi, xj, bi) == pytest.approx(chi2_g, rel=1e-8)
    else:
        # GTSAM weights e (p, v errors in body frame j) with the ΔRᵀ-rotated covariance: equal
        # to ours after the frame change r' = [r_φ, ΔR M r_v, ΔR M r_p].
        t = s["pim"].delta_R @ xj.rotation.T @ xi.rotation
        r2 = np.concatenate([r[0:3], t @ r[3:6], t @ r[6:9]])
        u = f.sqrt_information
        assert (u @ r2) @ (u @ r2) == pytest.approx(chi2_g, rel=1e-8)
        assert f.chi2(xi, xj, bi) != pytest.approx(chi2_g, rel=1e-6)


@pytest.mark.parametrize("mode", MODES)
def test_combined_factor_matches_gtsam(scene, mode):
    s = scene
    pim_g = gtsam_pim(gtsam.PreintegratedCombinedMeasurementsManifold, gtsam_params(mode, True),
                      s["t_ns"], s["gyro"], s["acc"])
    xi, xj, bi, bj = s["xi"], s["xj"], s["bi"], s["bj"]
    e_g, h_g = gtsam_formula(pim_g, mode, to_gtsam_state(xi), to_gtsam_state(xj),
                             to_gtsam_bias(bi), to_gtsam_bias(bj))
    f = preint.CombinedImuFactor(s["pim"], OURS[mode])
    r, jac = f.evaluate(xi, xj, bi, bj)
    e, h = map_to_gtsam(r, jac, xi, xj, mode)
    assert np.abs(e_g[9:]).max() > 1e-4  # the bias rows are exercised
    assert rel(e, e_g) <= TOL, (e, e_g)
    for name, ours, theirs in zip(H_NAMES, h, h_g):
        assert rel(ours, theirs) <= TOL, (name, ours, theirs)
    if mode == "Logmap":
        q = [0, 1, 2, 6, 7, 8, 3, 4, 5, 12, 13, 14, 9, 10, 11]
        cov_g = pim_g.residualCovariance()
        assert rel(f.residual_covariance[np.ix_(q, q)], cov_g) <= TOL
        chi2_g = e_g @ np.linalg.solve(cov_g, e_g)
        assert f.chi2(xi, xj, bi, bj) == pytest.approx(chi2_g, rel=1e-8)


@pytest.mark.parametrize("omega", [None, [0.0, 4.5e-5, 5.4e-5], [0.0, 0.02, 0.05]],
                         ids=["no-earth-rate", "earth-48deg", "fast-frame"])
def test_predict_matches_gtsam(scene, omega):
    """preint.predict (and ImuFactor.predict) against GTSAM's pim.predict, including a
    rotating navigation frame (our default Coriolis mode "exact" is GTSAM 4.3's)."""
    s = scene
    pim_g = gtsam_pim(gtsam.PreintegratedImuMeasurementsManifold,
                      gtsam_params("Logmap", False, omega), s["t_ns"], s["gyro"], s["acc"])
    ours = our_pim(s["t_ns"], s["gyro"], s["acc"], omega)
    for xi, bi in [(s["xi"], s["bi"]), (preint.NavState(), preint.ImuBias(BG_HAT, BA_HAT))]:
        got = preint.predict(ours, xi, bi)
        want = pim_g.predict(to_gtsam_state(xi), to_gtsam_bias(bi))
        assert rel(got.rotation, want.attitude().matrix()) <= TOL
        assert rel(got.position, want.position()) <= TOL
        assert rel(got.velocity, want.velocity()) <= TOL
        assert preint.ImuFactor(ours).predict(xi, bi) == got
    if omega is not None:  # the Earth rate changes the prediction measurably
        plain = preint.predict(our_pim(s["t_ns"], s["gyro"], s["acc"]), s["xi"], s["bi"])
        assert np.abs(plain.position - got.position).max() > 1e-9


def test_residual_covariance_matches_gtsam_in_both_modes(scene):
    """GTSAM's residualCovariance() does not depend on the error mode; ours (logmap) equals it."""
    s = scene
    covs = [gtsam_pim(gtsam.PreintegratedImuMeasurementsManifold, gtsam_params(m, False),
                      s["t_ns"], s["gyro"], s["acc"]).residualCovariance() for m in MODES]
    assert rel(covs[0], covs[1]) <= 1e-15
    q = [0, 1, 2, 6, 7, 8, 3, 4, 5]
    ours = preint.ImuFactor(s["pim"], "logmap").residual_covariance[np.ix_(q, q)]
    assert rel(ours, covs[0]) <= TOL


def so3_exp(w):
    th = np.linalg.norm(w)
    k = hat(w)
    return np.eye(3) + np.sin(th) / th * k + (1 - np.cos(th)) / th**2 * k @ k


@pytest.mark.parametrize("mode", MODES)
@pytest.mark.parametrize("omega", [[0.0, 4.5e-5, 5.4e-5], [0.0, 0.02, 0.05]],
                         ids=["earth-48deg", "fast-frame"])
def test_imu_factor_residual_in_a_rotating_frame_matches_gtsam(scene, mode, omega):
    """With omega_coriolis (Coriolis mode "exact"), GTSAM compares the states in body frame j
    with the physical velocity; with A = Exp(−ωT), M = R_jᵀ A R_i, N = R_jᵀ [ω]× A R_i and r
    our component-wise residual: e = [−r_φ, −M r_p, −M r_v + N r_p] (ComponentWise), and
    e = −Q r_L + [0, 0, Jl(w)⁻¹ N r_p], w = −r_φ, from our Logmap residual r_L (Logmap)."""
    s = scene
    omega = np.asarray(omega)
    ours = our_pim(s["t_ns"], s["gyro"], s["acc"], omega)
    xi, bi = s["xi"], s["bi"]
    pred = preint.predict(ours, xi, bi)
    xj = pred.retract(np.array([0.02, -0.01, 0.03, 0.05, -0.04, 0.03, -0.02, 0.05, 0.04]))
    pim_g = gtsam_pim(gtsam.PreintegratedImuMeasurementsManifold,
                      gtsam_params(mode, False, omega), s["t_ns"], s["gyro"], s["acc"])
    e_g, _ = gtsam_formula(pim_g, mode, to_gtsam_state(xi), to_gtsam_state(xj),
                           to_gtsam_bias(bi))
    r = preint.ImuFactor(ours, "component").residual(xi, xj, bi)
    a = so3_exp(-omega * ours.delta_t)
    m = xj.rotation.T @ a @ xi.rotation
    n = xj.rotation.T @ hat(omega) @ a @ xi.rotation
    if mode == "ComponentWise":
        e = np.concatenate([-r[0:3], -m @ r[6:9], -m @ r[3:6] + n @ r[6:9]])
    else:
        r_l = preint.ImuFactor(ours, "logmap").residual(xi, xj, bi)
        e = -r_l[[0, 1, 2, 6, 7, 8, 3, 4, 5]]
        e[6:9] += jl_inv(-r[0:3]) @ n @ r[6:9]
    assert np.abs(n @ r[6:9]).max() > 1e-10  # the rotating-frame term is exercised
    assert rel(e, e_g) <= TOL, (e, e_g)
