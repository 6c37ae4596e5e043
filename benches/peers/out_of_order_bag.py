#!/usr/bin/env python3
"""Writes `bag/tests/fixtures/out_of_order.bag`: a tiny ROS 1 bag (written by `rosbags`, not by
haunts) whose chunks overlap in log time, for `bag/tests/log_time_order.rs`.

24 `geometry_msgs/PoseStamped` messages on `/a` and `/b` are written in an order that is not
their log-time order (log time of the i-th written message: t0 + ((7 i) mod 24) · 0.1 s), with
chunks of about three messages, so every chunk's time range overlaps others. Each message's
`pose.position.x` is its write index and its header stamp its log time. The bag is written
twice, uncompressed and with lz4 chunks (`out_of_order_lz4.bag`).

    python3 benches/peers/out_of_order_bag.py    # from the project root; pip install rosbags
"""
from pathlib import Path

from rosbags.rosbag1 import Writer
from rosbags.typesys import Stores, get_typestore

OUT = Path("bag/tests/fixtures")
T0 = 1_700_000_000 * 10**9


def write(path, compression):
    ts = get_typestore(Stores.ROS1_NOETIC)
    T = ts.types
    path.unlink(missing_ok=True)
    w = Writer(path)
    if compression:
        w.set_compression(compression)
    w.chunk_threshold = 300  # about three messages a chunk
    with w:
        conns = {t: w.add_connection(t, "geometry_msgs/msg/PoseStamped", typestore=ts) for t in ("/a", "/b")}
        for i in range(24):
            ns = T0 + ((7 * i) % 24) * 100_000_000
            stamp = T["builtin_interfaces/msg/Time"](sec=ns // 10**9, nanosec=ns % 10**9)
            msg = T["geometry_msgs/msg/PoseStamped"](
                header=T["std_msgs/msg/Header"](seq=i, stamp=stamp, frame_id="map"),
                pose=T["geometry_msgs/msg/Pose"](
                    position=T["geometry_msgs/msg/Point"](x=float(i), y=0.0, z=0.0),
                    orientation=T["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=0.0, w=1.0)))
            topic = "/a" if i % 3 else "/b"
            w.write(conns[topic], ns, ts.serialize_ros1(msg, "geometry_msgs/msg/PoseStamped"))


def main():
    write(OUT / "out_of_order.bag", None)
    write(OUT / "out_of_order_lz4.bag", Writer.CompressionFormat.LZ4)
    print(f"wrote {OUT}/out_of_order.bag and out_of_order_lz4.bag")


if __name__ == "__main__":
    main()
