"""The Python package gives the Rust command line's numbers to the bit on the same input.

The Rust side is ``preint integrate --json`` (``$PREINT_CLI``, set by ``tools/test`` to the binary
``cargo test --workspace`` built; else ``cargo run -p preint-cli``). Its JSON numbers are
written by serde_json as the shortest decimal that reads back as the same double, and Python's
``json`` reads decimals correctly rounded, so every number crosses exactly; the CSV is read here
with correctly rounded parsing as the Rust reader does (``conftest.read_euroc_imu``). Every
array is then compared as raw bytes.
"""

from __future__ import annotations

import json
import subprocess

import numpy as np
import pytest

import preint

from conftest import EUROC, GTSAM_FIXTURES, REPO, read_euroc_imu

IMU = EUROC / "V1_01_easy_imu0.csv"


def cli_json(cmd: list[str], *args: str) -> dict:
    out = subprocess.run([*cmd, "integrate", *args, "--json"], cwd=REPO, capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, f"preint integrate {' '.join(args)} failed:\n{out.stderr}"
    return json.loads(out.stdout)


def as_bytes(x) -> bytes:
    return np.asarray(x, dtype=np.float64).tobytes()


def assert_identical(m: preint.PreintegratedImu, r: dict, what: str) -> None:
    assert (m.t_i_ns, m.t_j_ns) == (r["t_i_ns"], r["t_j_ns"]), what
    pairs = {
        "delta_t": (m.delta_t, r["delta_t"]),
        "delta_R": (m.delta_R, r["delta_R"]),
        "delta_R_log": (m.delta_rotvec, r["delta_R_log"]),
        "delta_v": (m.delta_v, r["delta_v"]),
        "delta_p": (m.delta_p, r["delta_p"]),
        "covariance": (m.cov, r["covariance"]),
        "covariance15": (m.cov15, r["covariance15"]),
        "residual_covariance15": (m.residual_cov15(), r["residual_covariance15"]),
        "gravity": (m.gravity, r["gravity"]),
        "bias_hat": (m.bias_hat.vector(), r["bias_hat"]["gyro"] + r["bias_hat"]["acc"]),
    }
    j, rj = m.bias_jacobians, r["jacobians"]
    for name, block in (("dR_dbg", j[0:3, 0:3]), ("dv_dbg", j[3:6, 0:3]), ("dv_dba", j[3:6, 3:6]),
                        ("dp_dbg", j[6:9, 0:3]), ("dp_dba", j[6:9, 3:6])):
        pairs[name] = (block, rj[name])
    for name, (ours, rust) in pairs.items():
        o, t = np.asarray(ours, dtype=np.float64), np.asarray(rust, dtype=np.float64)
        assert o.shape == t.shape, f"{what}: {name} shape"
        assert as_bytes(o) == as_bytes(t), f"{what}: {name} differs, max {np.abs(o - t).max():e}"
    # ΔR's bias Jacobian w.r.t. b_a is identically zero (not printed by the command line).
    assert not j[0:3, 3:6].any()


@pytest.fixture(scope="module")
def euroc(euroc_imu):
    return euroc_imu


@pytest.mark.parametrize("scheme", ["euler", "midpoint", "hermite4"])
def test_window_between_samples_is_bit_identical(preint_cli, euroc, scheme):
    t, g, a = euroc
    ti, tj = 1_403_715_280_000_000_000, 1_403_715_281_000_000_000  # keyframes between samples
    assert not np.isin([ti, tj], t).any()
    bg, ba = [-0.00224703, 0.0215352, 0.0770299], [-0.0180115, 0.0659796, 0.0309774]
    r = cli_json(preint_cli, "--imu", str(IMU), "--from", str(ti), "--to", str(tj), "--scheme", scheme,
                 f"--bias-gyro={','.join(map(repr, bg))}", f"--bias-acc={','.join(map(repr, ba))}")
    assert r["scheme"] == scheme and r["samples"] == 200
    p = preint.Params(preint.Noise.euroc(), scheme=scheme, level="combined")
    m = preint.preintegrate(p, t, g, a, ti, tj, bias=preint.ImuBias(bg, ba))
    assert_identical(m, r, f"euroc {scheme}")
    # The JSON carries full precision (a value printed to 6 digits would not be bit-equal).
    digits = [len(repr(x).split("e")[0].replace("-", "").replace(".", "").lstrip("0")) for x in np.ravel(r["covariance"])]
    assert max(digits) >= 16


def test_noise_file_and_keyframes_on_samples_are_bit_identical(preint_cli, euroc):
    t, g, a = euroc
    ti, tj = int(t[1000]), int(t[1600])
    r = cli_json(preint_cli, "--imu", str(IMU), "--from", str(ti), "--to", str(tj), "--scheme", "midpoint",
                 "--noise", str(EUROC / "imu.yaml"), "--gravity", "9.80665")
    # The densities of tests/data/euroc/imu.yaml, as written there.
    noise = preint.Noise(1.6968e-04, 1.9393e-05, 2.0000e-03, 3.0000e-03, 200.0)
    assert [r["noise"][k] for k in ("gyroscope_noise_density", "gyroscope_random_walk",
                                    "accelerometer_noise_density", "accelerometer_random_walk")] == [
        noise.gyro_noise_density, noise.gyro_random_walk, noise.acc_noise_density, noise.acc_random_walk]
    p = preint.Params(noise, scheme="midpoint")
    p.gravity = [0.0, 0.0, -9.80665]
    assert_identical(preint.preintegrate(p, t, g, a, ti, tj), r, "euroc imu.yaml")


def test_whole_recording_streamed_by_rust_equals_integrate_arrays(preint_cli, euroc):
    # Without --from/--to the command line streams the whole file through a Preintegrator in
    # chunks of 4096 samples; Python feeds the same samples in one integrate_arrays call.
    t, g, a = euroc
    r = cli_json(preint_cli, "--imu", str(IMU), "--scheme", "euler")
    assert r["samples"] == len(t) == 29120
    pi = preint.Preintegrator(preint.Params(scheme="euler"))
    pi.integrate_arrays(t, g, a)
    assert_identical(pi.finish(), r, "euroc whole recording")


def test_fast_spin_fixture_is_bit_identical(preint_cli):
    csv = GTSAM_FIXTURES / "fastspin.csv"  # 400 Hz, ~10 rad/s
    t, g, a = read_euroc_imu(csv)
    ti, tj = int(t[7]) + 1_111_111, int(t[390]) - 333
    r = cli_json(preint_cli, "--imu", str(csv), "--from", str(ti), "--to", str(tj), "--scheme", "hermite4",
                 "--no-unit-check")
    assert_identical(preint.preintegrate(preint.Params(scheme="hermite4"), t, g, a, ti, tj), r, "fastspin")
