"""Bad values are refused where they enter, with a typed error naming the argument, as the
command line refuses a bad flag: noise densities, rates, gravity, Earth rate, covariances,
thresholds, biases, states, rotations and lever arms, sample arrays given to writers and to
the functions that do not preintegrate; nothing is written from a refused value. And a bias a
measurement cannot be corrected to (level "deltas": no bias Jacobians) is refused instead of
being ignored.

Expected values are written here (the rules of ``python/src/checks.rs`` and the messages'
key phrases), or come from another entry point whose equality is asserted.
"""

from __future__ import annotations

import contextlib

import numpy as np
import pytest

import preint

NAN, INF = float("nan"), float("inf")
EUROC = (1.6968e-4, 1.9393e-5, 2.0e-3, 3.0e-3)
FIELDS = ("gyro_noise_density", "gyro_random_walk", "acc_noise_density", "acc_random_walk")


def stream(n: int = 401) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """2 s at 200 Hz of a turning, accelerating body: (t_ns, gyro, acc)."""
    t = np.arange(n, dtype=np.int64) * 5_000_000
    k = np.arange(n)[:, None]
    gyro = np.hstack([0.3 * np.sin(0.02 * k), np.full((n, 1), -0.2), np.full((n, 1), 0.5)])
    acc = np.hstack([0.3 * np.cos(0.03 * k), np.zeros((n, 1)), np.full((n, 1), 9.81)])
    return t, gyro, acc


@contextlib.contextmanager
def refused(kind: str, *phrases: str):
    """Asserts that the block raises PreintError (a ValueError) of `kind` whose message holds
    every phrase."""
    with pytest.raises(preint.PreintError) as info:
        yield info
    e = info.value
    assert e.kind == kind and isinstance(e, ValueError), (e.kind, str(e))
    for p in phrases:
        assert p in str(e), (p, str(e))


# ---------------------------------------------------------------------------------- Noise
@pytest.mark.parametrize("field", ["gyro_noise_density", "acc_noise_density"])
@pytest.mark.parametrize("value", [-1e-4, 0.0, -0.0, NAN, INF])
def test_white_noise_density_must_be_finite_and_positive(field, value):
    args = dict(zip(FIELDS, EUROC))
    args[field] = value
    with refused("InvalidParameter", f"Noise: {field} must be a finite density > 0", "a factor cannot be weighted with a zero white-noise density"):
        preint.Noise(**args)


@pytest.mark.parametrize("field", ["gyro_random_walk", "acc_random_walk"])
def test_random_walk_may_be_zero_but_not_negative_or_non_finite(field):
    args = dict(zip(FIELDS, EUROC))
    args[field] = 0.0
    assert getattr(preint.Noise(**args), field) == 0.0  # a constant bias, as in GTSAM's tests
    for value in (-1e-5, NAN, INF):
        args[field] = value
        with refused("InvalidParameter", f"{field} must be a finite density ≥ 0"):
            preint.Noise(**args)


@pytest.mark.parametrize("rate", [0.0, -200.0, NAN, INF])
def test_noise_rate_must_be_finite_and_positive(rate):
    with refused("InvalidParameter", "update_rate_hz must be a finite rate > 0"):
        preint.Noise(*EUROC, rate)


def test_kalibr_yaml_with_a_zero_density_is_refused_naming_the_file(tmp_path):
    p = tmp_path / "imu.yaml"
    p.write_text(
        "gyroscope_noise_density: 0.0\ngyroscope_random_walk: 1e-5\n"
        "accelerometer_noise_density: 2e-3\naccelerometer_random_walk: 3e-3\nupdate_rate: 200\n"
    )
    with pytest.raises(preint.InputError) as e:
        preint.read_kalibr_yaml(p)
    assert str(p) in str(e.value) and "density" in str(e.value)
    with pytest.raises(preint.InputError):
        preint.calibrate_static(*stream(), noise=str(p))


def test_allan_of_readings_that_never_change_is_refused(tmp_path):
    # Readings that never change: the Allan deviation is 0 at every τ, so there is no noise to
    # read; the fit says so instead of returning a density of 0 or an infinite bound.
    n = 4001
    t = np.arange(n, dtype=np.int64) * 5_000_000
    with pytest.raises(preint.CalibrationError) as e:
        preint.allan_variance(t, np.zeros((n, 3)), np.tile([0.0, 0.0, 9.81], (n, 1)))
    assert "gyro x: the readings never change" in str(e.value), str(e.value)
    out = tmp_path / "imu.yaml"
    # A valid Noise is written and read back exactly.
    ok = preint.Noise(*EUROC, 400.0)
    preint.write_kalibr_yaml(out, ok)
    assert preint.read_kalibr_yaml(out) == ok


# --------------------------------------------------------------------------------- Params
@pytest.mark.parametrize(
    "name, value, phrase",
    [
        ("gravity", [0.0, 0.0, NAN], "Params.gravity: non-finite component"),
        ("gravity", [0.0, 0.0, -INF], "Params.gravity: non-finite component"),
        ("gravity", [0.0, 80.0, -80.0], "outside [0, 100] m/s²"),
        ("omega_coriolis", [0.0, 0.0, NAN], "Params.omega_coriolis: non-finite component"),
        ("omega_coriolis", [0.0, 0.0, 100.0], "is not below 100 rad/s"),
        ("gyroscope_covariance", -1e-8, "Params.gyroscope_covariance: negative variance"),
        ("accelerometer_covariance", NAN, "Params.accelerometer_covariance: non-finite entry"),
        ("bias_gyro_covariance", [[1, 2, 0], [0, 1, 0], [0, 0, 1]], "Params.bias_gyro_covariance: not symmetric"),
        ("bias_acc_covariance", -1.0, "Params.bias_acc_covariance"),
        ("integration_covariance", INF, "Params.integration_covariance: non-finite entry"),
        ("reintegrate_gyro_threshold", 0.0, "Params.reintegrate_gyro_threshold: must be positive"),
        ("reintegrate_acc_threshold", NAN, "Params.reintegrate_acc_threshold: must be positive"),
        ("max_gap_ns", -5, "Params.max_gap_ns: must be positive"),
    ],
)
def test_params_setters_refuse_bad_values_and_keep_the_old_one(name, value, phrase):
    p = preint.Params()
    with refused("InvalidParameter", phrase):
        setattr(p, name, value)
    assert p == preint.Params()


def test_params_accept_the_edges_of_their_ranges():
    p = preint.Params()
    p.gravity = [0.0, 0.0, 0.0]
    p.gravity = [0.0, 0.0, -100.0]
    p.omega_coriolis = [0.0, 0.0, 99.0]
    p.gyroscope_covariance = 0.0
    p.reintegrate_gyro_threshold = INF  # never re-integrate
    p.validate()


def test_body_p_sensor_rotation_and_lever_arm():
    p = preint.Params()
    with refused("InvalidParameter", "translation[0] must be finite [m]"):
        p.set_body_p_sensor(np.eye(3), [NAN, 0.0, 0.0])
    with pytest.raises(preint.ShapeError, match="unit norm"):
        p.set_body_p_sensor([1.0, 0.01, 0.0, 0.0])
    with pytest.raises(preint.ShapeError, match="not a rotation matrix"):
        p.set_body_p_sensor(np.diag([1.0, 1.0, NAN]))
    with pytest.raises(preint.ShapeError, match="not a rotation matrix"):
        p.set_body_p_sensor(np.diag([1.0, 1.0, -1.0]))
    assert p.body_p_sensor is None
    # Within the stated tolerance (1e-6) the quaternion is normalised.
    p.set_body_p_sensor([1.0 + 5e-7, 0.0, 0.0, 0.0], [0.1, 0.0, 0.0])
    r, t = p.body_p_sensor
    assert np.allclose(r, np.eye(3), rtol=0, atol=1e-15) and np.array_equal(t, [0.1, 0.0, 0.0])


# ------------------------------------------------------------------- biases and states
@pytest.mark.parametrize("value", [NAN, INF, -INF])
def test_bias_and_state_must_be_finite(value):
    with refused("InvalidParameter", "ImuBias.gyro[1] must be finite [rad/s]"):
        preint.ImuBias([0.0, value, 0.0])
    with refused("InvalidParameter", "ImuBias.acc[0] must be finite [m/s²]"):
        preint.ImuBias(acc=[value, 0.0, 0.0])
    with refused("InvalidParameter", "velocity[2] must be finite [m/s]"):
        preint.NavState(np.eye(3), [0.0, 0.0, 0.0], [0.0, 0.0, value])
    with refused("InvalidParameter", "delta[4] must be finite"):
        preint.NavState().retract([0.0, 0.0, 0.0, 0.0, value, 0.0, 0.0, 0.0, 0.0])


def test_preintegrator_capacity_is_bounded():
    with refused("InvalidParameter", "capacity must be at most 50000000 samples"):
        preint.Preintegrator(preint.Params(), capacity=10**12)


# -------------------------------------------------------------------------- sample arrays
def test_write_euroc_imu_refuses_bad_samples_before_writing(tmp_path):
    t, g, a = stream()
    out = tmp_path / "imu0.csv"
    bad = g.copy()
    bad[7, 1] = NAN
    with refused("NonFinite", "sample 7 (t = 35000000 ns): non-finite gyro"):
        preint.write_euroc_imu(out, t, bad, a)
    dup = t.copy()
    dup[12] = dup[11]
    with refused("DuplicateTimestamp", "sample 12"):
        preint.write_euroc_imu(out, dup, g, a)
    back = t.copy()
    back[20] = back[18]
    with refused("DecreasingTimestamp", "sample 20"):
        preint.write_euroc_imu(out, back, g, a)
    assert not out.exists()
    with pytest.raises(preint.ShapeError, match="t_ns"):
        preint.write_euroc_imu(out, t.astype(np.float64), g, a)
    with pytest.raises(preint.ShapeError, match="same length"):
        preint.write_euroc_imu(out, t[:-1], g, a)
    assert not out.exists()


def test_preintegration_names_the_non_finite_sample():
    t, g, a = stream()
    a = a.copy()
    a[100, 2] = INF
    with refused("NonFinite", "sample 100", "non-finite acc"):
        preint.preintegrate(preint.Params(), t, g, a, int(t[50]), int(t[150]))


def test_scalar_arguments_of_calibration_and_advice():
    t, g, a = stream()
    for gravity in (NAN, -1.0, 150.0):
        with refused("InvalidParameter", "gravity must be a magnitude in [0, 100] m/s²"):
            preint.calibrate_static(t, g, a, gravity=gravity)
        with refused("InvalidParameter", "gravity must be a magnitude"):
            preint.calibrate_multi_pose(t, g, a, gravity=gravity)
    for name in ("window", "fraction"):
        with pytest.raises(preint.ShapeError, match=f"{name} must be a positive number, got 0") as e:
            preint.advise(t, g, a, preint.Noise.euroc(), **{name: 0.0})
        assert e.value.kind == "Usage"


def test_truncation_estimate_needs_the_bias_the_window_was_integrated_with():
    t, g, a = stream()
    b = preint.ImuBias([0.01, 0.0, 0.0])
    p = preint.Params(scheme="midpoint")
    m = preint.preintegrate(p, t, g, a, int(t[40]), int(t[240]), bias=b)
    default = preint.truncation_estimate(p, t, g, a, m)
    given = preint.truncation_estimate(p, t, g, a, m, bias=b)
    assert np.array_equal(default[0], given[0])
    with refused("InvalidParameter", "truncation_estimate re-integrates the window of pim", "omit bias"):
        preint.truncation_estimate(p, t, g, a, m, bias=preint.ImuBias())


# ----------------------------------------- a bias the measurement cannot be corrected to
def deltas_window(bias: preint.ImuBias) -> tuple[preint.Params, preint.PreintegratedImu]:
    p = preint.Params(level="deltas")
    t, g, a = stream()
    return p, preint.preintegrate(p, t, g, a, int(t[0]), int(t[-1]), bias=bias)


B_HAT = preint.ImuBias([0.002, -0.001, 0.0], [0.03, 0.0, 0.0])
OTHER = preint.ImuBias([0.003, -0.001, 0.0], [0.03, 0.0, 0.0])
MESSAGE = (
    "this measurement was preintegrated at level deltas, without bias Jacobians",
    "cannot be corrected to bias gyro [0.003, -0.001, 0.0] rad/s",
    "(it was integrated at gyro [0.002, -0.001, 0.0] rad/s, acc [0.03, 0.0, 0.0] m/s²)",
    "preintegrate at level covariance or combined, or re-preintegrate at the new bias",
)


def test_deltas_level_refuses_a_bias_change_it_cannot_correct():
    _, m = deltas_window(B_HAT)
    x = preint.NavState(np.eye(3), [1.0, 2.0, 3.0], [0.5, 0.0, 0.0])
    with refused("NoBiasJacobians", *MESSAGE):
        preint.predict(m, x, OTHER)
    with refused("NoBiasJacobians", *MESSAGE):
        m.corrected(OTHER)
    # No factor holds such a measurement: it has no covariance to weight with.
    with pytest.raises(preint.FactorError) as e:
        preint.ImuFactor(m)
    assert e.value.kind == "LevelTooLow"


def test_deltas_level_at_its_own_bias_predicts_with_its_deltas():
    _, m = deltas_window(B_HAT)
    x = preint.NavState(np.eye(3), [1.0, 2.0, 3.0], [0.5, 0.0, 0.0])
    y = preint.predict(m, x, B_HAT)
    assert y == preint.predict(m, x)  # bias_i=None is bias_hat
    r, v, p = m.corrected(B_HAT)
    assert np.array_equal(r, m.delta_R) and np.array_equal(v, m.delta_v) and np.array_equal(p, m.delta_p)
    # Forster eq. 33 with the uncorrected deltas, to the bit (R_i = I, the operations in the
    # Rust order).
    g, dt = m.gravity, m.delta_t
    assert np.array_equal(y.rotation, m.delta_R)
    assert np.array_equal(y.velocity, x.velocity + g * dt + m.delta_v)
    assert np.array_equal(y.position, x.position + x.velocity * dt + g * (0.5 * dt * dt) + m.delta_p)


def test_covariance_level_corrects_the_same_change():
    t, g, a = stream()
    p = preint.Params(level="covariance")
    m = preint.preintegrate(p, t, g, a, int(t[0]), int(t[-1]), bias=B_HAT)
    x = preint.NavState()
    moved = preint.predict(m, x, OTHER).local(preint.predict(m, x, B_HAT))
    # δb_g = 1e-3 rad/s over 2 s turns the prediction by about 2e-3 rad.
    assert 1e-3 < np.linalg.norm(moved[:3]) < 3e-3


def test_measurement_for_bias_at_deltas_level_re_integrates_or_refuses():
    t, g, a = stream()
    p = preint.Params(level="deltas")
    pi = preint.Preintegrator(p, B_HAT)
    pi.integrate_arrays(t, g, a)
    m, again = pi.measurement_for_bias(OTHER)
    assert again
    fresh = preint.Preintegrator(p, OTHER)
    fresh.integrate_arrays(t, g, a)
    assert m == fresh.finish()
    same, again = pi.measurement_for_bias(B_HAT)
    assert not again and same == pi.finish()
    p.keep_samples = False
    kept_none = preint.Preintegrator(p, B_HAT)
    kept_none.integrate_arrays(t, g, a)
    with refused("NoBiasJacobians", *MESSAGE):
        kept_none.measurement_for_bias(OTHER)

