"""``preint.gtsam``: our ImuFactor / CombinedImuFactor as GTSAM factors (gtsam.CustomFactor on
Pose3, Vector3 and ConstantBias keys), against the live gtsam 4.3.0 wheel.

1. The Jacobians of ``factor.linearize`` equal central differences of ``unwhitenedError`` through
   GTSAM's own charts (``Pose3.retract``, ``v + d``, ``ConstantBias.retract``), states off the
   prediction and bias off the estimate; euler and hermite4 + lever arm + Earth rate measurements,
   both residual modes, with and without the in-window drift weight.
2. ``factor.error`` is ½χ² of our factor; for an "euler" measurement it equals GTSAM's formula on
   its Manifold preintegration (≡ euler) and is close (1e-2, the tangent preintegration's
   discretisation) to the wheel's gtsam.ImuFactor / CombinedImuFactor error.
3. A 10-keyframe graph solved by Levenberg–Marquardt with the adapter, with GTSAM's formula on its
   Manifold preintegration (same optimum ≤ 1e-8) and with gtsam.ImuFactor (≤ 1e-3 in poses and
   velocities, ≤ 1e-8 in biases).
4. GTSAM's testImuFactor ``ErrorAndJacobians`` configuration (imuFactorTesting.h) through the
   adapter: zero error, and the same Gauss–Newton information as gtsam.ImuFactor's.

"""

from __future__ import annotations

import sys

import numpy as np
import pytest

import preint


gtsam = pytest.importorskip("gtsam")

from test_factor_gtsam import (  # noqa: E402
    BA_HAT, BG_HAT, SA, SBA, SBG, SG, gtsam_formula, gtsam_params, our_pim, stream,
)


import preint.gtsam as pg  # noqa: E402

X, V, B = (lambda k: gtsam.symbol("x", k)), (lambda k: gtsam.symbol("v", k)), (lambda k: gtsam.symbol("b", k))


def values_of(states, biases):
    vals = gtsam.Values()
    for k, s in enumerate(states):
        pose, vel = pg.navstate_to_pose_velocity(s)
        vals.insert(X(k), pose)
        vals.insert(V(k), vel)
    for k, b in enumerate(biases):
        vals.insert(B(k), pg.bias_to_gtsam(b))
    return vals


def retracted(vals, key, d):
    out = gtsam.Values(vals)
    c = gtsam.symbolChr(key)
    if c == ord("x"):
        out.update(key, vals.atPose3(key).retract(d))
    elif c == ord("v"):
        out.update(key, vals.atVector(key) + d)
    else:
        out.update(key, vals.atConstantBias(key).retract(d))
    return out


DIMS = {ord("x"): 6, ord("v"): 3, ord("b"): 6}


def numeric_jacobian(factor, vals, h=1e-6):
    cols = []
    for key in factor.keys():
        for i in range(DIMS[gtsam.symbolChr(key)]):
            d = np.zeros(DIMS[gtsam.symbolChr(key)])
            d[i] = h
            ep = factor.unwhitenedError(retracted(vals, key, d))
            em = factor.unwhitenedError(retracted(vals, key, -d))
            cols.append((ep - em) / (2 * h))
    return np.stack(cols, axis=1)


@pytest.fixture(scope="module")
def scene():
    t_ns, gyro, acc = stream()
    rng = np.random.default_rng(7)
    pim = our_pim(t_ns, gyro, acc)  # euler, level combined, bias_hat (BG_HAT, BA_HAT)
    q = rng.normal(size=4)
    xi = preint.NavState(q / np.linalg.norm(q), rng.normal(size=3), rng.normal(size=3))
    bi = preint.ImuBias(BG_HAT + rng.normal(size=3) * 0.002, BA_HAT + rng.normal(size=3) * 0.02)
    bj = preint.ImuBias(bi.gyro + rng.normal(size=3) * 1e-4, bi.acc + rng.normal(size=3) * 1e-2)
    xj = preint.predict(pim, xi, bi).retract(np.concatenate([rng.normal(size=3) * 0.03, rng.normal(size=6) * 0.05]))
    return {"t_ns": t_ns, "gyro": gyro, "acc": acc, "pim": pim, "xi": xi, "xj": xj, "bi": bi, "bj": bj}


@pytest.fixture(scope="module")
def hermite_lever_earth(scene):
    """A measurement the wheel cannot make: hermite4 scheme, lever arm, Earth rate, in-window
    drift weight."""
    p = preint.Params(preint.Noise(SG, SBG, SA, SBA), scheme="hermite4", level="combined")
    p.set_body_p_sensor([0.9998477, 0.0, 0.0, 0.0174524], [0.1, -0.05, 0.02])
    p.omega_coriolis = [0.0, 4.9e-5, 5.5e-5]
    s = scene
    return preint.preintegrate(p, s["t_ns"], s["gyro"], s["acc"], int(s["t_ns"][0]), int(s["t_ns"][-1]),
                               preint.ImuBias(BG_HAT, BA_HAT))


def adapters(pim, residual):
    return {
        "imu": pg.ImuFactor(X(0), V(0), X(1), V(1), B(0), pim, residual),
        "combined": pg.CombinedImuFactor(X(0), V(0), X(1), V(1), B(0), B(1), pim, residual),
    }


def test_route_and_optional_import():
    assert pg.ROUTE in ("native", "custom") and pg.ROUTE in (pg.__doc__ or "")
    # `import preint` does not import gtsam (the adapter is optional).
    import subprocess

    code = "import sys, preint; assert 'gtsam' not in sys.modules and 'preint.gtsam' not in sys.modules"
    assert subprocess.run([sys.executable, "-c", code], capture_output=True).returncode == 0


# ----------------------------------------------------------------------------- 1. Jacobians
@pytest.mark.parametrize("residual", ["logmap", "component"])
@pytest.mark.parametrize("kind", ["imu", "combined", "imu_drift"])
@pytest.mark.parametrize("which", ["euler", "hermite_lever_earth"])
def test_jacobians_are_exact_for_gtsams_charts(scene, hermite_lever_earth, which, kind, residual):
    s = scene
    pim = s["pim"] if which == "euler" else hermite_lever_earth
    if kind == "imu_drift":
        f = pg.ImuFactor(X(0), V(0), X(1), V(1), B(0), pim, residual, in_window_drift=True)
    else:
        f = adapters(pim, residual)[kind]
    vals = values_of([s["xi"], s["xj"]], [s["bi"], s["bj"]])
    num = numeric_jacobian(f, vals)
    a, b = f.linearize(vals).jacobian()  # whitened: U J, −U r
    u = np.asarray(f.noiseModel().R())
    assert np.abs(f.unwhitenedError(vals)).max() > 1e-3
    np.testing.assert_allclose(b, -u @ f.unwhitenedError(vals), rtol=1e-12, atol=1e-12 * np.abs(b).max())
    scale = np.abs(u @ num).max()
    # Central differences with h = 1e-6: truncation O(h²), rounding O(ε/h) ≈ 1e-10 relative.
    assert np.abs(a - u @ num).max() <= 1e-6 * scale


# ----------------------------------------------------------------------------- 2. error
@pytest.mark.parametrize("residual", ["logmap", "component"])
def test_error_is_half_chi2_of_our_factor(scene, residual):
    s = scene
    vals = values_of([s["xi"], s["xj"]], [s["bi"], s["bj"]])
    fs = adapters(s["pim"], residual)
    ours = preint.ImuFactor(s["pim"], residual).cost(s["xi"], s["xj"], s["bi"])
    ours_c = preint.CombinedImuFactor(s["pim"], residual).cost(s["xi"], s["xj"], s["bi"], s["bj"])
    assert ours > 1.0
    assert fs["imu"].error(vals) == pytest.approx(ours, rel=1e-12)
    assert fs["combined"].error(vals) == pytest.approx(ours_c, rel=1e-12)


def gtsam_tangent_pim(t_ns, gyro, acc, params, bias, combined=False):
    cls = gtsam.PreintegratedCombinedMeasurements if combined else gtsam.PreintegratedImuMeasurements
    pim = cls(params, bias)
    for k in range(len(t_ns) - 1):
        pim.integrateMeasurement(acc[k], gyro[k], (int(t_ns[k + 1]) - int(t_ns[k])) * 1e-9)
    return pim


def test_error_is_close_to_gtsams_own_imu_factor(scene):
    s = scene
    vals = values_of([s["xi"], s["xj"]], [s["bi"], s["bj"]])
    hat = gtsam.imuBias.ConstantBias(BA_HAT, BG_HAT)
    fs = adapters(s["pim"], "logmap")
    # GTSAM's own formula on its Manifold preintegration (≡ our euler; the wheel's ImuFactor
    # does not accept it, see test_factor_gtsam): equal.
    gp = gtsam_params("Logmap", False)
    pim_m = gtsam.PreintegratedImuMeasurementsManifold(gp, hat)
    t_ns, gyro, acc = s["t_ns"], s["gyro"], s["acc"]
    for k in range(len(t_ns) - 1):
        pim_m.integrateMeasurement(acc[k], gyro[k], (int(t_ns[k + 1]) - int(t_ns[k])) * 1e-9)
    e, _ = gtsam_formula(pim_m, "Logmap", pg.to_gtsam(s["xi"]), pg.to_gtsam(s["xj"]), pg.to_gtsam(s["bi"]))
    half_chi2 = 0.5 * e @ np.linalg.solve(pim_m.residualCovariance(), e)
    assert fs["imu"].error(vals) == pytest.approx(half_chi2, rel=1e-8)
    # The wheel's gtsam.ImuFactor / CombinedImuFactor run on its tangent preintegration, whose
    # deltas differ from the Manifold (euler) ones by ~1e-6 (ΔR, Δv over 2 s): at residuals of
    # 0.03 rad / 5 cm that moves ½χ² by ~2e-3 relative. Asserted: 1e-2.
    pim_g = gtsam_tangent_pim(t_ns, gyro, acc, gp, hat)
    theirs = gtsam.ImuFactor(X(0), V(0), X(1), V(1), B(0), pim_g).error(vals)
    pim_c = gtsam_tangent_pim(t_ns, gyro, acc, gtsam_params("Logmap", True), hat, True)
    theirs_c = gtsam.CombinedImuFactor(X(0), V(0), X(1), V(1), B(0), B(1), pim_c).error(vals)
    assert fs["imu"].error(vals) == pytest.approx(theirs, rel=1e-2)
    assert fs["combined"].error(vals) == pytest.approx(theirs_c, rel=1e-2)


# ----------------------------------------------------------------------------- 3. graph
N_KF, KF_SAMPLES = 10, 100  # 10 keyframes 0.5 s apart at 200 Hz


def graph_inputs():
    t_ns, gyro, acc = stream(seconds=(N_KF - 1) * KF_SAMPLES / 200)
    p = preint.Params(preint.Noise(SG, SBG, SA, SBA), scheme="euler", level="combined")
    p.gravity = [0.0, 0.0, -9.81]
    zero = preint.ImuBias()
    pims = [
        preint.preintegrate(p, t_ns, gyro, acc, int(t_ns[k * KF_SAMPLES]), int(t_ns[(k + 1) * KF_SAMPLES]), zero)
        for k in range(N_KF - 1)
    ]
    truth = [preint.NavState(None, [0.0, 0.0, 0.0], [1.0, 0.0, 0.0])]
    for m in pims:
        truth.append(preint.predict(m, truth[-1], zero))
    return t_ns, gyro, acc, p, pims, truth


def build_graph(factors, truth, dt):
    g = gtsam.NonlinearFactorGraph()
    pose0, vel0 = pg.navstate_to_pose_velocity(truth[0])
    g.add(gtsam.PriorFactorPose3(X(0), pose0, gtsam.noiseModel.Isotropic.Sigma(6, 1e-3)))
    g.add(gtsam.PriorFactorVector(V(0), vel0, gtsam.noiseModel.Isotropic.Sigma(3, 1e-2)))
    g.add(gtsam.PriorFactorConstantBias(B(0), gtsam.imuBias.ConstantBias(),
                                        gtsam.noiseModel.Isotropic.Sigma(6, 1e-1)))
    walk = gtsam.noiseModel.Diagonal.Sigmas(np.sqrt(dt) * np.array([SBA] * 3 + [SBG] * 3))
    for k, f in enumerate(factors):
        g.add(f)
        g.add(gtsam.BetweenFactorConstantBias(B(k), B(k + 1), gtsam.imuBias.ConstantBias(), walk))
    return g


def initial_values(truth, seed=3):
    rng = np.random.default_rng(seed)
    vals = gtsam.Values()
    for k, s in enumerate(truth):
        s2 = s.retract(np.concatenate([rng.normal(size=3) * 0.05, rng.normal(size=3) * 0.2, rng.normal(size=3) * 0.1]))
        pose, vel = pg.navstate_to_pose_velocity(s2)
        vals.insert(X(k), pose)
        vals.insert(V(k), vel)
        vals.insert(B(k), gtsam.imuBias.ConstantBias(rng.normal(size=3) * 0.01, rng.normal(size=3) * 1e-3))
    return vals


def solve(graph, init):
    lm = gtsam.LevenbergMarquardtParams()
    lm.setRelativeErrorTol(1e-14)
    lm.setAbsoluteErrorTol(1e-14)
    lm.setMaxIterations(300)
    lm.setDiagonalDamping(True)  # without it LM crawls (the bias directions are ill-scaled)
    return gtsam.LevenbergMarquardtOptimizer(graph, init, lm).optimize()


def manifold_factor(k, pim_m):
    """GTSAM's ImuFactor formula (Logmap, test_factor_gtsam.gtsam_formula, asserted there equal
    to the wheel factor's evaluateError) on GTSAM's Manifold preintegration, which the wheel's
    ImuFactor does not accept: the reference our "euler" must match exactly."""

    def error(this, vals, H):
        xi = gtsam.NavState(vals.atPose3(X(k)), vals.atVector(V(k)))
        xj = gtsam.NavState(vals.atPose3(X(k + 1)), vals.atVector(V(k + 1)))
        e, h = gtsam_formula(pim_m, "Logmap", xi, xj, vals.atConstantBias(B(k)))
        if H is not None:
            for i, m in enumerate(h):
                H[i] = np.ascontiguousarray(m)
        return e

    model = gtsam.noiseModel.Gaussian.Covariance(pim_m.residualCovariance())
    return gtsam.CustomFactor(model, [X(k), V(k), X(k + 1), V(k + 1), B(k)], error)


def graph_triple():
    t_ns, gyro, acc, p, pims, truth = graph_inputs()
    ours = [pg.ImuFactor(X(k), V(k), X(k + 1), V(k + 1), B(k), m) for k, m in enumerate(pims)]
    gp = pg.params_to_gtsam(p, combined=False)
    gp.setImuFactorErrorMode(gtsam.ImuFactorErrorMode.Logmap)
    theirs, manifold = [], []
    for k in range(N_KF - 1):
        sl = slice(k * KF_SAMPLES, (k + 1) * KF_SAMPLES + 1)
        pim_g = gtsam_tangent_pim(t_ns[sl], gyro[sl], acc[sl], gp, gtsam.imuBias.ConstantBias())
        theirs.append(gtsam.ImuFactor(X(k), V(k), X(k + 1), V(k + 1), B(k), pim_g))
        pim_m = gtsam.PreintegratedImuMeasurementsManifold(gp, gtsam.imuBias.ConstantBias())
        for i in range(sl.start, sl.stop - 1):
            pim_m.integrateMeasurement(acc[i], gyro[i], (int(t_ns[i + 1]) - int(t_ns[i])) * 1e-9)
        manifold.append(manifold_factor(k, pim_m))
    dt = pims[0].delta_t
    return [build_graph(f, truth, dt) for f in (ours, theirs, manifold)], truth


def max_diff(ra, rb):
    """Largest difference of poses (Pose3 local coordinates), velocities and biases."""
    dp = max(np.abs(ra.atPose3(X(k)).localCoordinates(rb.atPose3(X(k)))).max() for k in range(N_KF))
    dv = max(np.abs(ra.atVector(V(k)) - rb.atVector(V(k))).max() for k in range(N_KF))
    db = max(np.abs(ra.atConstantBias(B(k)).vector() - rb.atConstantBias(B(k)).vector()).max() for k in range(N_KF))
    return dp, dv, db


def test_graph_optimum_matches_gtsams_own_imu_factor():
    (g_ours, g_theirs, g_manifold), truth = graph_triple()
    init = initial_values(truth)
    assert g_ours.error(init) > 1e3
    r_ours, r_theirs, r_man = solve(g_ours, init), solve(g_theirs, init), solve(g_manifold, init)
    # Every graph has a zero-residual configuration (the biases absorb the differences), and LM
    # (error tolerances 1e-14) stops there.
    for g, r in ((g_ours, r_ours), (g_theirs, r_theirs), (g_manifold, r_man)):
        assert g.error(r) < 1e-10
    # Against GTSAM's formula on its Manifold preintegration (≡ our euler, deltas equal to
    # ~1e-15): the same optimum to the optimiser's convergence, asserted 1e-8 (rad, m, m/s, bias).
    dp, dv, db = max_diff(r_ours, r_man)
    assert max(dp, dv, db) < 1e-8, (dp, dv, db)
    # Against the wheel's gtsam.ImuFactor, which accepts only its tangent preintegration: its
    # deltas differ from the Manifold/euler ones by ~1e-6 per 0.5 s window (ΔR, Δv), which over
    # 4.5 s of dead reckoning moves the positions by ~2e-4 m. Asserted: poses and velocities
    # within 1e-3, biases within 1e-8.
    dp, dv, db = max_diff(r_ours, r_theirs)
    assert dp < 1e-3 and dv < 1e-3 and db < 1e-8, (dp, dv, db)
    for k in range(N_KF):
        pt, _ = pg.navstate_to_pose_velocity(truth[k])
        assert np.abs(r_ours.atPose3(X(k)).localCoordinates(pt)).max() < 1e-4


# ----------------------------------------------------------------------------- 4. GTSAM's case
def test_gtsam_testImuFactor_ErrorAndJacobians_through_the_adapter():
    # imuFactorTesting.h (common::, testing::Params()): kGravity = 10 (nav z down), 0.5°/√h ARW,
    # 10 cm/s/√h VRW, integration covariance 1e-4 I; one sample of 1 s.
    gp = gtsam.PreintegrationParams.MakeSharedD(10.0)
    gp.setGyroscopeCovariance((np.radians(0.5) / 60) ** 2 * np.eye(3))
    gp.setAccelerometerCovariance((0.1 / 60) ** 2 * np.eye(3))
    gp.setIntegrationCovariance(1e-4 * np.eye(3))
    w = np.pi / 100
    x1 = gtsam.Pose3(gtsam.Rot3.RzRyRx(np.pi / 12, np.pi / 6, np.pi / 4), np.array([5.0, 1.0, 0.0]))
    x2 = gtsam.Pose3(gtsam.Rot3.RzRyRx(np.pi / 12 + w, np.pi / 6, np.pi / 4), np.array([5.5, 1.0, 0.0]))
    v = np.array([0.5, 0.0, 0.0])
    omega = np.array([w, 0.0, 0.0])
    acc = x1.rotation().unrotate(-np.array([0.0, 0.0, 10.0]))

    p = pg.params_from_gtsam(gp)  # scheme euler
    p.max_gap_ns = 2_000_000_000
    pi = preint.Preintegrator(p)
    pi.integrate(0, omega, acc)
    pi.integrate(1_000_000_000, omega, acc)
    m = pi.finish()
    pim_g = gtsam.PreintegratedImuMeasurements(gp)
    pim_g.integrateMeasurement(acc, omega, 1.0)

    vals = gtsam.Values()
    vals.insert(X(0), x1)
    vals.insert(V(0), v)
    vals.insert(X(1), x2)
    vals.insert(V(1), v)
    vals.insert(B(0), gtsam.imuBias.ConstantBias())
    ours = pg.ImuFactor(X(0), V(0), X(1), V(1), B(0), m)
    theirs = gtsam.ImuFactor(X(0), V(0), X(1), V(1), B(0), pim_g)
    # GTSAM: EXPECT(assert_equal(Z_9x1, factor.evaluateError(x1, v1, x2, v2, kZeroBias)))
    assert np.abs(ours.unwhitenedError(vals)).max() < 1e-9
    assert np.abs(theirs.unwhitenedError(vals)).max() < 1e-9
    # Same linearisation up to the residual's row order: equal Gauss–Newton information AᵀA.
    ha = ours.linearize(vals).information()
    hb = theirs.linearize(vals).information()
    np.testing.assert_allclose(ha, hb, rtol=0, atol=1e-6 * np.abs(hb).max())
    # GTSAM's numerical-derivative check of its factor, here of the adapter.
    a, _ = ours.linearize(vals).jacobian()
    u = np.asarray(ours.noiseModel().R())
    assert np.abs(a - u @ numeric_jacobian(ours, vals)).max() <= 1e-6 * np.abs(a).max()


# ----------------------------------------------------------------------------- conversions
def test_conversions_round_trip(scene):
    s = scene
    x = s["xi"]
    gx = pg.to_gtsam(x)
    assert isinstance(gx, gtsam.NavState)
    y = pg.from_gtsam(gx)
    np.testing.assert_allclose(y.rotation, x.rotation, atol=1e-15)
    np.testing.assert_allclose(y.position, x.position, atol=1e-15)
    np.testing.assert_allclose(y.velocity, x.velocity, atol=1e-15)
    pose, vel = pg.navstate_to_pose_velocity(x)
    z = pg.navstate_from_pose_velocity(pose, vel)
    np.testing.assert_allclose(z.position, x.position, atol=1e-15)
    b = pg.to_gtsam(s["bi"])
    np.testing.assert_array_equal(b.accelerometer(), s["bi"].acc)
    np.testing.assert_array_equal(b.gyroscope(), s["bi"].gyro)
    assert pg.from_gtsam(b) == s["bi"]
    # Our NavState.retract and GTSAM's charts agree to first order (the premise of the mapping).
    d = np.full(9, 1e-7)
    ours = x.retract(d)
    gp = pose.retract(d[:6])
    assert np.abs(gp.translation() - ours.position).max() < 1e-12
    np.testing.assert_allclose(vel + d[6:], ours.velocity, atol=1e-15)

    p = preint.Params(preint.Noise(SG, SBG, SA, SBA), scheme="euler", level="combined")
    p.gravity = [0.0, 0.1, -9.8]
    p.integration_covariance = 1e-8 * np.eye(3)
    p.omega_coriolis = [0.0, 1e-5, 7e-5]
    p.set_body_p_sensor(np.eye(3), [0.1, 0.0, 0.02])
    g = pg.to_gtsam(p)
    assert isinstance(g, gtsam.PreintegrationCombinedParams)
    np.testing.assert_array_equal(g.n_gravity, p.gravity)
    np.testing.assert_array_equal(g.getBiasOmegaCovariance(), p.bias_gyro_covariance)
    np.testing.assert_array_equal(g.getBiasAccCovariance(), p.bias_acc_covariance)
    q = pg.from_gtsam(g)
    for name in ("gravity", "gyroscope_covariance", "accelerometer_covariance", "bias_gyro_covariance",
                 "bias_acc_covariance", "integration_covariance", "omega_coriolis"):
        np.testing.assert_allclose(getattr(q, name), getattr(p, name), rtol=1e-15, err_msg=name)
    np.testing.assert_allclose(q.body_p_sensor[1], p.body_p_sensor[1], atol=1e-15)
    assert isinstance(pg.to_gtsam(p, combined=False), gtsam.PreintegrationParams)
