"""Speed of the Python package against the Rust library in the same run, and against GTSAM's
own Python wheel, on the same samples (run by hand; the numbers go to docs/PERFORMANCE.md).

    pip install ./python gtsam==4.3.0        # the package in release mode, as pip builds it
    python python/bench/bench.py [--rounds 7] [--json]

Cases (EuRoC noise densities, zero bias, a smooth synthetic 200 Hz stream: the formula of
``preint_sim::synthetic_stream``):

1. 10⁶ samples, midpoint with the 9×9 covariance and bias Jacobians (level "covariance"), in one
   call: ``preint.preintegrate`` (and ``Preintegrator.integrate_arrays`` + ``finish``) against
   Rust's ``preint::preintegrate`` (and ``Preintegrator::integrate_slice`` + ``finish``).
2. 1 000 windows of 200 samples from one ``preint.preintegrate_windows`` call against Rust's
   ``preint::preintegrate`` per window.
3. GTSAM 4.3.0's ``PreintegratedImuMeasurements`` (the wheel's default, tangent) and
   ``PreintegratedImuMeasurementsManifold`` fed by a per-sample Python loop of
   ``integrateMeasurement`` (the wheel has no batch call) against preint ``euler`` (the same
   discretisation as the Manifold class) and ``midpoint`` from one Python call.

The Rust side is ``python/bench/rust`` (built here with ``cargo build --release``, the Python
extension's release profile), reading the same samples from a binary file. Each round times
Python and then Rust (interleaved, so load on the machine affects both alike); the medians over
the rounds are reported in ns per sample.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any, Callable

import numpy as np
import numpy.typing as npt

import preint

REPO = Path(__file__).resolve().parents[2]
CRATE = REPO / "python" / "bench" / "rust"


def synthetic_stream(n: int) -> tuple[npt.NDArray[np.int64], npt.NDArray[np.float64], npt.NDArray[np.float64]]:
    """N samples at 200 Hz: ``preint_sim::synthetic_stream``'s sinusoidal rates [rad/s] and
    specific force [m/s²]."""
    k = np.arange(n)
    t = k * 0.005
    gyro = np.stack([0.3 * np.sin(1.1 * t), 0.2 * np.cos(0.7 * t), 0.5 * np.sin(0.3 * t) + 0.1], axis=1)
    acc = np.stack([0.5 * np.sin(0.9 * t), 0.3 * np.cos(1.3 * t), 9.81 + 0.2 * np.sin(0.5 * t)], axis=1)
    return (k * 5_000_000).astype(np.int64), gyro, acc


def write_samples(path: Path, t: np.ndarray, g: np.ndarray, a: np.ndarray) -> None:
    """N, t_ns, gyro, acc as little-endian words (the Rust side's input)."""
    with open(path, "wb") as f:
        f.write(np.array([len(t)], dtype="<u8").tobytes())
        f.write(t.astype("<i8").tobytes())
        f.write(np.ascontiguousarray(g, dtype="<f8").tobytes())
        f.write(np.ascontiguousarray(a, dtype="<f8").tobytes())


def build_rust() -> Path:
    target = Path(os.environ.get("CARGO_TARGET_DIR", REPO / "target")).resolve() / "python-bench"
    subprocess.run(["cargo", "build", "-q", "--release", "--manifest-path", str(CRATE / "Cargo.toml")], check=True,
                   env={**os.environ, "CARGO_TARGET_DIR": str(target)})
    return target / "release" / "preint-python-bench-ref"


def rust(binary: Path, samples: Path, scheme: str, runs: int, window: int | None = None) -> dict[str, Any]:
    args = [str(binary), str(samples), scheme, "covariance", str(runs)] + ([str(window)] if window else [])
    out = subprocess.run(args, check=True, capture_output=True, text=True)
    return dict(json.loads(out.stdout))


def timed(f: Callable[[], object], n: int) -> float:
    """ns per sample of one call of f over n samples."""
    t0 = time.perf_counter()
    f()
    return (time.perf_counter() - t0) * 1e9 / n


def median(xs: list[float]) -> float:
    return float(np.median(xs))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--rounds", type=int, default=7)
    ap.add_argument("--samples", type=int, default=1_000_000)
    ap.add_argument("--gtsam-samples", type=int, default=100_000)
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()

    binary = build_rust()
    t, g, a = synthetic_stream(args.samples)
    tw, gw, aw = synthetic_stream(1000 * 200 + 1)
    keys = tw[::200]
    mid = preint.Params(preint.Noise.euroc(), scheme="midpoint", level="covariance")
    eul = preint.Params(preint.Noise.euroc(), scheme="euler", level="covariance")
    n, nw = len(t), len(tw) - 1

    def arrays(p: preint.Params) -> None:
        pi = preint.Preintegrator(p)
        pi.integrate_arrays(t, g, a)
        pi.finish()

    res: dict[str, list[float]] = {k: [] for k in (
        "py_one_call", "rust_one_call", "py_arrays", "rust_slice", "py_windows", "rust_windows",
        "py_euler_one_call", "rust_euler_one_call")}
    with tempfile.TemporaryDirectory() as d:
        big, small = Path(d) / "stream.bin", Path(d) / "windows.bin"
        write_samples(big, t, g, a)
        write_samples(small, tw, gw, aw)
        preint.preintegrate(mid, t, g, a, int(t[0]), int(t[-1]))  # warm-up
        for _ in range(args.rounds):
            res["py_one_call"].append(timed(lambda: preint.preintegrate(mid, t, g, a, int(t[0]), int(t[-1])), n))
            res["py_arrays"].append(timed(lambda: arrays(mid), n))
            res["py_windows"].append(timed(lambda: preint.preintegrate_windows(mid, tw, gw, aw, keys), nw))
            res["py_euler_one_call"].append(timed(lambda: preint.preintegrate(eul, t, g, a, int(t[0]), int(t[-1])), n))
            r = rust(binary, big, "midpoint", 1)
            res["rust_one_call"].append(r["one_call"])
            res["rust_slice"].append(r["integrate_slice"])
            res["rust_windows"].append(rust(binary, small, "midpoint", 1, 200)["windows"])
            res["rust_euler_one_call"].append(rust(binary, big, "euler", 1)["one_call"])
    med = {k: median(v) for k, v in res.items()}

    gt: dict[str, float] = {}
    try:
        import gtsam

        m = args.gtsam_samples
        dts = np.diff(t[: m + 1]) * 1e-9
        gp = gtsam.PreintegrationParams.MakeSharedU(9.81)
        gp.setGyroscopeCovariance(1.6968e-4**2 * np.eye(3))
        gp.setAccelerometerCovariance(2.0e-3**2 * np.eye(3))
        gp.setIntegrationCovariance(np.zeros((3, 3)))
        for name, cls in (("gtsam_tangent", gtsam.PreintegratedImuMeasurements),
                          ("gtsam_manifold", gtsam.PreintegratedImuMeasurementsManifold)):
            runs = []
            for _ in range(3):
                pim = cls(gp, gtsam.imuBias.ConstantBias())
                t0 = time.perf_counter()
                for k in range(m):
                    pim.integrateMeasurement(a[k], g[k], dts[k])
                runs.append((time.perf_counter() - t0) * 1e9 / m)
            gt[name] = median(runs)
    except ImportError:
        pass

    report = {
        "samples": n,
        "rounds": args.rounds,
        "ns_per_sample": med | gt,
        "ratios": {
            "one_call_python_over_rust": med["py_one_call"] / med["rust_one_call"],
            "arrays_python_over_rust_slice": med["py_arrays"] / med["rust_slice"],
            "windows_python_over_rust": med["py_windows"] / med["rust_windows"],
            "euler_one_call_python_over_rust": med["py_euler_one_call"] / med["rust_euler_one_call"],
        } | ({
            "gtsam_tangent_over_preint_midpoint": gt["gtsam_tangent"] / med["py_one_call"],
            "gtsam_manifold_over_preint_euler": gt["gtsam_manifold"] / med["py_euler_one_call"],
        } if gt else {}),
    }
    if args.json:
        print(json.dumps(report, indent=1))
        return
    print(f"ns per sample, median of {args.rounds} interleaved rounds (this machine):")
    rows = [
        (f"{n:,} samples, midpoint + covariance, one call", "py_one_call", "rust_one_call"),
        ("  ... Preintegrator.integrate_arrays / integrate_slice", "py_arrays", "rust_slice"),
        ("  ... euler", "py_euler_one_call", "rust_euler_one_call"),
        ("1 000 windows × 200 samples, one call", "py_windows", "rust_windows"),
    ]
    print(f"{'case':<56} {'Python':>8} {'Rust':>8} {'ratio':>6}")
    for label, py_key, rust_key in rows:
        print(f"{label:<56} {med[py_key]:>8.1f} {med[rust_key]:>8.1f} {med[py_key] / med[rust_key]:>6.3f}")
    for name, ours, label in (("gtsam_tangent", "py_one_call", "midpoint"), ("gtsam_manifold", "py_euler_one_call", "euler")):
        if name in gt:
            print(f"GTSAM {name[6:]:<8} per-sample Python loop: {gt[name]:8.1f} ns/sample = "
                  f"{gt[name] / med[ours]:.1f}× preint {label} from Python")
    if not gt:
        print("gtsam not installed: GTSAM rows left out", file=sys.stderr)


if __name__ == "__main__":
    main()
