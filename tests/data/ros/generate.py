#!/usr/bin/env python3
"""Writes the ROS fixtures of tests/data/ros from tests/data/euroc/V1_01_easy_imu0.csv.

Needs the pure-Python `rosbags` package (pip install rosbags; written with 0.11.9).
Run from anywhere: python3 tests/data/ros/generate.py

Outputs (see README.md next to this script):
- euroc_imu.bag   ROS 1, topic /imu0, sensor_msgs/Imu, the first ROWS rows of the CSV.
- euroc_imu.mcap  ROS 2 (CDR in MCAP), the same messages.
- euroc_imu.db3   ROS 2 (CDR in rosbag2's SQLite storage), the same messages.
- split.bag, split.mcap, split.db3  a RealSense-like split recording of the first SPLIT_ROWS rows:
  /camera/gyro/sample (200 Hz, angular_velocity of every row, linear_acceleration zero),
  /camera/accel/sample (63 Hz, linear_acceleration interpolated linearly between the two
  CSV rows around t0 + round(k * 1e9 / 63) ns, angular_velocity zero) and /status
  (std_msgs/String, 1 Hz). split.bag uses bz2-compressed chunks.

Header stamps are the CSV's integer-nanosecond timestamps; the record (log) time of every
message is its header stamp + RECORD_OFFSET_NS.
"""

import csv
import shutil
import tempfile
from pathlib import Path

import numpy as np

from rosbags.rosbag1 import Writer as Writer1
from rosbags.rosbag2 import StoragePlugin, Writer as Writer2
from rosbags.typesys import Stores, get_typestore

HERE = Path(__file__).resolve().parent
CSV = HERE.parent / "euroc" / "V1_01_easy_imu0.csv"
ROWS = 500  # 2.5 s at 200 Hz
SPLIT_ROWS = 400  # 2.0 s
ACCEL_HZ = 63
RECORD_OFFSET_NS = 1_000_000  # record time = header stamp + 1 ms
IMU = "sensor_msgs/msg/Imu"
STRING = "std_msgs/msg/String"


def read_rows(n):
    with CSV.open() as f:
        r = csv.reader(f)
        next(r)
        rows = []
        for row in r:
            rows.append((int(row[0]), [float(v) for v in row[1:7]]))
            if len(rows) == n:
                return rows
    raise SystemExit(f"{CSV} has fewer than {n} rows")


def imu_msg(ts, ros1, t_ns, seq, gyro, acc, frame="imu4"):
    t = ts.types
    time = t["builtin_interfaces/msg/Time"](sec=t_ns // 1_000_000_000, nanosec=t_ns % 1_000_000_000)
    header = (t["std_msgs/msg/Header"](seq=seq, stamp=time, frame_id=frame) if ros1
              else t["std_msgs/msg/Header"](stamp=time, frame_id=frame))
    v3 = t["geometry_msgs/msg/Vector3"]
    unknown = [-1.0] + [0.0] * 8  # orientation not estimated (REP 145)
    return t[IMU](
        header=header,
        orientation=t["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=0.0, w=1.0),
        orientation_covariance=np.array(unknown),
        angular_velocity=v3(x=gyro[0], y=gyro[1], z=gyro[2]),
        angular_velocity_covariance=np.zeros(9),
        linear_acceleration=v3(x=acc[0], y=acc[1], z=acc[2]),
        linear_acceleration_covariance=np.zeros(9),
    )


def serialize(ts, ros1, msg, msgtype):
    return ts.serialize_ros1(msg, msgtype) if ros1 else ts.serialize_cdr(msg, msgtype)


def euroc_messages(ts, ros1):
    """(topic, msgtype, record time ns, message) of euroc_imu.*."""
    for seq, (t_ns, v) in enumerate(read_rows(ROWS)):
        yield "/imu0", IMU, t_ns + RECORD_OFFSET_NS, imu_msg(ts, ros1, t_ns, seq, v[:3], v[3:])


def lerp_accel(rows, t):
    """Accelerometer of the CSV linearly interpolated at t ns (t within the rows)."""
    for (t0, v0), (t1, v1) in zip(rows, rows[1:]):
        if t0 <= t <= t1:
            w = (t - t0) / (t1 - t0)
            return [a + w * (b - a) for a, b in zip(v0[3:], v1[3:])]
    raise ValueError(t)


def split_messages(ts, ros1):
    """Messages of split.*, in record-time order."""
    rows = read_rows(SPLIT_ROWS)
    t0, t_end = rows[0][0], rows[-1][0]
    out = []
    for seq, (t_ns, v) in enumerate(rows):
        msg = imu_msg(ts, ros1, t_ns, seq, v[:3], [0.0] * 3, "camera_gyro_optical_frame")
        out.append(("/camera/gyro/sample", IMU, t_ns, msg))
    k = 0
    while t0 + round(k * 1e9 / ACCEL_HZ) <= t_end:
        t = t0 + round(k * 1e9 / ACCEL_HZ)
        msg = imu_msg(ts, ros1, t, k, [0.0] * 3, lerp_accel(rows, t), "camera_accel_optical_frame")
        out.append(("/camera/accel/sample", IMU, t, msg))
        k += 1
    for s in range(int((t_end - t0) // 1_000_000_000) + 1):
        t = t0 + s * 1_000_000_000 + 500_000
        out.append(("/status", STRING, t, ts.types[STRING](data=f"recording {s} s")))
    out.sort(key=lambda m: m[2])
    for topic, msgtype, t, msg in out:
        yield topic, msgtype, t + RECORD_OFFSET_NS, msg


def write_bag(path, messages, compress):
    ts = get_typestore(Stores.ROS1_NOETIC)
    path.unlink(missing_ok=True)
    w = Writer1(path)
    if compress:
        w.set_compression(Writer1.CompressionFormat.BZ2)
    with w:
        conns = {}
        for topic, msgtype, t, msg in messages(ts, True):
            if topic not in conns:
                conns[topic] = w.add_connection(topic, msgtype, typestore=ts)
            w.write(conns[topic], t, serialize(ts, True, msg, msgtype))


def write_ros2(path, messages, storage):
    """A ROS 2 bag in `storage` (MCAP or SQLITE3); its one storage file copied to `path`."""
    ts = get_typestore(Stores.ROS2_HUMBLE)
    with tempfile.TemporaryDirectory() as tmp:
        bagdir = Path(tmp) / "bag"
        with Writer2(bagdir, version=9, storage_plugin=storage) as w:
            conns = {}
            for topic, msgtype, t, msg in messages(ts, False):
                if topic not in conns:
                    conns[topic] = w.add_connection(topic, msgtype, typestore=ts)
                w.write(conns[topic], t, serialize(ts, False, msg, msgtype))
        (storage_file,) = bagdir.glob("*" + path.suffix)
        shutil.copyfile(storage_file, path)


def main():
    write_bag(HERE / "euroc_imu.bag", euroc_messages, compress=False)
    write_ros2(HERE / "euroc_imu.mcap", euroc_messages, StoragePlugin.MCAP)
    write_ros2(HERE / "euroc_imu.db3", euroc_messages, StoragePlugin.SQLITE3)
    write_bag(HERE / "split.bag", split_messages, compress=True)
    write_ros2(HERE / "split.mcap", split_messages, StoragePlugin.MCAP)
    write_ros2(HERE / "split.db3", split_messages, StoragePlugin.SQLITE3)
    for p in sorted(HERE.glob("*.bag")) + sorted(HERE.glob("*.mcap")) + sorted(HERE.glob("*.db3")):
        print(f"{p.name}: {p.stat().st_size} bytes")


if __name__ == "__main__":
    main()
