#!/usr/bin/env python3
"""Writes a long synthetic static IMU recording as a ROS 1 bag, a ROS 2 MCAP file and a ROS 2
.db3 file, for the container benchmark in docs/PERFORMANCE.md (outputs are not committed).

    python3 tests/data/ros/bench_long.py OUT_DIR [HOURS] [RATE_HZ]

Writes OUT_DIR/long.bag, OUT_DIR/long.mcap and OUT_DIR/long.db3: topic /imu, sensor_msgs/Imu,
RATE_HZ (default 200) for HOURS (default 3); gyro white noise 1e-3 rad/s per axis around zero, accelerometer
(0, 0, 9.81) m/s² plus 2e-2 m/s² white noise (seed 17). Payloads are packed here in the fixed
ROS 1 / CDR layouts of sensor_msgs/Imu; the containers are written by `rosbags`.
"""

import shutil
import struct
import sys
import tempfile
from pathlib import Path

import numpy as np
from rosbags.rosbag1 import Writer as Writer1
from rosbags.rosbag2 import StoragePlugin, Writer as Writer2
from rosbags.typesys import Stores, get_typestore

FRAME = b"imu"
T0_NS = 1_700_000_000_000_000_000
COV = (-1.0,) + (0.0,) * 8 + (0.0,) * 9


def samples(hours, rate):
    n = int(hours * 3600 * rate)
    rng = np.random.default_rng(17)
    step = 1_000_000_000 // rate
    for start in range(0, n, 100_000):
        m = min(100_000, n - start)
        g = rng.normal(0.0, 1e-3, (m, 3))
        a = rng.normal(0.0, 2e-2, (m, 3)) + (0.0, 0.0, 9.81)
        for i in range(m):
            yield start + i, T0_NS + (start + i) * step, g[i], a[i]


def ros1(seq, t, g, a):
    head = struct.pack("<IIII", seq, t // 10**9, t % 10**9, len(FRAME)) + FRAME
    return head + struct.pack("<37d", 0, 0, 0, 1, *COV[:9], *g, *([0.0] * 9), *a, *([0.0] * 9))


def cdr(t, g, a):
    body = struct.pack("<iII", t // 10**9, t % 10**9, len(FRAME) + 1) + FRAME + b"\0"
    body += b"\0" * (-len(body) % 8)
    body += struct.pack("<37d", 0, 0, 0, 1, *COV[:9], *g, *([0.0] * 9), *a, *([0.0] * 9))
    return b"\0\x01\0\0" + body


def main():
    out = Path(sys.argv[1])
    hours = float(sys.argv[2]) if len(sys.argv) > 2 else 3.0
    rate = int(sys.argv[3]) if len(sys.argv) > 3 else 200
    out.mkdir(parents=True, exist_ok=True)
    bag = out / "long.bag"
    bag.unlink(missing_ok=True)
    with Writer1(bag) as w:
        c = w.add_connection("/imu", "sensor_msgs/msg/Imu", typestore=get_typestore(Stores.ROS1_NOETIC))
        for seq, t, g, a in samples(hours, rate):
            w.write(c, t, ros1(seq, t, g, a))
    for storage, ext in ((StoragePlugin.MCAP, ".mcap"), (StoragePlugin.SQLITE3, ".db3")):
        with tempfile.TemporaryDirectory(dir=out) as tmp:
            d = Path(tmp) / "bag"
            with Writer2(d, version=9, storage_plugin=storage) as w:
                ts = get_typestore(Stores.ROS2_HUMBLE)
                c = w.add_connection("/imu", "sensor_msgs/msg/Imu", typestore=ts)
                for _, t, g, a in samples(hours, rate):
                    w.write(c, t, cdr(t, g, a))
            shutil.move(next(d.glob("*" + ext)), out / ("long" + ext))
    for p in (bag, out / "long.mcap", out / "long.db3"):
        print(f"{p}: {p.stat().st_size / 1e6:.1f} MB")


if __name__ == "__main__":
    main()
