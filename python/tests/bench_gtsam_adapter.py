"""Cost of preint.gtsam's factors against gtsam's own ImuFactor (not collected by pytest).

    cd python/tests && ../../target/python-venv/bin/python bench_gtsam_adapter.py

Prints the median µs of one ``linearize`` per factor (over ≥1000 calls) for our adapter
(ImuFactor, CombinedImuFactor) and gtsam.ImuFactor / CombinedImuFactor, and the median ms of one
Levenberg–Marquardt iteration on test_gtsam_adapter's 10-keyframe graph with either factor.
"""

from __future__ import annotations

import time

import numpy as np

import gtsam
import test_gtsam_adapter as T


def median_us(fn, n=2000):
    for _ in range(50):
        fn()
    ts = []
    for _ in range(n):
        t0 = time.perf_counter_ns()
        fn()
        ts.append(time.perf_counter_ns() - t0)
    return float(np.median(ts)) / 1e3


def main() -> None:
    t_ns, gyro, acc = T.stream()
    pim = T.our_pim(t_ns, gyro, acc)
    xi = T.preint.NavState.identity()
    xj = T.preint.predict(pim, xi).retract(np.full(9, 0.01))
    vals = T.values_of([xi, xj], [pim.bias_hat, pim.bias_hat])
    hat = gtsam.imuBias.ConstantBias(T.BA_HAT, T.BG_HAT)
    ours = T.adapters(pim, "logmap")
    pg = T.gtsam_tangent_pim(t_ns, gyro, acc, T.gtsam_params("Logmap", False), hat)
    pc = T.gtsam_tangent_pim(t_ns, gyro, acc, T.gtsam_params("Logmap", True), hat, True)
    theirs = {
        "imu": gtsam.ImuFactor(T.X(0), T.V(0), T.X(1), T.V(1), T.B(0), pg),
        "combined": gtsam.CombinedImuFactor(T.X(0), T.V(0), T.X(1), T.V(1), T.B(0), T.B(1), pc),
    }
    for kind in ("imu", "combined"):
        a = median_us(lambda: ours[kind].linearize(vals))
        b = median_us(lambda: theirs[kind].linearize(vals))
        print(f"linearize {kind:8s}: preint.gtsam {a:7.1f} µs   gtsam {b:7.1f} µs   ratio {a / b:5.1f}")

    (g_ours, g_theirs, _), truth = T.graph_triple()
    init = T.initial_values(truth)
    for name, g in (("preint.gtsam", g_ours), ("gtsam.ImuFactor", g_theirs)):
        ts = []
        for _ in range(30):
            opt = gtsam.LevenbergMarquardtOptimizer(g, init, gtsam.LevenbergMarquardtParams())
            t0 = time.perf_counter_ns()
            opt.iterate()
            ts.append(time.perf_counter_ns() - t0)
        print(f"one LM iteration, 10 keyframes (9 IMU factors), {name:16s}: {np.median(ts) / 1e6:6.3f} ms")


if __name__ == "__main__":
    main()
