"""Allan variance, calibration and advice from Python, checked against independent numpy
computations on synthetic data of known noise and bias, and against the recordings' published
figures; refusals raise CalibrationError with the Rust message.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import preint

DATA = Path(__file__).resolve().parents[2] / "tests" / "data"
EUROC = DATA / "euroc" / "V1_01_easy_imu0.csv"
EUROC_NOISE = DATA / "euroc" / "imu.yaml"
BROAD = DATA / "broad" / "broad_10_undisturbed_slow_translation_A_30s_45s.csv"
ADIS = DATA / "adis16405" / "adis16405_run1_first3600s_10Hz_blockmean.csv"
SIGMA_G, SIGMA_A = 1.6968e-4, 2.0e-3  # EuRoC densities (tests/data/euroc/imu.yaml)


def stamps(n: int, dt: float) -> np.ndarray:
    return (np.arange(n) * round(dt * 1e9)).astype(np.int64)


def white(seed: int, n: int, dt: float, densities) -> np.ndarray:
    """Discrete white noise of continuous densities `densities` (σ = N/√Δt per sample)."""
    return np.random.default_rng(seed).standard_normal((n, len(densities))) * (
        np.asarray(densities) / math.sqrt(dt)
    )


# --- Allan variance ---------------------------------------------------------------------------


def overlapping_adev(y: np.ndarray, m: int) -> float:
    """IEEE 952 overlapping Allan deviation at τ = mΔt from the cumulative sum (numpy)."""
    theta = np.concatenate([[0.0], np.cumsum(y - y.mean())])
    d = theta[2 * m:] - 2 * theta[m:-m] + theta[:-2 * m]
    return math.sqrt(np.sum(d * d) / (2.0 * m * m * d.size))


def test_allan_of_white_noise_recovers_the_density():
    dt, n = 0.01, 60_000  # 10 min at 100 Hz
    dens = np.array([1e-3, 1e-3, 1e-3, 2e-2, 2e-2, 2e-2])
    x = white(7, n, dt, dens)
    r = preint.allan_variance(stamps(n, dt), x[:, :3], x[:, 3:] + [0.0, 0.0, 9.81])
    # N from ~60 000 samples: relative σ ≈ 1 % (white_density_err); 5 % is > 4σ.
    np.testing.assert_allclose(r["white_density"], dens, rtol=0.05)
    assert np.all(np.abs(r["white_density"] - dens) < 4 * r["white_density_err"])
    assert not r["white_density_is_bound"].any()
    # The curve itself against an independent numpy estimator at τ = Δt and τ = 10Δt.
    for m in (1, 10):
        k = int(np.argmin(np.abs(r["tau"] - m * dt)))
        assert r["tau"][k] == pytest.approx(m * dt)
        for c in range(6):
            assert r["adev"][k, c] == pytest.approx(overlapping_adev(x[:, c], m), rel=1e-9)
    assert r["adev"].shape == (r["tau"].size, 6) and r["adev_err"].shape == r["adev"].shape
    # Kalibr figures: the maximum over the axes.
    assert r["noise"].gyro_noise_density == pytest.approx(r["white_density"][:3].max())
    assert r["noise"].acc_noise_density == pytest.approx(r["white_density"][3:].max())
    assert r["noise"].update_rate_hz == pytest.approx(100.0)


def test_allan_random_walk_within_its_stated_error():
    dt, n = 0.01, 360_000  # 1 h at 100 Hz, white noise + bias random walk
    dens = np.array([1e-3] * 3 + [2e-2] * 3)
    walk = np.array([2e-5] * 3 + [4e-4] * 3)
    rng = np.random.default_rng(0)
    x = rng.standard_normal((n, 6)) * dens / math.sqrt(dt)
    x += np.cumsum(rng.standard_normal((n, 6)) * walk * math.sqrt(dt), axis=0)
    r = preint.allan_variance(stamps(n, dt), x[:, :3], x[:, 3:] + [0.0, 0.0, 9.81])
    fitted = ~r["random_walk_is_bound"]
    assert fitted.sum() >= 2
    err = np.abs(r["random_walk"] - walk)[fitted]
    assert np.all(err < 3 * r["random_walk_err"][fitted])


def test_allan_file_matches_the_published_adis16405_figure_and_the_arrays():
    r = preint.allan_variance_file(ADIS)
    # The curators' figure (tests/data/README.md): gyro σ(1 s) ≈ 0.041 deg/s.
    k = int(np.argmin(np.abs(r["tau"] - 1.0)))
    assert r["tau"][k] == pytest.approx(1.0)
    np.testing.assert_allclose(np.rad2deg(r["adev"][k, :3]), 0.041, rtol=0.15)
    assert r["stillness"]["still_fraction"] == 1.0
    d = preint.read_imu(ADIS)
    a = preint.allan_variance(d["t_ns"], d["gyro"], d["acc"])
    np.testing.assert_array_equal(a["adev"], r["adev"])
    np.testing.assert_array_equal(a["white_density"], r["white_density"])


def test_allan_refuses_a_moving_recording():
    d = preint.read_imu(BROAD)  # at rest until 36.8 s, then moving
    with pytest.raises(preint.CalibrationError, match="not static") as e:
        preint.allan_variance(d["t_ns"], d["gyro"], d["acc"])
    assert e.value.kind == "NotStatic"
    with pytest.raises(preint.CalibrationError, match="not static"):
        preint.allan_variance_file(BROAD)
    r = preint.allan_variance(d["t_ns"], d["gyro"], d["acc"], check_still=False)
    assert r["stillness"]["still_fraction"] < 0.9


def test_allan_refuses_a_gap():
    dt, n = 0.01, 2000
    x = white(1, n, dt, [1e-3] * 6)
    t = stamps(n, dt)
    t[1000:] += 50_000_000  # a 50 ms gap
    with pytest.raises(preint.CalibrationError) as e:
        preint.allan_variance(t, x[:, :3], x[:, 3:] + [0, 0, 9.81], check_still=False)
    assert e.value.kind == "Timestamps" and "interval 999" in str(e.value)


# --- calibration --------------------------------------------------------------------------------


def expm(v: np.ndarray) -> np.ndarray:
    """Rodrigues' formula."""
    th = float(np.linalg.norm(v))
    if th < 1e-15:
        return np.eye(3)
    k = v / th
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + math.sin(th) * K + (1 - math.cos(th)) * K @ K


def static_recording(seed, bg, ba, r_wb, seconds=20.0, rate=200.0, g=9.81):
    dt = 1.0 / rate
    n = int(seconds * rate)
    noise = white(seed, n, dt, [SIGMA_G] * 3 + [SIGMA_A] * 3)
    gyro = bg + noise[:, :3]
    acc = r_wb.T @ np.array([0.0, 0.0, g]) + ba + noise[:, 3:]
    return stamps(n, dt), gyro, acc


def test_static_calibration_recovers_the_gyro_bias_with_the_predicted_sigma():
    bg = np.array([0.01, -0.02, 0.005])
    r_wb = expm(np.array([0.1, -0.05, 0.3]))
    t, g, a = static_recording(3, bg, np.zeros(3), r_wb)
    noise = preint.Noise(SIGMA_G, 0.0, SIGMA_A, 0.0, 200.0)
    c = preint.calibrate_static(t, g, a, noise)
    iv = c["interval"]
    # σ of the mean of white noise over the interval: σ_g / √T (T = samples · Δt).
    T = (iv["end"] - iv["start"]) * 0.005
    sd = SIGMA_G / math.sqrt(T)
    np.testing.assert_allclose(c["gyro_bias_std"], sd, rtol=0.02)
    assert np.all(np.abs(c["gyro_bias"] - bg) < 4 * sd)
    # Up direction: the mean specific force's, σ ≈ σ_a/√T / g per axis.
    up = r_wb.T @ np.array([0.0, 0.0, 1.0])
    assert np.linalg.norm(c["up_body"] - up) < 4 * math.sqrt(3) * SIGMA_A / math.sqrt(T) / 9.81
    assert c["acc_bias"] is None and "acc_bias" in c["unobservable"]
    assert iv["duration_s"] > 15.0


def test_static_calibration_of_a_file_equals_the_arrays(tmp_path):
    t, g, a = static_recording(4, np.array([0.002, 0.001, -0.003]), np.zeros(3), np.eye(3))
    p = tmp_path / "static.csv"
    rows = [",".join([str(int(t[k]))] + [repr(float(v)) for v in (*g[k], *a[k])])
            for k in range(t.size)]
    p.write_text("#timestamp [ns],w_x,w_y,w_z,a_x,a_y,a_z\n" + "\n".join(rows) + "\n")
    f = preint.calibrate_file(p)  # default noise: EuRoC, as the arrays below
    c = preint.calibrate_static(t, g, a)
    assert f["model"] == "static-single-attitude"
    np.testing.assert_array_equal(np.array(f["gyro_bias"]), c["gyro_bias"])
    np.testing.assert_array_equal(np.array(f["gyro_bias_std"]), c["gyro_bias_std"])
    assert f["interval_ns"] == [c["interval"]["t_start_ns"], c["interval"]["t_end_ns"]]


def test_latitude_removes_the_vertical_earth_rate():
    t, g, a = static_recording(8, np.zeros(3), np.zeros(3), np.eye(3), seconds=5.0)
    c0 = preint.calibrate_static(t, g, a)
    c = preint.calibrate_static(t, g, a, latitude=47.4)
    omega_e = 7.292115e-5  # rad/s (WGS-84)
    # Ω_E sin φ along the measured up direction (≈ +z for this level sensor) comes off b_g.
    assert np.linalg.norm(c0["up_body"] - [0.0, 0.0, 1.0]) < 1e-3
    np.testing.assert_allclose(c0["gyro_bias"] - c["gyro_bias"],
                               omega_e * math.sin(math.radians(47.4)) * c0["up_body"],
                               rtol=0, atol=omega_e * 1e-6)
    with pytest.raises(preint.ShapeError, match="latitude"):
        preint.calibrate_static(t, g, a, latitude=95.0)
    with pytest.raises(preint.ShapeError, match="heading needs latitude"):
        preint.calibrate_static(t, g, a, heading=10.0)


def test_calibration_refuses_moving_data():
    d = preint.read_imu(BROAD)
    moving = d["t_ns"] >= 37_000_000_000
    with pytest.raises(preint.CalibrationError, match="no still interval") as e:
        preint.calibrate_static(d["t_ns"][moving], d["gyro"][moving], d["acc"][moving])
    assert e.value.kind == "NotStatic"
    with pytest.raises(preint.CalibrationError, match="no still interval") as e:
        preint.calibrate_file(BROAD, from_ns=37_000_000_000)
    assert str(BROAD) in str(e.value)
    # One attitude is not a multi-position calibration.
    t, g, a = static_recording(5, np.zeros(3), np.zeros(3), np.eye(3))
    with pytest.raises(preint.CalibrationError, match="too few still intervals") as e:
        preint.calibrate_multi_pose(t, g, a)
    assert e.value.kind == "TooFew"


def test_calibration_rejects_bad_samples():
    t, g, a = static_recording(6, np.zeros(3), np.zeros(3), np.eye(3), seconds=2.0)
    g[100, 1] = np.nan
    with pytest.raises(preint.CalibrationError, match="sample 100") as e:
        preint.calibrate_static(t, g, a)
    assert e.value.kind == "NonFinite"
    with pytest.raises(preint.ShapeError):
        preint.calibrate_static(t.astype(np.float64), g, a)


def multi_pose_recording(seed, bg, ba, rate=200.0, still_s=6.0, turn_s=2.0, g=9.81):
    """Seven still attitudes linked by 90° turns at constant rate about axes perpendicular to
    gravity (a turn about the vertical would look still)."""
    dt = 1.0 / rate
    r = np.eye(3)
    gyro, acc = [], []

    def still(r):
        k = int(still_s * rate)
        gyro.extend([np.zeros(3)] * k)
        acc.extend([r.T @ np.array([0.0, 0.0, g])] * k)

    still(r)
    for h in ([1, 0, 0], [0, 1, 0], [1, 1, 0], [0, 1, 1], [1, 0, 1], [1, -1, 0]):
        k = int(turn_s * rate)
        e = np.cross(r.T @ np.array([0.0, 0.0, 1.0]), np.asarray(h, float))
        w = e / np.linalg.norm(e) * (math.pi / 2) / turn_s
        for i in range(k):
            gyro.append(w.copy())
            acc.append((r @ expm(w * i * dt)).T @ np.array([0.0, 0.0, g]))
        r = r @ expm(w * k * dt)
        still(r)
    n = len(gyro)
    noise = white(seed, n, dt, [SIGMA_G] * 3 + [SIGMA_A] * 3)
    return stamps(n, dt), np.array(gyro) + bg + noise[:, :3], np.array(acc) + ba + noise[:, 3:]


def test_multi_pose_calibration_recovers_both_biases():
    bg = np.array([0.003, -0.002, 0.004])
    ba = np.array([0.05, -0.04, 0.08])
    t, g, a = multi_pose_recording(0, bg, ba)
    c = preint.calibrate_multi_pose(t, g, a, EUROC_NOISE)
    assert len(c["intervals"]) == 7
    assert c["model"] == "multi-pose/bias-only"  # the truth has no scale errors
    assert np.all(np.abs(c["gyro_bias"] - bg) < 4 * c["gyro_bias_std"])
    assert np.all(np.abs(c["acc_bias"] - ba) < 4 * c["acc_bias_std"])
    assert c["R_wb"].shape == (7, 3, 3)


# --- advise -------------------------------------------------------------------------------------


def test_advise_on_arrays_equals_the_command_and_predicts_the_noise_sigma():
    d = preint.read_imu(EUROC)
    end = int(d["t_ns"][0]) + 4_000_000_000
    m = d["t_ns"] <= end
    a = preint.advise(d["t_ns"][m], d["gyro"][m], d["acc"][m], EUROC_NOISE, window=1.0)
    f = preint.advise_file(EUROC, noise=EUROC_NOISE, to_ns=end, window=1.0)
    assert a["samples"] == f["samples"] == int(m.sum())
    assert len(a["candidates"]) == len(f["candidates"]) > 0
    for x, y in zip(a["candidates"], f["candidates"]):
        assert (x["scheme"], x["rate"]) == (y["scheme"], y["rate"])
        assert x["disc_err"] == y["disc_err"] and x["noise_sigma"] == y["noise_sigma"]
        # Rotation σ over a window of T ≥ 1 s of white gyro noise (the window ends at the first
        # sample at or after 1 s, T ≤ 1 s + 1/rate): √trace = σ_g √(3 T) for Euler's
        # propagation; the other schemes weight the samples differently (within a few %).
        ratio = x["noise_sigma"]["rot_rad"] / (SIGMA_G * math.sqrt(3.0))
        hi = math.sqrt(1.0 + 1.0 / x["rate"])
        if x["scheme"] == "euler":
            assert 1.0 - 1e-6 <= ratio <= hi + 1e-6
        else:
            assert 0.95 <= ratio <= hi * 1.05
    assert a["recommended_scheme"] in (None, "euler", "midpoint", "hermite4")


def test_advise_held_input_on_arrays_equals_the_command():
    d = preint.read_imu(EUROC)
    end = int(d["t_ns"][0]) + 4_000_000_000
    m = d["t_ns"] <= end
    a = preint.advise(d["t_ns"][m], d["gyro"][m], d["acc"][m], EUROC_NOISE, window=1.0, input="held")
    f = preint.advise_file(EUROC, noise=EUROC_NOISE, to_ns=end, window=1.0, input="held")
    assert a["input_class"] == f["input_class"] == "held"
    assert a["exact_scheme"] == f["exact_scheme"] == "galilean"
    assert a["denoise_cutoff_hz"] == f["denoise_cutoff_hz"]
    for x, y in zip(a["candidates"], f["candidates"], strict=True):
        assert (x["scheme"], x["rate"], x["disc_err"]) == (y["scheme"], y["rate"], y["disc_err"])
    s = preint.advise(d["t_ns"][m], d["gyro"][m], d["acc"][m], EUROC_NOISE, window=1.0)
    assert s["input_class"] == "smooth" and s["exact_scheme"] is None
    with pytest.raises(preint.ShapeError):
        preint.advise(d["t_ns"][m], d["gyro"][m], d["acc"][m], EUROC_NOISE, input="stepwise")


def test_advise_refusals_are_typed():
    d = preint.read_imu(EUROC)
    m = slice(0, 100)  # 0.5 s: shorter than the window
    with pytest.raises(preint.ShapeError):
        preint.advise(d["t_ns"][m], d["gyro"][m], d["acc"][m], EUROC_NOISE, window=1.0)
    with pytest.raises(preint.ShapeError):
        preint.advise(d["t_ns"][:800], d["gyro"][:800], d["acc"][:800], EUROC_NOISE,
                      fraction=-1.0)


# --- Time offset and intrinsics from known poses ------------------------------------------------

EUROC_GT = DATA / "euroc" / "V1_01_easy_groundtruth_vicon2gt.csv"


def test_time_offset_from_known_poses_equals_the_command(preint_cli, tmp_path):
    """``calibrate_file(estimate=...)`` is ``preint calibrate --estimate ... --json`` (the same
    numbers, parsed from the same JSON), and the calibration file ``out`` writes carries the
    estimated time offset."""
    import json
    import subprocess

    t0 = 1_403_715_283_262_142_976  # 10 s into the ground truth
    span = ["--from", str(t0), "--to", str(t0 + 20_000_000_000)]
    out = tmp_path / "calib.yaml"
    f = preint.calibrate_file(EUROC, poses=EUROC_GT, from_ns=t0, to_ns=t0 + 20_000_000_000,
                              pose_rot_std=1.75e-3, pose_pos_std=0.005,
                              estimate="time-offset", out=out)
    r = subprocess.run([*preint_cli, "calibrate", "--imu", str(EUROC), "--poses", str(EUROC_GT),
                        *span, "--pose-rot-std", "1.75e-3", "--pose-pos-std", "0.005",
                        "--estimate", "time-offset", "--json"],
                       check=True, capture_output=True, text=True)
    c = json.loads(r.stdout)
    assert f["model"] == c["model"] == "known-poses"
    assert f["parameters"] == c["parameters"]
    (td,) = f["parameters"]
    assert td["name"] == "t_d" and td["unit"] == "s" and td["excited"]
    assert abs(td["value"]) < 0.02 and 0 < td["std"] < 1e-3
    text = out.read_text()
    assert "time_offset:" in text and repr(f["time_offset_s"]) in text


def test_extrinsics_from_known_poses_equal_the_command(preint_cli, tmp_path):
    """``calibrate_file(estimate=["extrinsic-rotation", "lever-arm"])`` on EuRoC poses
    re-expressed in a frame turned by 90° about z with the IMU 0.2 m along x of it: the result's
    ``extrinsics`` equal the command's, and the rotation found (from the hand-eye start, no
    guess given) is the hidden one to 1° (10 s of this recording do not excite every
    component to the 5 mrad limit: ``cargo test -p preint-calib --test known_pose_extrinsics``
    has the 3σ check on 20 s)."""
    import json
    import subprocess

    t0 = 1_403_715_283_262_142_976  # 10 s into the ground truth
    rows = [r for r in EUROC_GT.read_text().splitlines() if r and not r.startswith("#")]
    # R_bs = Rz(90°): the body's attitude R_b = R_s R_bsᵀ, its origin p_b = p_s − R_b p_bs.
    c, s = 0.0, 1.0
    rbs = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    p_bs = np.array([0.2, 0.0, 0.0])
    out_rows = []
    for r in rows:
        v = r.split(",")
        t = int(v[0])
        if not (t0 - 1_000_000_000 <= t <= t0 + 11_000_000_000):
            continue
        p = np.array([float(x) for x in v[1:4]])
        w, x, y, z = (float(q) for q in v[4:8])
        rs = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                       [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                       [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])
        rb = rs @ rbs.T
        pb = p - rb @ p_bs
        qw = 0.5 * math.sqrt(max(0.0, 1 + np.trace(rb)))
        q = [qw, (rb[2, 1] - rb[1, 2]) / (4 * qw), (rb[0, 2] - rb[2, 0]) / (4 * qw),
             (rb[1, 0] - rb[0, 1]) / (4 * qw)]
        out_rows.append(",".join([str(t), *(repr(float(u)) for u in pb), *(repr(float(u)) for u in q)]))
    poses = tmp_path / "body_poses.csv"
    poses.write_text("#t,x,y,z,qw,qx,qy,qz\n" + "\n".join(out_rows) + "\n")
    span = dict(from_ns=t0, to_ns=t0 + 10_000_000_000)
    f = preint.calibrate_file(EUROC, poses=poses, **span, pose_rot_std=1.75e-3,
                              pose_pos_std=0.005, estimate=["extrinsic-rotation", "lever-arm"])
    r = subprocess.run([*preint_cli, "calibrate", "--imu", str(EUROC), "--poses", str(poses),
                        "--from", str(t0), "--to", str(t0 + 10_000_000_000),
                        "--pose-rot-std", "1.75e-3", "--pose-pos-std", "0.005",
                        "--estimate", "extrinsic-rotation,lever-arm", "--json"],
                       check=True, capture_output=True, text=True)
    e = f["extrinsics"]
    assert e == json.loads(r.stdout)["extrinsics"]
    assert e["start"] == "hand-eye"
    qw, qx, qy, qz = e["body_p_sensor"][3:]
    # Rz(90°) is (cos 45°, 0, 0, sin 45°); |δq| ≈ |δθ|/2.
    err = max(abs(qw - math.sqrt(0.5)), abs(qx), abs(qy), abs(qz - math.sqrt(0.5)))
    assert err <= 0.5 * math.radians(1.0), (e["body_p_sensor"], e["std_scaled"])
    assert len(e["covariance"]) == 6 and "R_bs*Exp" in e["tangent"]


def test_scheme_and_fit_of_a_known_pose_calibration_equal_the_command(preint_cli, tmp_path):
    """``calibrate_file(scheme="euler")`` is ``preint calibrate --scheme euler --json``: the
    same fit and scaled σ; the calibration file records the scheme; an unknown scheme is refused
    naming the accepted ones."""
    import json
    import subprocess

    t0 = 1_403_715_283_262_142_976
    out = tmp_path / "calib.yaml"
    f = preint.calibrate_file(EUROC, poses=EUROC_GT, from_ns=t0, to_ns=t0 + 20_000_000_000,
                              pose_rot_std=1.75e-3, pose_pos_std=0.005,
                              estimate="time-offset", scheme="euler", out=out)
    r = subprocess.run([*preint_cli, "calibrate", "--imu", str(EUROC), "--poses", str(EUROC_GT),
                        "--from", str(t0), "--to", str(t0 + 20_000_000_000),
                        "--pose-rot-std", "1.75e-3", "--pose-pos-std", "0.005",
                        "--estimate", "time-offset", "--scheme", "euler", "--json"],
                       check=True, capture_output=True, text=True)
    c = json.loads(r.stdout)
    assert f["scheme"] == c["scheme"] == "euler"
    assert f["fit"] == c["fit"] and f["fit"]["dof"] > 30
    assert f["gyro_bias_std_scaled"] == c["gyro_bias_std_scaled"]
    assert f["time_offset_s"] is not None and 'preint_scheme: "euler"' in out.read_text()
    with pytest.raises(ValueError, match="unknown scheme"):
        preint.calibrate_file(EUROC, poses=EUROC_GT, scheme="rk45")


def test_estimate_refusals():
    with pytest.raises(preint.InputError, match="give poses"):
        preint.calibrate_file(EUROC, estimate="time-offset")
    with pytest.raises(preint.InputError, match="unknown parameter `scale`"):
        preint.calibrate_file(EUROC, poses=EUROC_GT, estimate="time-offset,scale")


def test_audit_with_a_calibration_file(tmp_path):
    """``audit(calibration=...)``: the file's accelerometer scale divides the median norm."""
    cal = tmp_path / "c.yaml"
    cal.write_text("%YAML:1.0\nimu0:\n  model: \"kalibr\"\n  Ta:\n    - [1.02, 0.0, 0.0]\n"
                   "    - [0.0, 1.02, 0.0]\n    - [0.0, 0.0, 1.02]\n  time_offset: 0.001\n")
    a = preint.audit(EUROC, calibration=cal)
    u = a["units"]
    assert u["gravity_median_m_s2"] == pytest.approx(u["raw_gravity_median_m_s2"] / 1.02, rel=1e-9)
    assert a["calibration"]["time_offset_s"] == 0.001
    assert "calibration" in [f["kind"] for f in a["findings"]]


def _calibration_file(tmp_path: Path) -> Path:
    """An OpenVINS kalibr_imu_chain.yaml with every term: 1 % scales, 2 mrad misalignments,
    an axis rotation, g-sensitivity and a time offset."""
    p = tmp_path / "intrinsics.yaml"
    p.write_text(
        "%YAML:1.0\nimu0:\n  model: \"kalibr\"\n"
        "  Tw:\n    - [1.01, 0.0, 0.0]\n    - [0.002, 0.99, 0.0]\n    - [-0.002, 0.001, 1.005]\n"
        "  R_IMUtoGYRO:\n    - [0.9999980000006666, -0.0019999986666669335, 0.0]\n"
        "    - [0.0019999986666669335, 0.9999980000006666, 0.0]\n    - [0.0, 0.0, 1.0]\n"
        "  Ta:\n    - [0.99, 0.0, 0.0]\n    - [-0.002, 1.01, 0.0]\n    - [0.001, 0.002, 1.0]\n"
        "  R_IMUtoACC:\n    - [1.0, 0.0, 0.0]\n    - [0.0, 1.0, 0.0]\n    - [0.0, 0.0, 1.0]\n"
        "  Tg:\n    - [0.0002, 0.0, 0.0001]\n    - [0.0, -0.0003, 0.0]\n    - [0.0001, 0.0, 0.0002]\n"
        "  time_offset: 0.0042\n")
    return p


def test_read_calibration_and_apply_intrinsics(tmp_path, euroc_imu):
    """``apply_intrinsics`` against OpenVINS' correction written here in numpy
    (``a' = R_ACCtoIMU Ta⁻¹ a_m``, ``ω' = R_GYROtoIMU Tw⁻¹ (ω_m − Tg a')``)."""
    cal = _calibration_file(tmp_path)
    c = preint.read_calibration(cal)
    assert c["model"] == "kalibr" and c["time_offset_s"] == 0.0042 and c["noise"] is None
    assert c["Tw"].shape == (3, 3) and c["Tw"][1, 0] == 0.002 and c["Tg"][0, 2] == 0.0001
    t, g, a = euroc_imu
    g2, a2 = preint.apply_intrinsics(cal, t, g, a)
    a_ref = (c["R_IMUtoACC"].T @ np.linalg.inv(c["Ta"]) @ a.T).T
    w_ref = (c["R_IMUtoGYRO"].T @ np.linalg.inv(c["Tw"]) @ (g.T - c["Tg"] @ a_ref.T)).T
    np.testing.assert_allclose(a2, a_ref, rtol=0, atol=1e-13)
    np.testing.assert_allclose(g2, w_ref, rtol=0, atol=1e-13)
    assert np.abs(a2 - a).max() > 0.05  # the intrinsics do change the samples
    with pytest.raises(preint.InputError, match="nope.yaml"):
        preint.read_calibration(tmp_path / "nope.yaml")


def test_apply_intrinsics_is_integrate_calibration(preint_cli, tmp_path, euroc_imu):
    """Preintegrating the corrected arrays over keyframes moved by the file's time offset is
    ``preint integrate --calibration`` (to rounding: the command corrects interpolated boundary
    samples, here the samples are corrected before the interpolation)."""
    import json
    import subprocess

    cal = _calibration_file(tmp_path)
    t, g, a = euroc_imu
    g2, a2 = preint.apply_intrinsics(cal, t, g, a)
    ti, tj = 1_403_715_280_000_000_000, 1_403_715_281_000_000_000
    r = subprocess.run([*preint_cli, "integrate", "--imu", str(EUROC), "--from", str(ti), "--to",
                        str(tj), "--calibration", str(cal), "--json"],
                       check=True, capture_output=True, text=True)
    cli = json.loads(r.stdout)
    td = round(0.0042 * 1e9)
    m = preint.preintegrate(preint.Params(preint.Noise.euroc()), t, g2, a2, ti + td, tj + td)
    np.testing.assert_allclose(m.delta_v, cli["delta_v"], rtol=0, atol=1e-12)
    np.testing.assert_allclose(m.delta_p, cli["delta_p"], rtol=0, atol=1e-12)
    np.testing.assert_allclose(m.delta_R, cli["delta_R"], rtol=0, atol=1e-12)


# --- Noise model from ground truth ---------------------------------------------------------------


def test_noise_model_from_ground_truth_equals_the_command(preint_cli, tmp_path):
    """``calibrate_file(estimate="noise")`` is ``preint calibrate --estimate noise --json``
    (the whole dict, from the same JSON), the Kalibr imu.yaml of ``out`` holds the fitted
    accelerometer density, EuRoC's accelerometer comes out noisier than its datasheet's
    2e-3 m/s²/√Hz, and the vicon2gt world frame is tilted from gravity by about 0.24° (the
    whole recording's estimate, within 3σ of this slice's)."""
    import json
    import subprocess

    t0 = 1_403_715_283_262_142_976  # 10 s into the ground truth; 30 s keep the test cheap
    t1 = t0 + 30_000_000_000
    out = tmp_path / "fitted.yaml"
    f = preint.calibrate_file(EUROC, poses=EUROC_GT, noise=EUROC_NOISE, from_ns=t0, to_ns=t1,
                              estimate="noise", window=[0.5, 1, 2, 4], vel_std=None,
                              bias_gyro_std=None, bias_acc_std=None, out=out)
    r = subprocess.run([*preint_cli, "calibrate", "--imu", str(EUROC), "--poses", str(EUROC_GT),
                        "--noise", str(EUROC_NOISE), "--from", str(t0), "--to", str(t1),
                        "--estimate", "noise", "--window", "0.5,1,2,4", "--out", str(out),
                        "--json"],
                       check=True, capture_output=True, text=True)
    c = json.loads(r.stdout)
    assert f == c
    assert f["estimate"] == "noise" and f["written"] == str(out)
    assert [row["length_s"] for row in f["per_length"]] == [0.5, 1.0, 2.0, 4.0]
    assert [row["count"] for row in f["per_length"]] == [60, 30, 15, 7]
    acc = f["noise"]["accelerometer_noise_density"]
    assert acc > 2e-3
    (line,) = [x for x in out.read_text().splitlines()
               if x.startswith("accelerometer_noise_density:")]
    assert float(line.split(":")[1].split("#")[0]) == acc
    as_list = preint.calibrate_file(EUROC, poses=EUROC_GT, noise=EUROC_NOISE, from_ns=t0,
                                    to_ns=t1, estimate=["noise"], window=[0.5, 1, 2, 4])
    assert as_list["gravity"] == f["gravity"] and as_list["noise"] == f["noise"]
    with pytest.raises(preint.InputError, match="list of names"):
        preint.calibrate_file(EUROC, poses=EUROC_GT, estimate=3)
    g = f["gravity"]
    assert g["supported"] and g["likelihood_ratio"] > g["bic_penalty"]
    assert abs(g["tilt_deg"] - 0.236) < 3 * g["tilt_deg_std"]
    assert g["vector"] == [a + d for a, d in zip(g["given"], g["correction"])]


def test_noise_model_arguments_are_refused_without_estimate_noise():
    """``window``, ``vel_std``, ``bias_gyro_std``, ``bias_acc_std`` are read by
    ``estimate="noise"`` only, and ``noise`` is estimated on its own; a held value must be
    non-negative (the command's flag named)."""
    for kw in ({"window": [1.0]}, {"vel_std": 0.01}, {"bias_gyro_std": 1e-4},
               {"bias_acc_std": 1e-3}):
        (name,) = kw
        with pytest.raises(preint.InputError, match=f"{name} is read by estimate=\"noise\""):
            preint.calibrate_file(EUROC, poses=EUROC_GT, **kw)
    with pytest.raises(preint.InputError, match="`noise` is estimated on its own"):
        preint.calibrate_file(EUROC, poses=EUROC_GT, estimate="noise,time-offset")
    with pytest.raises(preint.ShapeError, match="--vel-std"):
        preint.calibrate_file(EUROC, poses=EUROC_GT, estimate="noise", vel_std=-1.0)


def test_initialise_file_equals_the_command(preint_cli, tmp_path):
    """``initialise_file`` on 4 s of EuRoC with the ground truth's positions divided by 4 (a
    front end's unknown scale): the result equals ``preint initialise --json`` on the same
    files, the scale found is 0.25 m per unit to 5 %, gravity is 9.81 m/s² long and the
    covariance has the order it names; ``scale="known"`` on the metric poses gives scale 1."""
    import json
    import subprocess

    t0 = 1_403_715_283_262_142_976
    rows = [r for r in EUROC_GT.read_text().splitlines() if r and not r.startswith("#")]
    out_rows = []
    for r in rows:
        v = r.split(",")
        if not (t0 <= int(v[0]) <= t0 + 4_000_000_000):
            continue
        p = [repr(float(x) * 4.0) for x in v[1:4]]
        out_rows.append(",".join([v[0], *p, *v[4:8]]))
    poses = tmp_path / "keyframes.csv"
    poses.write_text("#t,x,y,z,qw,qx,qy,qz\n" + "\n".join(out_rows) + "\n")
    f = preint.initialise_file(EUROC, poses=poses, pose_rot_std=1e-3, pose_pos_std=0.008)
    r = subprocess.run([*preint_cli, "initialise", "--imu", str(EUROC), "--poses", str(poses),
                        "--pose-rot-std", "1e-3", "--pose-pos-std", "0.008", "--json"],
                       check=True, capture_output=True, text=True)
    c = json.loads(r.stdout)
    for key in ["scale", "scale_std", "gravity", "bias_gyro", "bias_acc", "covariance", "ready",
                "reason", "velocities", "covariance_order"]:
        assert f[key] == c[key], key
    assert abs(f["scale"] / 0.25 - 1.0) < 0.05, f["scale"]
    assert abs(np.linalg.norm(f["gravity"]) - 9.81) < 1e-9
    assert f["covariance_order"][:4] == ["s", "g.x", "g.y", "g.z"]
    assert np.asarray(f["covariance"]).shape == (10, 10)
    k = preint.initialise_file(EUROC, poses=EUROC_GT, scale="known", from_ns=t0,
                               to_ns=t0 + 2_000_000_000, pose_pos_std=0.002)
    assert (k["scale"], k["scale_std"], k["scale_mode"]) == (1.0, 0.0, "known")
    with pytest.raises(preint.InputError):
        preint.initialise_file(EUROC, poses=poses, scale="metric")
