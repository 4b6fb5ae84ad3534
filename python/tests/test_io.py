"""The readers from Python: every fixture of tests/data read by preint gives the values an
independent parse in Python gives (exact decimal-to-float conversion, integer nanoseconds),
errors are typed and name the file and line.
"""

from __future__ import annotations

import math
from decimal import Decimal
from pathlib import Path

import numpy as np
import pytest

import preint

DATA = Path(__file__).resolve().parents[2] / "tests" / "data"
EUROC = DATA / "euroc" / "V1_01_easy_imu0.csv"
GT = DATA / "euroc" / "V1_01_easy_groundtruth_vicon2gt.csv"


def parse_euroc(path: Path, rows: int | None = None):
    """EuRoC imu0 rows parsed with Python's int/float (both exact / correctly rounded)."""
    t: list[int] = []
    vals: list[list[float]] = []
    for line in path.read_text().splitlines():
        if not line.strip() or line.startswith("#"):
            continue
        f = line.split(",")
        t.append(int(f[0]))
        vals.append([float(x) for x in f[1:7]])
        if rows is not None and len(t) == rows:
            break
    v = np.array(vals)
    return np.array(t, dtype=np.int64), v[:, 0:3], v[:, 3:6]


def test_euroc_csv_is_read_exactly():
    d = preint.read_imu(EUROC)
    t, g, a = parse_euroc(EUROC)
    assert d["t_ns"].dtype == np.int64 and d["t_ns"].shape == (29120,)
    assert d["gyro"].dtype == np.float64 and d["gyro"].shape == (29120, 3)
    np.testing.assert_array_equal(d["t_ns"], t)
    np.testing.assert_array_equal(d["gyro"], g)
    np.testing.assert_array_equal(d["acc"], a)
    assert d["format"] == "euroc"
    assert d["units"] == {"time": "ns", "gyro": "rad/s", "accel": "m/s2"}
    assert d["columns"] == "t,wx,wy,wz,ax,ay,az"
    assert d["split"] is False


@pytest.mark.parametrize("name,fmt", [("euroc_imu.bag", "bag"), ("euroc_imu.mcap", "mcap"),
                                      ("euroc_imu.db3", "db3")])
def test_containers_hold_the_first_500_csv_rows(name, fmt):
    d = preint.read_imu(DATA / "ros" / name)
    t, g, a = parse_euroc(EUROC, rows=500)
    assert d["format"] == fmt
    np.testing.assert_array_equal(d["t_ns"], t)
    np.testing.assert_array_equal(d["gyro"], g)
    np.testing.assert_array_equal(d["acc"], a)
    assert any("/imu0" in note for note in d["notes"])
    # Record time = header stamp + 1 ms (tests/data/ros/README.md).
    r = preint.read_imu(DATA / "ros" / name, stamp="record", topic="/imu0")
    np.testing.assert_array_equal(r["t_ns"], t + 1_000_000)


def test_delimited_text_in_seconds_deg_s_and_g_is_converted_to_si():
    path = DATA / "adis16405" / "adis16405_run1_first3600s_10Hz_blockmean.csv"
    d = preint.read_imu(path)
    assert d["units"] == {"time": "s", "gyro": "deg/s", "accel": "g"}
    rows = [line.split(",") for line in path.read_text().splitlines()[1:] if line.strip()]
    t = np.array([int(Decimal(r[0]) * 10**9) for r in rows], dtype=np.int64)
    raw = np.array([[float(x) for x in r[1:7]] for r in rows])
    np.testing.assert_array_equal(d["t_ns"], t)
    np.testing.assert_allclose(d["gyro"], raw[:, 0:3] * (math.pi / 180.0), rtol=2e-16, atol=0)
    np.testing.assert_allclose(d["acc"], raw[:, 3:6] * 9.80665, rtol=2e-16, atol=0)


def test_kitti_columns_are_mapped_from_gtsams_header():
    path = DATA / "kitti" / "KittiEquivBiasedImu_first120s.txt"
    d = preint.read_imu(path)
    raw = np.loadtxt(path, skiprows=1)  # Time dt accelX accelY accelZ omegaX omegaY omegaZ
    assert d["format"] == "kitti" and len(d["t_ns"]) == raw.shape[0]
    np.testing.assert_array_equal(d["acc"], raw[:, 2:5])
    np.testing.assert_array_equal(d["gyro"], raw[:, 5:8])
    # Seconds of day with 9 decimals: integer ns within rounding of the float parse.
    assert np.max(np.abs(d["t_ns"] * 1e-9 - raw[:, 0])) < 1e-8


def test_options_choose_columns_units_and_delimiter(tmp_path):
    p = tmp_path / "imu.txt"
    p.write_text("0.000;1;2;3;10;20;30\n0.005;4;5;6;40;50;60\n0.010;7;8;9;70;80;90\n")
    d = preint.read_imu(p, columns="t,ax,ay,az,wx,wy,wz", delimiter="semicolon",
                        time_unit="s", gyro_unit="deg/s", accel_unit="m/s2", check_units=False)
    np.testing.assert_array_equal(d["t_ns"], [0, 5_000_000, 10_000_000])
    np.testing.assert_array_equal(d["acc"], [[1, 2, 3], [4, 5, 6], [7, 8, 9]])
    np.testing.assert_allclose(d["gyro"][2], np.deg2rad([70, 80, 90]), rtol=1e-15)
    assert d["columns"] == "t,ax,ay,az,wx,wy,wz"


def test_split_container_is_merged_on_the_gyro_stamps():
    d = preint.read_imu(DATA / "ros" / "split.mcap", gyro_topic="/camera/gyro/sample",
                        accel_topic="/camera/accel/sample")
    t, g, a = parse_euroc(EUROC, rows=400)
    assert d["split"] is True and 0.0 < d["accel_white_ratio"] <= 1.0
    k = np.searchsorted(t, d["t_ns"])
    np.testing.assert_array_equal(t[k], d["t_ns"])  # a subset of the gyro stamps
    np.testing.assert_array_equal(d["gyro"], g[k])
    assert len(d["t_ns"]) == 390


def test_groundtruth_matches_an_independent_parse():
    d = preint.read_groundtruth(GT)
    rows = [line.split(",") for line in GT.read_text().splitlines()
            if line.strip() and not line.startswith("#")]
    t = np.array([int(r[0]) for r in rows], dtype=np.int64)
    v = np.array([[float(x) for x in r[1:]] for r in rows])
    np.testing.assert_array_equal(d["t_ns"], t)
    np.testing.assert_array_equal(d["p"], v[:, 0:3])
    q = v[:, 3:7] / np.linalg.norm(v[:, 3:7], axis=1, keepdims=True)  # (w, x, y, z)
    np.testing.assert_allclose(d["q_wxyz"], q, rtol=0, atol=1e-15)
    np.testing.assert_array_equal(d["v"], v[:, 7:10])
    np.testing.assert_array_equal(d["bias_gyro"], v[:, 10:13])
    np.testing.assert_array_equal(d["bias_acc"], v[:, 13:16])


def write_euroc_rows(path: Path, rows: list[str]) -> Path:
    header = "#timestamp [ns],w_x,w_y,w_z,a_x,a_y,a_z\n"
    path.write_text(header + "".join(r + "\n" for r in rows))
    return path


GOOD = ["1000000000,0.01,0.02,0.03,0.1,0.2,9.8", "1005000000,0.01,0.02,0.03,0.1,0.2,9.8"]


def test_malformed_row_raises_input_error_naming_file_and_line(tmp_path):
    p = write_euroc_rows(tmp_path / "bad.csv", GOOD + ["1010000000,0.01,abc,0.03,0.1,0.2,9.8"])
    with pytest.raises(preint.InputError) as e:
        preint.read_imu(p, format="euroc")
    assert f"{p}:4" in str(e.value)
    assert e.value.kind == "Parse"
    assert isinstance(e.value, OSError) and isinstance(e.value, preint.Error)


def test_decreasing_timestamp_names_its_line(tmp_path):
    p = write_euroc_rows(tmp_path / "dec.csv", GOOD + ["1001000000,0.01,0.02,0.03,0.1,0.2,9.8"])
    with pytest.raises(preint.InputError, match=r"dec\.csv:4: timestamp 1001000000 ns decreases"):
        preint.read_imu(p, format="euroc", check_units=False)


def test_missing_file_and_unknown_option_are_typed(tmp_path):
    with pytest.raises(preint.InputError, match="nothere.csv"):
        preint.read_imu(tmp_path / "nothere.csv", format="euroc")
    with pytest.raises(preint.ShapeError, match="gyro_unit"):
        preint.read_imu(EUROC, gyro_unit="furlong/s")
    with pytest.raises(preint.ShapeError):
        preint.read_imu(EUROC, gyro=EUROC)  # path and a split recording at once


def test_groundtruth_bad_quaternion_names_the_line(tmp_path):
    lines = GT.read_text().splitlines()[:3]
    f = lines[2].split(",")
    f[4] = "0.5"  # q_w: norm no longer 1
    p = tmp_path / "gt.csv"
    p.write_text("\n".join(lines[:2] + [",".join(f)]) + "\n")
    with pytest.raises(preint.InputError, match=r"gt\.csv:3: quaternion"):
        preint.read_groundtruth(p)


def test_audit_reports_a_duplicate_and_passes_a_clean_bag(tmp_path):
    rows = [f"{1_000_000_000 + 5_000_000 * k},0.01,0.02,0.03,0.1,0.2,9.8" for k in range(400)]
    rows.insert(200, rows[199])
    p = write_euroc_rows(tmp_path / "dup.csv", rows)
    r = preint.audit(p)
    assert r["clean"] is False
    assert r["duplicates"]["count"] == 1
    assert any(f["kind"] == "duplicates" for f in r["findings"])
    clean = preint.audit(DATA / "ros" / "euroc_imu.bag")
    assert clean["clean"] is True and clean["samples"] == 500


def test_euroc_writer_round_trips_bit_for_bit(tmp_path):
    rng = np.random.default_rng(11)
    n = 1000
    t = 1_403_715_273_262_142_976 + np.cumsum(rng.integers(1, 10_000_000, n)).astype(np.int64)
    g = rng.standard_normal((n, 3)) * 10.0 ** rng.integers(-12, 3, (n, 3))
    a = rng.standard_normal((n, 3)) * 10.0 ** rng.integers(-12, 3, (n, 3))
    p = tmp_path / "out.csv"
    preint.write_euroc_imu(p, t, g, a)
    t2, g2, a2 = parse_euroc(p)  # Python's own parse of the text
    np.testing.assert_array_equal(t2, t)
    np.testing.assert_array_equal(g2, g)
    np.testing.assert_array_equal(a2, a)
    d = preint.read_imu(p, check_units=False)
    np.testing.assert_array_equal(d["gyro"], g)
    np.testing.assert_array_equal(d["acc"], a)


def test_kalibr_yaml_read_and_written():
    path = DATA / "euroc" / "imu.yaml"
    values = {}
    for line in path.read_text().splitlines():
        key, _, rest = line.partition(":")
        if rest and not line.startswith("#"):
            values[key.strip()] = rest.split("#")[0].strip()
    n = preint.read_kalibr_yaml(path)
    assert n.gyro_noise_density == float(values["gyroscope_noise_density"])
    assert n.gyro_random_walk == float(values["gyroscope_random_walk"])
    assert n.acc_noise_density == float(values["accelerometer_noise_density"])
    assert n.acc_random_walk == float(values["accelerometer_random_walk"])
    assert n.update_rate_hz == float(values["update_rate"])


def test_kalibr_yaml_round_trip_and_missing_key(tmp_path):
    n = preint.Noise(1.234567890123e-4, 2e-5, 3.3e-3, 4e-4, 400.0)
    p = tmp_path / "imu.yaml"
    preint.write_kalibr_yaml(p, n)
    m = preint.read_kalibr_yaml(p)
    assert (m.gyro_noise_density, m.gyro_random_walk, m.acc_noise_density, m.acc_random_walk,
            m.update_rate_hz) == (1.234567890123e-4, 2e-5, 3.3e-3, 4e-4, 400.0)
    p.write_text("gyroscope_noise_density: 1e-4\n")
    with pytest.raises(preint.InputError, match="imu.yaml: missing key") as e:
        preint.read_kalibr_yaml(p)
    assert e.value.kind == "MissingKey"


@pytest.mark.parametrize(
    "call",
    [
        lambda p, **kw: preint.read_imu(p, **kw),
        lambda p, **kw: preint.audit(p, **kw),
        lambda p, **kw: preint.allan_variance_file(p, **kw),
    ],
)
def test_reader_options_are_checked_by_name_and_type(call):
    path = str(EUROC)
    with pytest.raises(preint.ShapeError) as e:
        call(path, time_units="s")  # a misspelt option is refused, not ignored
    assert e.value.kind == "Usage" and "time_units" in str(e.value) and "time_unit" in str(e.value)
    with pytest.raises(preint.ShapeError) as e:
        call(path, format=3)
    assert e.value.kind == "Usage" and "format" in str(e.value)
    with pytest.raises(preint.ShapeError) as e:
        call(path, check_units="yes")
    assert "check_units" in str(e.value)


def test_audit_names_an_inverted_gyro_axis(preint_cli, tmp_path):
    """``audit`` checks the gyro's axes against the accelerometer's on a recording that turns
    gravity about x and y (``multi-pose-static``, simulated by the command line): they agree
    as simulated; with the gyro's y readings negated, ``units.gyro_axes`` names the axis and
    the audit has a defect."""
    import subprocess

    subprocess.run([*preint_cli, "simulate", "--scene", "multi-pose-static", "--duration",
                    "33", "--out", str(tmp_path)], check=True, capture_output=True)
    ok = preint.audit(tmp_path / "imu.csv")
    assert ok["units"]["gyro_axes"]["verdict"] == "agree"
    d = preint.read_imu(tmp_path / "imu.csv")
    gyro = d["gyro"].copy()
    gyro[:, 1] *= -1.0
    flipped = tmp_path / "flipped.csv"
    preint.write_euroc_imu(flipped, d["t_ns"], gyro, d["acc"])
    r = preint.audit(flipped)
    axes = r["units"]["gyro_axes"]
    assert axes["verdict"] == "mismatch" and "gyro y looks inverted" in axes["text"]
    assert any(f["kind"] == "gyro axes" and f["severity"] == "defect" for f in r["findings"])
