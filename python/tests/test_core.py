"""The core API: the three ways of feeding samples agree to the bit, windows and merge, exact
pickling, typed errors naming the sample, and the deltas of a constant-rate motion against
their closed form written here in numpy.

Expected values come from numpy (closed forms), from the other entry points of the package
(whose agreement to the bit is what is asserted), or from the tolerances the Rust merge tests
state (preint/tests/merge.rs: deltas to round-off, covariances to 1e-10 relative per block).
"""

from __future__ import annotations

import pickle
import re
import subprocess
import sys

import numpy as np
import pytest

import preint

from conftest import REPO

SCHEMES = ("euler", "midpoint", "hermite4")
T0 = 1_403_636_579_758_555_392  # a EuRoC-like start time [ns]


def stream(n: int, seed: int, jitter_ns: int = 1_000_000) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """An irregular ~200 Hz stream with fast rotation and acceleration: (t_ns, gyro, acc)."""
    rng = np.random.default_rng(seed)
    steps = 5_000_000 + rng.integers(-jitter_ns, jitter_ns + 1, size=n - 1)
    t = T0 + np.concatenate([[0], np.cumsum(steps)]).astype(np.int64)
    k = np.arange(n)
    gyro = np.stack([1.5 * np.sin(0.3 * k), np.full(n, 0.8), np.full(n, -0.5)], axis=1)
    gyro += rng.uniform(-0.3, 0.3, size=(n, 3))
    acc = np.array([0.5, -0.3, 9.81]) + rng.uniform(-2.0, 2.0, size=(n, 3))
    return t, gyro, acc


def arrays(m: preint.PreintegratedImu) -> dict[str, np.ndarray]:
    """Every numeric output of a measurement, by name."""
    return {
        "t": np.array([m.t_i_ns, m.t_j_ns]),
        "delta_t": np.array([m.delta_t]),
        "delta_R": m.delta_R,
        "delta_v": m.delta_v,
        "delta_p": m.delta_p,
        "cov": m.cov,
        "cov15": m.cov15,
        "residual_cov15": m.residual_cov15(),
        "bias_jacobians": m.bias_jacobians,
        "bias_hat": m.bias_hat.vector(),
        "gravity": m.gravity,
    }


def assert_bitwise_equal(a: preint.PreintegratedImu, b: preint.PreintegratedImu, what: str) -> None:
    """Every array of `a` equals `b`'s bit for bit (compared as raw bytes, so -0.0 ≠ 0.0)."""
    xa, xb = arrays(a), arrays(b)
    for k in xa:
        assert xa[k].dtype == xb[k].dtype and xa[k].shape == xb[k].shape, f"{what}: {k}"
        assert xa[k].tobytes() == xb[k].tobytes(), f"{what}: {k} differs by {np.abs(xa[k] - xb[k]).max():e}"


def params(scheme: str, level: str = "combined") -> preint.Params:
    return preint.Params(preint.Noise.euroc(), scheme=scheme, level=level)


# ---------------------------------------------------------------- three entry points, one result


@pytest.mark.parametrize("scheme", SCHEMES)
def test_per_sample_arrays_and_preintegrate_agree_bit_for_bit(scheme):
    t, g, a = stream(301, seed=1)
    p = params(scheme)
    bias = preint.ImuBias([0.01, -0.02, 0.005], [0.1, -0.05, 0.2])

    one = preint.Preintegrator(p, bias)
    for k in range(len(t)):
        one.integrate(int(t[k]), g[k], a[k])
    assert len(one) == len(t)
    per_sample = one.finish()

    many = preint.Preintegrator(p, bias)
    many.integrate_arrays(t[:100], g[:100], a[:100])  # in two calls: the state carries over
    many.integrate_arrays(t[100:], g[100:], a[100:])
    in_arrays = many.finish()

    whole = preint.preintegrate(p, t, g, a, int(t[0]), int(t[-1]), bias=bias)

    assert_bitwise_equal(per_sample, in_arrays, f"{scheme}: integrate vs integrate_arrays")
    assert_bitwise_equal(per_sample, whole, f"{scheme}: integrate vs preintegrate")
    assert per_sample.t_i_ns == t[0] and per_sample.t_j_ns == t[-1]
    assert per_sample.level == "combined" and per_sample.bias_hat == bias
    # The arrays are not trivially equal: the motion and its covariance are substantial.
    assert np.linalg.norm(per_sample.delta_rotvec) > 0.5 and per_sample.cov[0, 0] > 0.0


def test_integrate_accepts_lists_and_arrays_alike():
    t, g, a = stream(50, seed=2)
    p = params("midpoint")
    x, y = preint.Preintegrator(p), preint.Preintegrator(p)
    for k in range(len(t)):
        x.integrate(int(t[k]), g[k], a[k])
        y.integrate(int(t[k]), g[k].tolist(), tuple(a[k]))
    assert_bitwise_equal(x.finish(), y.finish(), "lists vs arrays")


@pytest.mark.parametrize("scheme", SCHEMES)
def test_preintegrate_windows_equals_per_window_calls(scheme):
    t, g, a = stream(1000, seed=3)
    # Keyframes between samples (interpolated boundaries), one on a sample, irregular lengths.
    keys = np.array([t[3] + 1_234_567, t[150], t[151] + 2_500_000, t[400] + 17, t[990] - 3], dtype=np.int64)
    p = params(scheme)
    bias = preint.ImuBias([0.002, 0.0, -0.001], [0.05, 0.02, -0.03])
    windows = preint.preintegrate_windows(p, t, g, a, keys, bias=bias)
    assert len(windows) == len(keys) - 1
    for k, w in enumerate(windows):
        single = preint.preintegrate(p, t, g, a, int(keys[k]), int(keys[k + 1]), bias=bias)
        assert_bitwise_equal(w, single, f"{scheme}: window {k}")
        assert (w.t_i_ns, w.t_j_ns) == (keys[k], keys[k + 1])
        assert w.delta_t == (keys[k + 1] - keys[k]) * 1e-9


# ---------------------------------------------------------------- merge


@pytest.mark.parametrize("scheme", SCHEMES)
def test_merge_of_two_windows_equals_the_whole_window(scheme):
    t, g, a = stream(600, seed=4)
    # Split at a stream sample (between samples the interpolated sample changes the
    # discretisation, as in the Rust test); the outer keyframes fall between samples.
    ti, tm, tj = int(t[10]) + 1_000_000, int(t[300]), int(t[580]) - 1_500_000
    p = params(scheme)
    bias = preint.ImuBias([0.003, -0.002, 0.001], [0.04, -0.02, 0.01])
    first, second = preint.preintegrate_windows(p, t, g, a, np.array([ti, tm, tj], dtype=np.int64), bias=bias)
    whole = preint.preintegrate(p, t, g, a, ti, tj, bias=bias)
    m = preint.merge(first, second)

    assert (m.t_i_ns, m.t_j_ns) == (ti, tj)
    assert abs(m.delta_t - whole.delta_t) < 1e-15
    # Rust merge tests: ΔR to 1e-14 (angle), Δv, Δp to 1e-13 relative.
    d_rot = m.delta_error(whole)[:3]
    assert np.linalg.norm(d_rot) < 1e-14
    assert np.abs(m.delta_v - whole.delta_v).max() < 1e-13 * (1 + np.abs(whole.delta_v).max())
    assert np.abs(m.delta_p - whole.delta_p).max() < 1e-13 * (1 + np.abs(whole.delta_p).max())
    # Covariances and bias Jacobians: 1e-10 relative per 3×3 block.
    for name, n in (("cov", 3), ("cov15", 5)):
        cm, cw = getattr(m, name), getattr(whole, name)
        for r in range(n):
            for c in range(n):
                bm, bw = cm[3 * r : 3 * r + 3, 3 * c : 3 * c + 3], cw[3 * r : 3 * r + 3, 3 * c : 3 * c + 3]
                if np.abs(bw).max() == 0.0:
                    assert np.abs(bm).max() < 1e-30 * np.abs(cw).max(), f"{name} block ({r},{c})"
                else:
                    rel = np.abs(bm - bw).max() / np.abs(bw).max()
                    assert rel < 1e-10, f"{scheme}: {name} block ({r},{c}) rel {rel:e}"
    jm, jw = m.bias_jacobians, whole.bias_jacobians
    for r in range(3):
        for c in range(2):
            bm, bw = jm[3 * r : 3 * r + 3, 3 * c : 3 * c + 3], jw[3 * r : 3 * r + 3, 3 * c : 3 * c + 3]
            if (r, c) == (0, 1):
                assert np.abs(bm).max() == 0.0 and np.abs(bw).max() == 0.0  # ΔR does not depend on b_a
            else:
                assert np.abs(bm - bw).max() < 1e-10 * np.abs(bw).max(), f"{scheme}: jacobian block ({r},{c})"


def test_merge_rejects_windows_that_are_not_consecutive():
    t, g, a = stream(300, seed=5)
    p = params("midpoint")
    x = preint.preintegrate(p, t, g, a, int(t[0]), int(t[100]))
    y = preint.preintegrate(p, t, g, a, int(t[101]), int(t[200]))
    with pytest.raises(preint.MergeError) as e:
        preint.merge(x, y)
    assert e.value.kind == "NotConsecutive"
    assert str(t[100]) in str(e.value) and str(t[101]) in str(e.value)
    assert isinstance(e.value, preint.Error) and isinstance(e.value, ValueError)
    z = preint.preintegrate(p, t, g, a, int(t[100]), int(t[200]), bias=preint.ImuBias([0.01, 0, 0]))
    with pytest.raises(preint.MergeError) as e:
        preint.merge(x, z)
    assert e.value.kind == "BiasMismatch"


# ---------------------------------------------------------------- pickle


def test_pickle_round_trips_are_exact():
    noise = preint.Noise(1.6968e-4 * 1.1, 1.9393e-5 / 3, 2.0e-3 + 1e-17, 3.0e-3, 200.0 / 3)
    for obj in (noise, preint.Noise.euroc()):
        back = pickle.loads(pickle.dumps(obj))
        assert back == obj and type(back) is preint.Noise
        for f in ("gyro_noise_density", "gyro_random_walk", "acc_noise_density", "acc_random_walk", "update_rate_hz"):
            assert np.float64(getattr(back, f)).tobytes() == np.float64(getattr(obj, f)).tobytes()

    bias = preint.ImuBias([0.1 / 3, -2e-300, 5e-324], [np.pi, -np.e, 1e300])
    back = pickle.loads(pickle.dumps(bias))
    assert back == bias and back.vector().tobytes() == bias.vector().tobytes()

    p = preint.Params(noise, scheme="hermite4", level="covariance")
    p.gravity = [0.01 / 3, -0.02, -9.80665]
    p.gyroscope_covariance = np.array([[3e-8, 1e-9, 0], [1e-9, 2e-8, 0], [0, 0, 1e-8 / 7]])
    p.integration_covariance = 1e-9 / 3
    p.max_gap_ns = 123_456_789
    p.keep_samples = False
    p.set_body_p_sensor([np.cos(0.2), 0.0, np.sin(0.2), 0.0], [0.1 / 3, -0.2, 0.05])
    p.omega_coriolis = [0.0, 4.8e-5, 5.4e-5]
    p.coriolis = "second"
    p.bias_correction = "group"
    back = pickle.loads(pickle.dumps(p))
    assert back == p
    for f in ("gravity", "gyroscope_covariance", "accelerometer_covariance", "integration_covariance", "omega_coriolis"):
        assert getattr(back, f).tobytes() == getattr(p, f).tobytes(), f
    for f in ("scheme", "level", "max_gap_ns", "keep_samples", "coriolis", "lever_arm", "bias_correction"):
        assert getattr(back, f) == getattr(p, f), f
    (rb, tb), (rp, tp) = back.body_p_sensor, p.body_p_sensor
    assert rb.tobytes() == rp.tobytes() and tb.tobytes() == tp.tobytes()

    t, g, a = stream(400, seed=6)
    bias = preint.ImuBias([0.1 / 3, -2e-3, 5e-324], [np.pi / 30, -np.e / 10, 1e-300])
    for scheme in SCHEMES:
        m = preint.preintegrate(params(scheme), t, g, a, int(t[2]) + 333, int(t[390]) - 77, bias=bias)
        back = pickle.loads(pickle.dumps(m, protocol=pickle.HIGHEST_PROTOCOL))
        assert back == m and type(back) is preint.PreintegratedImu
        assert_bitwise_equal(back, m, f"{scheme}: pickle")
        # A merge after the round trip uses the state pickle carried (edge noise included).
        m2 = preint.preintegrate(params(scheme), t, g, a, int(t[390]) - 77, int(t[399]), bias=bias)
        assert_bitwise_equal(
            preint.merge(back, pickle.loads(pickle.dumps(m2))), preint.merge(m, m2), f"{scheme}: merge after pickle"
        )


def test_a_corrupt_pickle_state_raises_a_typed_error():
    with pytest.raises(preint.ShapeError):
        preint.PreintegratedImu._from_state(b"\x01\x02")


# ---------------------------------------------------------------- typed errors


def clean(n: int = 40) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    t = np.arange(n, dtype=np.int64) * 5_000_000
    return t, np.tile([0.0, 0.0, 0.3], (n, 1)), np.tile([0.0, 0.0, 9.81], (n, 1))


def errors_of(t, g, a, expected_class=preint.PreintError):
    """The exception of each entry point on the same bad input."""
    p = params("midpoint")
    out = []
    with pytest.raises(expected_class) as e:
        preint.preintegrate(p, t, g, a, int(t[0]), int(t[-1]))
    out.append(e.value)
    with pytest.raises(expected_class) as e:
        preint.Preintegrator(p).integrate_arrays(t, g, a)
    out.append(e.value)
    with pytest.raises(expected_class) as e:
        pi = preint.Preintegrator(p)
        for k in range(len(t)):
            pi.integrate(int(t[k]), g[k], a[k])
    out.append(e.value)
    return out


@pytest.mark.parametrize("field", ["gyro", "acc"])
def test_nan_names_the_sample(field):
    t, g, a = clean()
    (g if field == "gyro" else a)[17, 1] = np.nan
    for e in errors_of(t, g, a):
        assert e.kind == "NonFinite" and isinstance(e, ValueError)
        assert "sample 17" in str(e) and f"non-finite {field}" in str(e) and str(t[17]) in str(e)


def test_duplicate_and_decreasing_timestamps_name_the_sample():
    t, g, a = clean()
    t[23] = t[22]
    for e in errors_of(t, g, a):
        assert e.kind == "DuplicateTimestamp" and "sample 23" in str(e)
    t, g, a = clean()
    t[30] = t[29] - 1
    for e in errors_of(t, g, a):
        assert e.kind == "DecreasingTimestamp" and "sample 30" in str(e) and "decreases" in str(e)


def test_gap_names_the_sample_and_the_limit():
    t, g, a = clean()
    t[12:] += 400_000_000  # a 0.405 s gap before sample 12; the default limit is 0.25 s
    for e in errors_of(t, g, a):
        assert e.kind == "GapTooLarge" and "sample 12" in str(e)
        assert "405000000" in str(e) and "250000000" in str(e)


def test_errors_inside_a_window_of_a_long_stream_name_the_sample_of_the_whole_arrays():
    t, g, a = clean(10_000)
    p = params("hermite4")
    g[5_550, 0] = np.nan
    with pytest.raises(preint.PreintError, match="sample 5550 "):
        preint.preintegrate(p, t, g, a, int(t[5_000]) + 1, int(t[6_000]) - 1)
    keys = np.array([t[10], t[3_000], t[5_500], t[9_000]], dtype=np.int64)
    with pytest.raises(preint.PreintError, match="sample 5550 "):
        preint.preintegrate_windows(p, t, g, a, keys)
    # A defect far outside a window does not fail it (the stream is checked around the window).
    m = preint.preintegrate(p, t, g, a, int(t[100]), int(t[200]))
    assert m.t_j_ns == t[200]
    t2 = t.copy()
    t2[7_001] = t2[7_000]
    with pytest.raises(preint.PreintError, match="sample 7001 ") as e:
        preint.preintegrate(params("midpoint"), t2, g, a, int(t[6_500]), int(t[7_500]))
    assert e.value.kind == "DuplicateTimestamp"
    # integrate_arrays converts in chunks: the index still counts from the first sample, and the
    # samples before the bad one are integrated.
    x = preint.Preintegrator(params("euler"))
    with pytest.raises(preint.PreintError, match="sample 5550 "):
        x.integrate_arrays(t, g, a)
    assert len(x) == 5_550


def test_non_contiguous_arrays_give_the_same_result():
    t, g, a = stream(500, seed=7)
    p = params("hermite4")
    wide_t = np.repeat(t, 2)[::2]  # a strided view of the same values
    wide_g, wide_a = np.hstack([g, a])[:, :3], np.hstack([a, g])[:, :3]  # rows with a stride of 6
    assert not (wide_t.flags.c_contiguous or wide_g.flags.c_contiguous or wide_a.flags.c_contiguous)
    x = preint.preintegrate(p, wide_t, wide_g, wide_a, int(t[3]) + 5, int(t[490]))
    assert_bitwise_equal(x, preint.preintegrate(p, t, g, a, int(t[3]) + 5, int(t[490])), "strided")
    y = preint.Preintegrator(p)
    y.integrate_arrays(wide_t, wide_g, wide_a)
    z = preint.Preintegrator(p)
    z.integrate_arrays(t, g, a)
    assert_bitwise_equal(y.finish(), z.finish(), "strided integrate_arrays")


def test_a_preintegrator_keeps_its_state_after_a_rejected_sample():
    t, g, a = clean()
    p = params("euler")
    x = preint.Preintegrator(p)
    x.integrate_arrays(t[:10], g[:10], a[:10])
    with pytest.raises(preint.PreintError) as e:
        x.integrate(int(t[8]), g[10], a[10])  # earlier than the last sample
    assert e.value.kind == "DecreasingTimestamp" and "sample 10" in str(e.value)
    assert len(x) == 10
    x.integrate_arrays(t[10:], g[10:], a[10:])
    assert_bitwise_equal(x.finish(), preint.preintegrate(p, t, g, a, int(t[0]), int(t[-1])), "after a rejection")


@pytest.mark.parametrize(
    "change, argument",
    [
        (lambda t, g, a: (t.astype(np.int32), g, a), "t_ns"),
        (lambda t, g, a: (t.astype(np.float64), g, a), "t_ns"),
        (lambda t, g, a: (t, g.astype(np.float32), a), "gyro"),
        (lambda t, g, a: (t, g, a.astype(np.int64)), "acc"),
        (lambda t, g, a: (t, g[:, :2], a), "gyro"),
        (lambda t, g, a: (t, g, np.hstack([a, a])), "acc"),
        (lambda t, g, a: (t, g.ravel(), a), "gyro"),
        (lambda t, g, a: (t[:-1], g, a), "same length"),
        (lambda t, g, a: (t.tolist(), g, a), "t_ns"),
        (lambda t, g, a: (t.reshape(-1, 1), g, a), "t_ns"),
    ],
)
def test_wrong_dtype_or_shape_is_a_shape_error_naming_the_argument(change, argument):
    t, g, a = change(*clean())
    with pytest.raises(preint.ShapeError) as e:
        preint.preintegrate(params("midpoint"), t, g, a, 0, 100_000_000)
    assert e.value.kind == "Shape" and argument in str(e.value) and isinstance(e.value, ValueError)
    with pytest.raises(preint.ShapeError) as e:
        preint.Preintegrator(params("midpoint")).integrate_arrays(t, g, a)
    assert argument in str(e.value)


def test_bad_scalars_windows_and_names_raise_typed_errors():
    t, g, a = clean()
    p = params("midpoint")
    with pytest.raises(preint.ShapeError, match="gyro"):
        preint.Preintegrator(p).integrate(0, [0.0, 1.0], [0.0, 0.0, 9.81])
    with pytest.raises(preint.ShapeError, match="scheme"):
        preint.Params(scheme="rk45")
    with pytest.raises(preint.ShapeError, match="level"):
        p.level = "everything"
    with pytest.raises(preint.PreintError) as e:
        preint.preintegrate(p, t, g, a, int(t[5]), int(t[5]))
    assert e.value.kind == "NonPositiveWindow"
    with pytest.raises(preint.PreintError) as e:
        preint.preintegrate(p, t, g, a, int(t[0]) - 1, int(t[5]))
    assert e.value.kind == "KeyframeOutsideSamples" and str(int(t[0]) - 1) in str(e.value)
    with pytest.raises(preint.ShapeError, match="keyframes_ns"):
        preint.preintegrate_windows(p, t, g, a, np.array([t[0]], dtype=np.int64))
    with pytest.raises(preint.ShapeError, match="keyframes_ns"):
        preint.preintegrate_windows(p, t, g, a, [int(t[0]), int(t[9])])
    bad = preint.Params()
    with pytest.raises(preint.PreintError) as e:
        bad.gyroscope_covariance = -1.0
    assert e.value.kind == "InvalidParameter" and "gyroscope_covariance" in str(e.value)
    assert bad == preint.Params()  # unchanged
    bad.validate()


# ---------------------------------------------------------------- closed form


def hat(w: np.ndarray) -> np.ndarray:
    return np.array([[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]])


def constant_rate_deltas(w: np.ndarray, f: np.ndarray, T: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Exact deltas of a body turning at a constant rate `w` [rad/s] with a constant specific
    force `f` [m/s²] (both in the body frame) over `T` [s], gravity excluded:
    R(s) = Exp(w s) = I + sin(θ s) K + (1 − cos(θ s)) K², θ = |w|, K = hat(w)/θ (Rodrigues);
    Δv = ∫₀ᵀ R(s) f ds, Δp = ∫₀ᵀ ∫₀ˢ R(u) f du ds, integrated term by term."""
    th = np.linalg.norm(w)
    K = hat(w / th)
    I = np.eye(3)
    R = I + np.sin(th * T) * K + (1 - np.cos(th * T)) * K @ K
    int_r = T * I + (1 - np.cos(th * T)) / th * K + (T - np.sin(th * T) / th) * K @ K
    int2_r = T**2 / 2 * I + (T - np.sin(th * T) / th) / th * K + (T**2 / 2 - (1 - np.cos(th * T)) / th**2) * K @ K
    return R, int_r @ f, int2_r @ f


def constant_rate_errors(scheme: str, rate_hz: int, T: float = 1.0) -> np.ndarray:
    """Max |error| of (ΔR, Δv, Δp) against the closed form, 1 s at `rate_hz`."""
    w, f = np.array([0.3, -0.2, 0.5]), np.array([0.5, -0.2, 9.81])
    n = int(T * rate_hz) + 1
    t = np.arange(n, dtype=np.int64) * (1_000_000_000 // rate_hz)
    m = preint.preintegrate(params(scheme), t, np.tile(w, (n, 1)), np.tile(f, (n, 1)), 0, int(t[-1]))
    R, v, p = constant_rate_deltas(w, f, m.delta_t)
    return np.array([np.abs(m.delta_R - R).max(), np.abs(m.delta_v - v).max(), np.abs(m.delta_p - p).max()])


def test_closed_form_itself_by_quadrature():
    # The closed form checked against brute-force numpy quadrature of R(s) f (not via preint).
    w, f, T = np.array([0.3, -0.2, 0.5]), np.array([0.5, -0.2, 9.81]), 1.0
    R, v, p = constant_rate_deltas(w, f, T)
    s = np.linspace(0.0, T, 20001)
    th, K = np.linalg.norm(w), hat(w / np.linalg.norm(w))
    Rs = np.eye(3) + np.sin(th * s)[:, None, None] * K + (1 - np.cos(th * s))[:, None, None] * (K @ K)
    Rf = Rs @ f
    vs = np.concatenate([[np.zeros(3)], np.cumsum((Rf[1:] + Rf[:-1]) / 2 * (s[1] - s[0]), axis=0)])
    ps = np.sum((vs[1:] + vs[:-1]) / 2 * (s[1] - s[0]), axis=0)
    assert np.abs(Rs[-1] - R).max() < 1e-15 and np.abs(vs[-1] - v).max() < 1e-8 and np.abs(ps - p).max() < 1e-8


@pytest.mark.parametrize("scheme, order", [("euler", 1), ("midpoint", 2), ("hermite4", 4)])
def test_constant_rate_deltas_converge_to_the_closed_form_at_the_schemes_order(scheme, order):
    e200, e400 = constant_rate_errors(scheme, 200), constant_rate_errors(scheme, 400)
    # Every scheme composes Exp(w dt) exactly at a constant rate: ΔR is exact to round-off.
    assert e200[0] < 1e-14 and e400[0] < 1e-14
    # Δv, Δp: the error halves `order` times when the rate doubles (ratio 2^order, ±25 %).
    ratio = e200[1:] / e400[1:]
    assert np.all(np.abs(np.log2(ratio) - order) < 0.33), f"{scheme}: ratios {ratio}"
    bound = {"euler": 0.1, "midpoint": 1e-4, "hermite4": 1e-9}[scheme]
    assert np.all(e200[1:] < bound) and np.all(e200[1:] > 0.0), f"{scheme}: {e200}"


# ---------------------------------------------------------------- the example script


def test_euroc_example_runs_and_its_median_errors_are_within_the_datas_limits():
    out = subprocess.run([sys.executable, str(REPO / "python" / "examples" / "euroc.py")], capture_output=True,
                         text=True, timeout=600)
    assert out.returncode == 0, out.stderr
    lines = out.stdout.splitlines()
    head = re.fullmatch(r"EuRoC V1_01_easy: 29120 IMU samples, (\d+) windows of 1 s, scheme midpoint", lines[0])
    assert head, lines[0]
    rows = [ln.split() for ln in lines[2:-1]]
    assert len(rows) == int(head.group(1)) >= 140  # 145 s of ground truth
    errors = np.array([[float(x) for x in r[2:]] for r in rows])
    assert [int(r[0]) for r in rows] == list(range(len(rows)))
    assert np.allclose([float(r[1]) for r in rows], np.arange(len(rows)), atol=1e-3)  # 1 s apart
    med = re.fullmatch(r"median rotation \[deg\] (\S+) velocity \[m/s\] (\S+) position \[m\] (\S+)", lines[-1])
    assert med, lines[-1]
    medians = np.array([float(x) for x in med.groups()])
    assert np.allclose(medians, np.median(errors, axis=0), atol=1e-4)
    # The data's limits (tests/data/README.md, midpoint, 1 s windows from the ground truth):
    # 0.10°, 0.045 m/s, 0.024 m; bounds with margin.
    assert medians[0] < 0.15 and medians[1] < 0.06 and medians[2] < 0.035, medians
    assert np.all(errors[:, 0] < 1.0) and np.all(errors[:, 1] < 0.3) and np.all(errors[:, 2] < 0.2)


def test_params_bias_correction_property():
    p = preint.Params()
    assert p.bias_correction is None
    p.bias_correction = "group"
    assert p.bias_correction == "group"
    p.bias_correction = None
    assert p.bias_correction is None
    with pytest.raises(preint.ShapeError, match="bias correction"):
        p.bias_correction = "multiplicative"
