"""A visual-inertial-style smoother on EuRoC V1_01 with preint's IMU factor inside GTSAM.

Keyframes at 10 Hz; between consecutive keyframes an IMU factor; at each keyframe a pose
measurement from the ground truth with added noise (2 cm, 0.5°: a visual odometry front end) and
a 3 s dropout without poses; biases estimated as a random walk (a BetweenFactor per keyframe).
Solved in batch (Levenberg–Marquardt) and with a fixed-lag smoother (IncrementalFixedLagSmoother,
2 s lag), with preint's factor (`preint.gtsam.ImuFactor`) and, beside it, GTSAM's own
`gtsam.ImuFactor` on its own preintegration of the same samples; then both at an IMU decimated
to 25 Hz (block means of 8 samples), where preint's `hermite4` is compared with GTSAM's. Prints the RMS rotation,
position and velocity errors against the ground truth and the mean estimated biases.

    python examples/python/smoother_euroc.py [--seconds S]
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import gtsam
import numpy as np

import preint
import preint.gtsam as pg

ROOT = Path(__file__).resolve().parents[2]
IMU = ROOT / "tests/data/euroc/V1_01_easy_imu0.csv"
GT = ROOT / "tests/data/euroc/V1_01_easy_groundtruth_vicon2gt.csv"
NOISE = ROOT / "tests/data/euroc/imu.yaml"
POSE_SIGMA = (np.radians(0.5), 0.02)  # [rad, m]
DROPOUT_S = (20.0, 23.0)  # seconds after the first keyframe without pose measurements
X, V, B = (lambda k: gtsam.symbol("x", k)), (lambda k: gtsam.symbol("v", k)), (lambda k: gtsam.symbol("b", k))


def pose3(q_wxyz, p):
    return gtsam.Pose3(gtsam.Rot3.Quaternion(*q_wxyz), np.asarray(p))


def keyframes(gt, imu, seconds):
    """Every other ground-truth row (10 Hz) over the first `seconds` from 0.1 s into the IMU's
    span (inside the decimated stream too)."""
    t0 = imu["t_ns"][0] + 100_000_000
    idx = [k for k in range(0, len(gt["t_ns"]), 2) if 0 <= gt["t_ns"][k] - t0 <= seconds * 1e9]
    return np.array(idx)


def measurements(imu, kf_t, scheme, rate_div):
    """preint's measurements and GTSAM's over each keyframe interval, the IMU reduced to one
    sample per `rate_div` by block means (as an IMU's own averaging filter does), stamped at the
    block's middle."""
    n = len(imu["t_ns"]) // rate_div * rate_div
    block = lambda x: x[:n].reshape(-1, rate_div, *x.shape[1:]).mean(axis=1)
    t = imu["t_ns"][:n].reshape(-1, rate_div)
    t = (t[:, 0] + (t[:, -1] - t[:, 0]) // 2).astype(np.int64)
    g, a = block(imu["gyro"]), block(imu["acc"])
    noise = preint.read_kalibr_yaml(NOISE)
    p = preint.Params(noise, scheme=scheme, level="covariance")
    p.max_gap_ns = 200_000_000
    ours = preint.preintegrate_windows(p, t, g, a, kf_t)
    gp = pg.params_to_gtsam(p, combined=False)
    theirs = []
    for t_i, t_j in zip(kf_t[:-1], kf_t[1:]):
        m = gtsam.PreintegratedImuMeasurements(gp, gtsam.imuBias.ConstantBias())
        k = np.searchsorted(t, t_i, side="right") - 1
        while t[k] < t_j:
            k1 = min(k + 1, len(t) - 1)
            lo, hi = max(t[k], t_i), min(t[k1], t_j)
            if hi > lo:
                m.integrateMeasurement(a[k], g[k], (hi - lo) * 1e-9)
            k += 1
        theirs.append(m)
    return ours, theirs


def graph(gt, kf, pims, own, rng):
    """The factor graph: priors on the first state, IMU factors, bias random walk, noisy poses."""
    g = gtsam.NonlinearFactorGraph()
    values = gtsam.Values()
    t0 = gt["t_ns"][kf[0]]
    pose_noise = gtsam.noiseModel.Diagonal.Sigmas(np.r_[[POSE_SIGMA[0]] * 3, [POSE_SIGMA[1]] * 3])
    for k, row in enumerate(kf):
        truth = pose3(gt["q_wxyz"][row], gt["p"][row])
        noisy = truth.retract(np.r_[rng.normal(0, POSE_SIGMA[0], 3), rng.normal(0, POSE_SIGMA[1], 3)])
        t_s = (gt["t_ns"][row] - t0) * 1e-9
        if k == 0 or not DROPOUT_S[0] <= t_s <= DROPOUT_S[1]:
            g.add(gtsam.PriorFactorPose3(X(k), noisy, pose_noise))
        values.insert(X(k), noisy)
        values.insert(V(k), np.zeros(3) if k else gt["v"][row])
        values.insert(B(k), gtsam.imuBias.ConstantBias())
    g.add(gtsam.PriorFactorVector(V(0), gt["v"][kf[0]], gtsam.noiseModel.Isotropic.Sigma(3, 0.05)))
    g.add(gtsam.PriorFactorConstantBias(B(0), gtsam.imuBias.ConstantBias(),
                                        gtsam.noiseModel.Diagonal.Sigmas(np.r_[[0.1] * 3, [0.01] * 3])))
    dt = 0.1
    walk = gtsam.noiseModel.Diagonal.Sigmas(np.r_[[3e-3 * np.sqrt(dt)] * 3, [1.94e-5 * np.sqrt(dt)] * 3])
    for k in range(len(kf) - 1):
        if own:
            g.add(gtsam.ImuFactor(X(k), V(k), X(k + 1), V(k + 1), B(k), pims[k]))
        else:
            g.add(pg.ImuFactor(X(k), V(k), X(k + 1), V(k + 1), B(k), pims[k]))
        g.add(gtsam.BetweenFactorConstantBias(B(k), B(k + 1), gtsam.imuBias.ConstantBias(), walk))
    return g, values


def errors(gt, kf, values):
    """RMS rotation [deg], position [m], velocity [m/s] errors; mean gyro and accelerometer bias."""
    rot, pos, vel, bg, ba = [], [], [], [], []
    for k, row in enumerate(kf):
        truth = pose3(gt["q_wxyz"][row], gt["p"][row])
        x = values.atPose3(X(k))
        rot.append(np.degrees(np.linalg.norm(gtsam.Rot3.Logmap(truth.rotation().between(x.rotation())))))
        pos.append(np.linalg.norm(x.translation() - gt["p"][row]))
        vel.append(np.linalg.norm(values.atVector(V(k)) - gt["v"][row]))
        b = values.atConstantBias(B(k))
        bg.append(b.gyroscope())
        ba.append(b.accelerometer())
    rms = lambda e: float(np.sqrt(np.mean(np.square(e))))
    return rms(rot), rms(pos), rms(vel), np.mean(bg, axis=0), np.mean(ba, axis=0)


def batch(g, values):
    p = gtsam.LevenbergMarquardtParams()
    p.setMaxIterations(50)
    return gtsam.LevenbergMarquardtOptimizer(g, values, p).optimize()


def fixed_lag(g, values, gt, kf, lag_s=2.0):
    """Feeds the graph keyframe by keyframe into an IncrementalFixedLagSmoother (lag `lag_s`);
    each state's estimate is its last one before it leaves the window (a causal-with-lag
    estimate, as a fixed-lag VIO back end reports)."""
    smoother = gtsam.IncrementalFixedLagSmoother(lag_s)
    t0 = gt["t_ns"][kf[0]]
    factors_of: dict[int, list] = {}
    for i in range(g.size()):
        f = g.at(i)
        factors_of.setdefault(max(gtsam.Symbol(key).index() for key in f.keys()), []).append(f)
    last: dict[int, tuple] = {}
    for k in range(len(kf)):
        new_f = gtsam.NonlinearFactorGraph()
        for f in factors_of.get(k, []):
            new_f.add(f)
        new_v = gtsam.Values()
        if k == 0:
            pose, vel, bias = values.atPose3(X(0)), values.atVector(V(0)), values.atConstantBias(B(0))
        else:
            pose, vel, bias = values.atPose3(X(k)), last[k - 1][1], last[k - 1][2]
        new_v.insert(X(k), pose)
        new_v.insert(V(k), vel)
        new_v.insert(B(k), bias)
        stamps = gtsam.FixedLagSmootherKeyTimestampMap()
        t_s = (gt["t_ns"][kf[k]] - t0) * 1e-9
        for key in (X(k), V(k), B(k)):
            stamps.insert((key, t_s))
        smoother.update(new_f, new_v, stamps)
        est = smoother.calculateEstimate()
        for j in range(max(0, k - int(lag_s * 10) - 2), k + 1):
            if est.exists(X(j)):
                last[j] = (est.atPose3(X(j)), est.atVector(V(j)), est.atConstantBias(B(j)))
    out = gtsam.Values()
    for j, (pose, vel, bias) in last.items():
        out.insert(X(j), pose)
        out.insert(V(j), vel)
        out.insert(B(j), bias)
    return out


def row(name, gt, kf, values, seconds):
    r, p, v, bg, ba = errors(gt, kf, values)
    print(f"{name:<44} {r:7.3f} {p:8.4f} {v:8.4f}   [{bg[0]:+.4f} {bg[1]:+.4f} {bg[2]:+.4f}] "
          f"[{ba[0]:+.3f} {ba[1]:+.3f} {ba[2]:+.3f}]   {seconds:5.2f}")
    return r, p, v


def main(seconds=150.0, seed=3):
    imu = preint.read_imu(IMU)
    gt = preint.read_groundtruth(GT)
    kf = keyframes(gt, imu, seconds)
    kf_t = gt["t_ns"][kf]
    print(f"EuRoC V1_01, {len(kf)} keyframes at 10 Hz over {seconds:.0f} s, poses ±{POSE_SIGMA[1] * 100:.0f} cm "
          f"± {np.degrees(POSE_SIGMA[0]):.1f}°, none over {DROPOUT_S[0]:.0f}–{DROPOUT_S[1]:.0f} s")
    print(f"{'':<44} {'rot °':>7} {'pos m':>8} {'vel m/s':>8}   mean b_g [rad/s]            mean b_a [m/s²]          time s")
    print(f"{'ground truth mean bias':<44} {'':>7} {'':>8} {'':>8}   "
          f"[{' '.join(f'{x:+.4f}' for x in gt['bias_gyro'][kf].mean(0))}] "
          f"[{' '.join(f'{x:+.3f}' for x in gt['bias_acc'][kf].mean(0))}]")
    results = {}
    for label, scheme, div in [("200 Hz", "midpoint", 1), ("25 Hz", "hermite4", 8)]:
        ours, theirs = measurements(imu, kf_t, scheme, div)
        for own, pims, name in [(False, ours, f"preint {scheme}"), (True, theirs, "GTSAM ImuFactor")]:
            g, values = graph(gt, kf, pims, own, np.random.default_rng(seed))
            t = time.perf_counter()
            est = batch(g, values)
            results[(label, name, "batch")] = row(f"{label} {name}, batch", gt, kf, est, time.perf_counter() - t)
            if label == "200 Hz":
                t = time.perf_counter()
                est = fixed_lag(g, values, gt, kf)
                results[(label, name, "lag")] = row(f"{label} {name}, fixed lag 2 s", gt, kf, est,
                                                    time.perf_counter() - t)
    return results


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=150.0)
    main(ap.parse_args().seconds)
