"""preint's ``euler`` and ``galilean`` schemes against GTSAM's own Python wheel, live, on the
same samples: ``gtsam.PreintegratedImuMeasurementsManifold`` (Forster et al. 2017, the sample
at the start of each interval held over it) and ``gtsam.PreintegratedImuMeasurementsG``
(Gal(3), exact for held input) for ΔR, Δv, Δp, the 9×9 covariance and the bias Jacobians, and
``gtsam.PreintegratedCombinedMeasurementsManifold`` for the 15×15 covariance and the combined
factor's residual covariance.

Mapping (as in preint/tests/gtsam_euler.rs, preint/tests/combined_gtsam.rs and
tests/fixtures/gtsam/gtsam_preint.py):

- GTSAM's argument order is ``integrateMeasurement(acc, gyro, dt)`` and its bias is
  ``ConstantBias(acc, gyro)``; ours ``[b_g, b_a]``.
- GTSAM's Manifold covariance is in [rot, pos, vel] with the pos and vel errors in its
  ``NavState`` chart (``dp + ΔR δp``): ``T = diag(I, ΔR, ΔR)`` maps it to Forster's chart (ours),
  then [φ, p, v] is reordered to our [δφ, δv, δp].
- Bias Jacobians: GTSAM's ``predict(NavState(), biasHat, H1, H2)`` at the identity state gives
  ``H2`` (9×6, columns [b_a, b_g], rows in the chart at ``R_j = ΔR``); ``∂ΔR/∂b_g = H2[0:3,
  3:6]``, ``∂Δp/∂b = ΔR H2[3:6]``, ``∂Δv/∂b = ΔR H2[6:9]``.
- Combined: with ``P`` our [δφ, δv, δp, δb_g, δb_a] → GTSAM's [rot, pos, vel, b_a, b_g] and
  ``T = diag(I, ΔRᵀ, ΔRᵀ, I, I)``, ``preintMeasCov() = T P cov15 Pᵀ Tᵀ`` and
  ``residualCovariance() = T P residual_cov15 Pᵀ Tᵀ``.

Norms: ``‖ours − gtsam‖_F ≤ 1e-12 ‖gtsam‖_F`` per item; combined covariances entrywise
``|ours − gtsam| ≤ 1e-12 √(gtsam_ii gtsam_jj)`` (the Rust tests' norms).
"""

from __future__ import annotations

import json
from importlib.metadata import version

import numpy as np
import pytest

import preint

from conftest import EUROC, GTSAM_FIXTURES, read_euroc_imu

gtsam = pytest.importorskip("gtsam")

TOL = 1e-12
FIXTURE_CASES = ["example", "example_componentwise", "rate50", "rate1000", "jitter200", "bias", "fastspin", "aniso", "intcov"]


def test_the_wheel_is_gtsam_4_3_0():
    # The charts and orders above are GTSAM 4.3's; tools/test installs gtsam==4.3.0.
    assert version("gtsam") == "4.3.0"


def cov3(v) -> np.ndarray:
    m = np.asarray(v, dtype=float)
    return m * np.eye(3) if m.shape == () else m


def config_of(cfg: dict) -> dict:
    """The parameters of a fixture's ``NAME.params.json`` (keys as gtsam_preint.py reads them)."""
    g = np.asarray(cfg["n_gravity"], float) if "n_gravity" in cfg else np.array([0.0, 0.0, -cfg.get("gravity", 9.81)])
    return {
        "gravity": g,
        "gyro_cov": cov3(cfg["gyro_covariance"]) if "gyro_covariance" in cfg else cfg["gyro_noise_density"] ** 2 * np.eye(3),
        "acc_cov": cov3(cfg["accel_covariance"]) if "accel_covariance" in cfg else cfg["accel_noise_density"] ** 2 * np.eye(3),
        "int_cov": cov3(cfg.get("integration_covariance", 0.0)),
        "bg": np.asarray(cfg.get("bg", [0, 0, 0]), float),
        "ba": np.asarray(cfg.get("ba", [0, 0, 0]), float),
    }


def ours(c: dict, t, g, a, scheme: str = "euler") -> preint.PreintegratedImu:
    p = preint.Params(scheme=scheme, level="covariance")
    p.gravity = c["gravity"]
    p.gyroscope_covariance = c["gyro_cov"]
    p.accelerometer_covariance = c["acc_cov"]
    p.integration_covariance = c["int_cov"]
    pi = preint.Preintegrator(p, preint.ImuBias(c["bg"], c["ba"]))
    pi.integrate_arrays(t, g, a)
    return pi.finish()


def theirs(c: dict, t, g, a, cls=None):
    """GTSAM's preintegration of the same samples (sample k held over interval k): Manifold by
    default, or the class ``cls``."""
    p = gtsam.PreintegrationParams(c["gravity"])
    p.setGyroscopeCovariance(c["gyro_cov"])
    p.setAccelerometerCovariance(c["acc_cov"])
    p.setIntegrationCovariance(c["int_cov"])
    bias = gtsam.imuBias.ConstantBias(c["ba"], c["bg"])  # (acc, gyro)
    pim = (cls or gtsam.PreintegratedImuMeasurementsManifold)(p, bias)
    for k in range(len(t) - 1):
        pim.integrateMeasurement(a[k], g[k], int(t[k + 1] - t[k]) * 1e-9)  # (acc, gyro, dt)
    return pim, bias


def rel(x: np.ndarray, y: np.ndarray) -> float:
    return float(np.linalg.norm(x - y) / np.linalg.norm(y))


def compare(name: str, c: dict, t, g, a, scheme: str = "euler", cls=None) -> dict[str, float]:
    m = ours(c, t, g, a, scheme)
    pim, bias = theirs(c, t, g, a, cls)
    dR = pim.deltaRij().matrix()
    T = np.eye(9)
    T[3:6, 3:6] = T[6:9, 6:9] = dR
    forster = T @ pim.preintMeasCov() @ T.T  # [φ, p, v], Forster's chart
    perm = [0, 1, 2, 6, 7, 8, 3, 4, 5]
    cov_theirs = forster[np.ix_(perm, perm)]  # [φ, v, p]
    H1, H2 = np.zeros((9, 9), order="F"), np.zeros((9, 6), order="F")
    pim.predict(gtsam.NavState(), bias, H1, H2)
    assert np.abs(H2).max() > 0.0, "predict did not fill its Jacobian"
    j = m.bias_jacobians  # rows [φ, v, p], columns [b_g, b_a]
    errors = {
        "delta_R": rel(m.delta_R, dR),
        "delta_v": rel(m.delta_v, pim.deltaVij()),
        "delta_p": rel(m.delta_p, pim.deltaPij()),
        "cov": rel(m.cov, cov_theirs),
        "dR_dbg": rel(j[0:3, 0:3], H2[0:3, 3:6]),
        "dv_dbg": rel(j[3:6, 0:3], dR @ H2[6:9, 3:6]),
        "dv_dba": rel(j[3:6, 3:6], dR @ H2[6:9, 0:3]),
        "dp_dbg": rel(j[6:9, 0:3], dR @ H2[3:6, 3:6]),
        "dp_dba": rel(j[6:9, 3:6], dR @ H2[3:6, 0:3]),
    }
    for k, e in errors.items():
        assert e <= TOL, f"{name}: {k} relative error {e:.2e} > {TOL:.0e}"
    # GTSAM's ΔR does not depend on b_a; neither does ours.
    assert np.abs(H2[0:3, 0:3]).max() == 0.0 and np.abs(j[0:3, 3:6]).max() == 0.0
    assert abs(m.delta_t - pim.deltaTij()) <= 1e-12 * m.delta_t
    assert (m.t_i_ns, m.t_j_ns) == (t[0], t[-1])
    return errors


@pytest.mark.parametrize("case", FIXTURE_CASES)
def test_euler_equals_gtsam_manifold_on_the_fixture_inputs(case):
    cfg = json.loads((GTSAM_FIXTURES / f"{case}.params.json").read_text())
    csv_name = "example" if case.startswith("example") else case
    t, g, a = read_euroc_imu(GTSAM_FIXTURES / f"{csv_name}.csv")
    compare(case, config_of(cfg), t, g, a)


@pytest.mark.parametrize("case", ["example", "rate50", "jitter200", "bias", "fastspin", "aniso", "intcov"])
def test_galilean_equals_gtsam_galilean_on_the_fixture_inputs(case):
    # GTSAM's PreintegratedImuMeasurementsG (Gal(3), exact for held input): its covariance is
    # in the right-trivialised Gal(3) chart restricted to [rot, pos, vel], which is the NavState
    # chart above to first order, so the same mapping applies.
    cfg = json.loads((GTSAM_FIXTURES / f"{case}.params.json").read_text())
    t, g, a = read_euroc_imu(GTSAM_FIXTURES / f"{case}.csv")
    c = config_of(cfg)
    compare(case, c, t, g, a, "galilean", gtsam.PreintegratedImuMeasurementsG)
    # Not the Euler numbers: galilean differs from GTSAM's Manifold by far more than 1e-12.
    e = ours(c, t, g, a, "euler")
    m = ours(c, t, g, a, "galilean")
    assert rel(m.delta_p, e.delta_p) > 1e-9
    # Bias-corrected deltas: GTSAM's predict at the identity state for a shifted bias (its
    # biasCorrectedDelta, right-applied on the group) against ours, ‖δb‖ = 0.35 with
    # ‖δb_a‖ = 30 ‖δb_g‖; the additive correction misses it.
    assert m.bias_correction == "group"
    pim, _ = theirs(c, t, g, a, gtsam.PreintegratedImuMeasurementsG)
    u = np.array([0.3, -0.5, 0.8])
    u /= np.linalg.norm(u)
    s = 0.35 / np.sqrt(1 + 30.0**2)
    dbg, dba = s * u, 30 * s * u[::-1]
    bias = preint.ImuBias(c["bg"] + dbg, c["ba"] + dba)
    want = pim.predict(gtsam.NavState(), gtsam.imuBias.ConstantBias(c["ba"] + dba, c["bg"] + dbg))
    got = preint.predict(m, preint.NavState(), bias)
    assert rel(got.rotation, want.attitude().matrix()) <= TOL
    assert rel(got.position, want.position()) <= TOL
    assert rel(got.velocity, want.velocity()) <= TOL
    p_add = preint.Params(scheme="galilean", level="covariance")
    p_add.bias_correction = "additive"
    p_add.gravity = c["gravity"]
    p_add.gyroscope_covariance = c["gyro_cov"]
    p_add.accelerometer_covariance = c["acc_cov"]
    pi = preint.Preintegrator(p_add, preint.ImuBias(c["bg"], c["ba"]))
    pi.integrate_arrays(t, g, a)
    add = preint.predict(pi.finish(), preint.NavState(), bias)
    assert rel(add.velocity, want.velocity()) > 1e-9


def test_euler_equals_gtsam_manifold_on_euroc(euroc_imu):
    t, g, a = euroc_imu
    sel = slice(5000, 5401)  # 2 s of V1_01_easy at 200 Hz
    c = {
        "gravity": np.array([0.0, 0.0, -9.81]),
        "gyro_cov": 1.6968e-4**2 * np.eye(3),
        "acc_cov": 2.0e-3**2 * np.eye(3),
        "int_cov": 1e-8 * np.eye(3),
        "bg": np.array([-0.00224703, 0.0215352, 0.0770299]),  # the ground truth's biases
        "ba": np.array([-0.0180079, 0.0659832, 0.0309754]),
    }
    compare("euroc", c, t[sel], g[sel], a[sel])


@pytest.mark.parametrize("seed", [11, 12])
def test_euler_equals_gtsam_manifold_on_random_irregular_streams(seed):
    rng = np.random.default_rng(seed)
    n = 300
    t = np.concatenate([[0], np.cumsum(rng.integers(2_000_000, 8_000_000, size=n - 1))]).astype(np.int64) + 10**18
    g = rng.normal(size=(n, 3)) * 2.0
    a = rng.normal(size=(n, 3)) * 3.0 + [0.0, 0.0, 9.81]
    A = rng.normal(size=(3, 3)) * 1e-3
    c = {
        "gravity": np.array([0.1, -0.2, -9.79]),
        "gyro_cov": A @ A.T + 1e-8 * np.eye(3),
        "acc_cov": np.diag([4e-6, 9e-6, 1e-5]),
        "int_cov": np.zeros((3, 3)),
        "bg": rng.normal(size=3) * 0.01,
        "ba": rng.normal(size=3) * 0.1,
    }
    compare(f"random {seed}", c, t, g, a)


# ---------------------------------------------------------------- combined (15×15)

# Our [δφ, δv, δp, δb_g, δb_a] index of GTSAM's [rot, pos, vel, b_a, b_g] index.
PERM15 = [0, 1, 2, 6, 7, 8, 3, 4, 5, 12, 13, 14, 9, 10, 11]


def to_gtsam(c15: np.ndarray, dR: np.ndarray) -> np.ndarray:
    T = np.eye(15)
    T[3:6, 3:6] = T[6:9, 6:9] = dR.T
    return T @ c15[np.ix_(PERM15, PERM15)] @ T.T


def worst_rel(x: np.ndarray, y: np.ndarray) -> float:
    s = np.sqrt(np.outer(np.diag(y), np.diag(y)))
    return float((np.abs(x - y) / s).max())


@pytest.mark.parametrize("case", ["combined_example", "combined_rate1000", "combined_fastspin"])
def test_combined_covariances_equal_gtsam_combined_manifold(case):
    fixture = json.loads((GTSAM_FIXTURES / f"{case}.gtsam.json").read_text())
    q = fixture["params"]  # the case's densities and bias estimate (not its GTSAM outputs)
    t, g, a = read_euroc_imu(GTSAM_FIXTURES / fixture["csv"])
    noise = preint.Noise(q["gyro_noise_density"], q["gyro_random_walk"], q["accel_noise_density"], q["accel_random_walk"])
    p = preint.Params(noise, scheme="euler", level="combined")
    p.gravity = [0.0, 0.0, -q["gravity"]]
    m = preint.preintegrate(p, t, g, a, int(t[0]), int(t[-1]), bias=preint.ImuBias(q["bg"], q["ba"]))

    gp = gtsam.PreintegrationCombinedParams.MakeSharedU(q["gravity"])
    gp.setGyroscopeCovariance(q["gyro_noise_density"] ** 2 * np.eye(3))
    gp.setAccelerometerCovariance(q["accel_noise_density"] ** 2 * np.eye(3))
    gp.setIntegrationCovariance(np.zeros((3, 3)))
    gp.setBiasOmegaCovariance(q["gyro_random_walk"] ** 2 * np.eye(3))
    gp.setBiasAccCovariance(q["accel_random_walk"] ** 2 * np.eye(3))
    pim = gtsam.PreintegratedCombinedMeasurementsManifold(gp, gtsam.imuBias.ConstantBias(np.array(q["ba"]), np.array(q["bg"])))
    for k in range(len(t) - 1):
        pim.integrateMeasurement(a[k], g[k], int(t[k + 1] - t[k]) * 1e-9)

    dR = pim.deltaRij().matrix()
    assert np.abs(m.delta_R - dR).max() < 1e-12
    cov = pim.preintMeasCov()
    w = worst_rel(to_gtsam(m.cov15, m.delta_R), cov)
    assert w < TOL, f"{case}: cov15 vs preintMeasCov, worst {w:.2e}"
    w = worst_rel(to_gtsam(m.residual_cov15(), m.delta_R), pim.residualCovariance())
    assert w < TOL, f"{case}: residual_cov15 vs residualCovariance, worst {w:.2e}"
    # The delta–bias blocks are not negligible, so the comparison tells their signs apart.
    blockdiag = cov.copy()
    blockdiag[:9, 9:] = blockdiag[9:, :9] = 0.0
    assert worst_rel(cov, blockdiag) > 0.05
    assert worst_rel(to_gtsam(m.cov15, m.delta_R), pim.residualCovariance()) > 0.05
