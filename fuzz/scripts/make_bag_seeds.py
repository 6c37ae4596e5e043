#!/usr/bin/env python3
"""Writes the seeds of the `bag_ros1` and `bag_mcap` fuzz targets (run from `fuzz/`).

The valid files are written by a peer tool, `rosbags` (`pip install rosbags`), not by
haunts: small ROS 1 bags (uncompressed, bz2, lz4; small chunks so there are several) and a
ROS 2 MCAP bag, each with every built-in message type of `haunts_bag::msg`; `ok-unindexed-lz4.bag`
is the lz4 one as a recorder killed before closing leaves it (index_pos 0, no index section). The ROS 1 seeds
also keep one real recording, `positive_2_extracted.bag` of the shared data (320 kB). `bad-*`
seeds are truncated or garbled copies. `bag/tests/fuzz_regressions.rs` checks every outcome.
"""
import pathlib
import shutil
import tempfile

import numpy as np
from rosbags.rosbag1 import Writer as Writer1
from rosbags.rosbag2 import StoragePlugin, Writer as Writer2
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

OUT = pathlib.Path("seeds")
REAL = pathlib.Path("/work/shared/data/leg_tracker/training/bags/positive_2_extracted.bag")


def messages(ts):
    """(topic, type, stamp ns, message) of a tiny recording."""
    T = ts.types
    Time = T["builtin_interfaces/msg/Time"]
    def header(ns, frame):
        stamp = Time(sec=ns // 10**9, nanosec=ns % 10**9)
        if "seq" in T["std_msgs/msg/Header"].__dataclass_fields__:  # ROS 1
            return T["std_msgs/msg/Header"](seq=0, stamp=stamp, frame_id=frame)
        return T["std_msgs/msg/Header"](stamp=stamp, frame_id=frame)
    Point, Quat = T["geometry_msgs/msg/Point"], T["geometry_msgs/msg/Quaternion"]
    Pose = T["geometry_msgs/msg/Pose"]
    pose = lambda x: Pose(position=Point(x=x, y=0.5, z=0.0), orientation=Quat(x=0.0, y=0.0, z=0.0, w=1.0))
    Vec3 = T["geometry_msgs/msg/Vector3"]
    tf = lambda ns, parent, child, x: T["geometry_msgs/msg/TransformStamped"](
        header=header(ns, parent), child_frame_id=child,
        transform=T["geometry_msgs/msg/Transform"](translation=Vec3(x=x, y=0.0, z=0.0), rotation=Quat(x=0.0, y=0.0, z=0.0, w=1.0)))
    out = []
    t0 = 1_600_000_000 * 10**9
    out.append(("/tf_static", "tf2_msgs/msg/TFMessage", t0, T["tf2_msgs/msg/TFMessage"](transforms=[tf(t0, "base_link", "laser", 0.3)])))
    m = T["nav_msgs/msg/MapMetaData"](map_load_time=Time(sec=0, nanosec=0), resolution=0.5, width=3, height=2, origin=pose(-1.0))
    out.append(("/map", "nav_msgs/msg/OccupancyGrid", t0, T["nav_msgs/msg/OccupancyGrid"](header=header(t0, "map"), info=m, data=np.array([0, 100, -1, 0, 0, 50], dtype=np.int8))))
    for i in range(3):
        ns = t0 + i * 100_000_000
        out.append(("/scan", "sensor_msgs/msg/LaserScan", ns, T["sensor_msgs/msg/LaserScan"](
            header=header(ns, "laser"), angle_min=-1.0, angle_max=1.0, angle_increment=0.5, time_increment=0.0,
            scan_time=0.1, range_min=0.05, range_max=8.0, ranges=np.array([1.0 + i, 2.0, float("nan"), 9.0, 0.5], dtype=np.float32),
            intensities=np.array([], dtype=np.float32))))
        cov = np.zeros(36, dtype=np.float64)
        odom = T["nav_msgs/msg/Odometry"](header=header(ns, "odom"), child_frame_id="base_link",
            pose=T["geometry_msgs/msg/PoseWithCovariance"](pose=pose(0.1 * i), covariance=cov),
            twist=T["geometry_msgs/msg/TwistWithCovariance"](twist=T["geometry_msgs/msg/Twist"](linear=Vec3(x=1.0, y=0.0, z=0.0), angular=Vec3(x=0.0, y=0.0, z=0.0)), covariance=cov))
        out.append(("/odom", "nav_msgs/msg/Odometry", ns, odom))
        out.append(("/tf", "tf2_msgs/msg/TFMessage", ns, T["tf2_msgs/msg/TFMessage"](transforms=[tf(ns, "odom", "base_link", 0.1 * i)])))
    ps = T["geometry_msgs/msg/PoseStamped"](header=header(t0, "map"), pose=pose(2.0))
    out.append(("/goal", "geometry_msgs/msg/PoseStamped", t0, ps))
    out.append(("/people", "geometry_msgs/msg/PoseArray", t0, T["geometry_msgs/msg/PoseArray"](header=header(t0, "map"), poses=[pose(1.0), pose(3.0)])))
    out.append(("/plan", "nav_msgs/msg/Path", t0, T["nav_msgs/msg/Path"](header=header(t0, "map"), poses=[ps, ps])))
    return out


def ros1(path, compression):
    ts = get_typestore(Stores.ROS1_NOETIC)
    # The Noetic store has no tf2_msgs: register its one message from its definition.
    ts.register(get_types_from_msg("geometry_msgs/TransformStamped[] transforms", "tf2_msgs/msg/TFMessage"))
    path.unlink(missing_ok=True)
    w = Writer1(path)
    if compression:
        w.set_compression(compression)
    w.chunk_threshold = 600  # several chunks
    with w:
        conns = {}
        for topic, typ, ns, msg in messages(ts):
            if topic not in conns:
                conns[topic] = w.add_connection(topic, typ, typestore=ts)
            w.write(conns[topic], ns, ts.serialize_ros1(msg, typ))


def mcap(path):
    ts = get_typestore(Stores.ROS2_HUMBLE)
    with tempfile.TemporaryDirectory() as tmp:
        d = pathlib.Path(tmp) / "bag"
        with Writer2(d, version=8, storage_plugin=StoragePlugin.MCAP) as w:
            conns = {}
            for topic, typ, ns, msg in messages(ts):
                if topic not in conns:
                    conns[topic] = w.add_connection(topic, typ, typestore=ts)
                w.write(conns[topic], ns, ts.serialize_cdr(msg, typ))
        shutil.copy(next(d.glob("*.mcap")), path)


def bad(src, name, data):
    (src.parent / name).write_bytes(data)


def unindexed(data):
    """A bag as a recorder killed before closing leaves it: index_pos 0, no index section."""
    at = data.index(b"index_pos=") + 10
    pos = int.from_bytes(data[at:at + 8], "little")
    out = bytearray(data[:pos])
    out[at:at + 8] = bytes(8)
    return bytes(out)


def main():
    r, m = OUT / "bag_ros1", OUT / "bag_mcap"
    ros1(r / "ok-plain.bag", None)
    ros1(r / "ok-bz2.bag", Writer1.CompressionFormat.BZ2)
    ros1(r / "ok-lz4.bag", Writer1.CompressionFormat.LZ4)
    shutil.copy(REAL, r / "ok-positive_2_extracted.bag")
    bad(r / "x", "ok-unindexed-lz4.bag", unindexed((r / "ok-lz4.bag").read_bytes()))
    plain = (r / "ok-plain.bag").read_bytes()
    bad(r / "x", "bad-truncated-half.bag", plain[: len(plain) // 2])
    g = bytearray(plain)
    for i in range(200, len(g), 97):
        g[i] ^= 0x5A
    bad(r / "x", "bad-garbled.bag", bytes(g))
    mcap(m / "ok-ros2.mcap")
    data = (m / "ok-ros2.mcap").read_bytes()
    bad(m / "x", "bad-truncated-half.mcap", data[: len(data) // 2])
    g = bytearray(data)
    for i in range(100, len(g) - 400, 89):  # records garbled, summary and footer kept
        g[i] ^= 0x5A
    bad(m / "x", "bad-garbled.mcap", bytes(g))


if __name__ == "__main__":
    main()
