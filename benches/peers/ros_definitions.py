#!/usr/bin/env python3
"""Prints bag/src/msg/definitions.rs: the ROS 2 (`ros2msg`) definitions and ROS 1 MD5 sums of the
messages haunts-bag reads and writes, from the `rosbags` package's type stores (ROS 2 Humble,
ROS 1 Noetic). tf2_msgs/TFMessage is not in rosbags' Noetic store: its ROS 1 MD5 is the one
recorded in general_tracking_moving_1.bag (and in every ROS 1 tf bag).

usage: python3 benches/peers/ros_definitions.py > bag/src/msg/definitions.rs
"""
from rosbags.typesys import Stores, get_typestore

NAMES = ["sensor_msgs/msg/LaserScan", "nav_msgs/msg/Odometry", "tf2_msgs/msg/TFMessage",
         "geometry_msgs/msg/PoseStamped", "geometry_msgs/msg/PoseWithCovarianceStamped",
         "geometry_msgs/msg/PoseArray", "nav_msgs/msg/OccupancyGrid", "nav_msgs/msg/Path",
         "visualization_msgs/msg/Marker", "visualization_msgs/msg/MarkerArray"]
TF_MD5 = "94810edda583a504dfda3829e70d7eec"


def main():
    ts1, ts2 = get_typestore(Stores.ROS1_NOETIC), get_typestore(Stores.ROS2_HUMBLE)
    out = ["//! The ROS 2 message definitions (`ros2msg` text, dependencies after `MSG:` separators) and\n"
           "//! ROS 1 MD5 sums of the built-in messages, generated once from the `rosbags` Python\n"
           "//! package's type stores (ROS 2 Humble, ROS 1 Noetic; `benches/peers/ros_definitions.py`).\n"]
    for n in NAMES:
        try:
            _, md5 = ts1.generate_msgdef(n, ros_version=1)
        except Exception:
            md5 = TF_MD5
        d2, _ = ts2.generate_msgdef(n, ros_version=2)
        c = n.split('/')[-1].upper()
        out.append(f"/// `{n}` in ROS 2 (`ros2msg`).\npub const {c}_DEFINITION: &str = {d2!r};\n".replace("'", '"'))
        out.append(f"/// MD5 sum of `{n.replace('/msg/', '/')}` in ROS 1.\npub const {c}_MD5: &str = \"{md5}\";\n")
    print("\n".join(out), end="")


if __name__ == "__main__":
    main()
