#!/usr/bin/env python3
"""Writes a ROS 1 bag COPIES times the /scan, /odom and /tf messages of IN (a ROS 1 bag), for
haunts-bag's peak-memory check (issue 16): the raw message bytes copied unchanged with the
`rosbags` rosbag1 writer (uncompressed chunks, as IN has), each copy's receive times shifted past
the previous copy's. Made in the temporary folder, never committed.

    python3 benches/peers/big_ros1_bag.py IN.bag OUT.bag 12
"""
import os
import sys
from pathlib import Path

from rosbags.rosbag1 import Reader, Writer

TOPICS = ("/scan", "/odom", "/tf")


def main():
    src, dst, copies = Path(sys.argv[1]), Path(sys.argv[2]), int(sys.argv[3])
    if dst.exists():
        dst.unlink()
    with Reader(src) as reader, Writer(dst) as writer:
        conns = [c for c in reader.connections if c.topic in TOPICS]
        out = {}
        for c in conns:
            out[c.id] = writer.add_connection(c.topic, c.msgtype, msgdef=c.msgdef.data,
                                              md5sum=c.digest, callerid=c.ext.callerid)
        span = reader.end_time - reader.start_time + 1_000_000_000
        n = 0
        for k in range(copies):
            for conn, stamp, raw in reader.messages(connections=conns):
                writer.write(out[conn.id], stamp + k * span, raw)
                n += 1
    print(f"wrote {n} messages ({copies} copies of {src}) to {dst}: {os.path.getsize(dst)} bytes")


if __name__ == "__main__":
    main()
