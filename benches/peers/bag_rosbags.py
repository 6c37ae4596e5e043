#!/usr/bin/env python3
"""Python peer of haunts-bag's read bench (bag/benches/read.rs): read and decode every
LaserScan (/scan), Odometry (/odom) and TFMessage (/tf) message of the shared ROS 1 bag and of
its MCAP twin with `rosbags` (its fastest general route: `rosbags.highlevel.AnyReader`, one pass
over the three connections, `reader.deserialize`, which is rosbags' compiled ROS 1 / CDR
deserialiser), the median of --runs passes per file.

Also times the floor any reader has: a plain read of each file (page cache warm), and for the
MCAP the zstd decompression of its chunks alone (python `zstandard`, chunk records taken with the
`mcap` package outside the timed loop).

Prints one JSON object: per file its size, the tallies (counts and sums the Rust bench prints
too, so both sides are checked to decode the same messages), the median/min/max seconds, and
the floors. Run from the project root:

    python3 benches/peers/bag_rosbags.py --bag /tmp/.../general_tracking_moving_1.bag \
        --mcap ../shared/data/leg_tracker/general_tracking_moving_1.mcap --runs 5
"""
import argparse
import json
import os
import statistics
import time
from importlib.metadata import version
from pathlib import Path

from rosbags.highlevel import AnyReader
from rosbags.typesys import Stores, get_typestore

TOPICS = ("/scan", "/odom", "/tf")


def one_pass(path):
    """Reads and decodes the three topics once; returns the tallies."""
    t = dict(scans=0, beams=0, odoms=0, odom_x_sum=0.0, tf_messages=0, transforms=0)
    with AnyReader([path], default_typestore=get_typestore(Stores.ROS2_HUMBLE)) as reader:
        conns = [c for c in reader.connections if c.topic in TOPICS]
        for conn, _stamp, raw in reader.messages(connections=conns):
            msg = reader.deserialize(raw, conn.msgtype)
            if conn.topic == "/scan":
                t["scans"] += 1
                t["beams"] += len(msg.ranges)
            elif conn.topic == "/odom":
                t["odoms"] += 1
                t["odom_x_sum"] += msg.pose.pose.position.x
            else:
                t["tf_messages"] += 1
                t["transforms"] += len(msg.transforms)
    return t


def timed(fn, runs):
    times, out = [], None
    for _ in range(runs):
        start = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - start)
    return out, dict(median_s=statistics.median(times), min_s=min(times), max_s=max(times), runs=runs)


def plain_read(path):
    with open(path, "rb") as f:
        while f.read(1 << 20):
            pass


def mcap_chunks(path):
    from mcap.records import Chunk
    from mcap.stream_reader import StreamReader

    with open(path, "rb") as f:
        chunks = [r for r in StreamReader(f, skip_magic=False, emit_chunks=True).records
                  if isinstance(r, Chunk)]
    return chunks


def zstd_chunks(chunks):
    import zstandard

    d = zstandard.ZstdDecompressor()
    total = 0
    for c in chunks:
        assert c.compression == "zstd", c.compression
        total += len(d.decompress(c.data, max_output_size=c.uncompressed_size))
    return total


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--bag", type=Path, required=True)
    ap.add_argument("--mcap", type=Path, required=True)
    ap.add_argument("--runs", type=int, default=5)
    args = ap.parse_args()
    out = dict(versions={p: version(p) for p in ("rosbags", "mcap", "zstandard")}, files={})
    for name, path in (("ros1", args.bag), ("mcap", args.mcap)):
        tally, timing = timed(lambda: one_pass(path), args.runs)
        _, read_floor = timed(lambda: plain_read(path), max(args.runs, 5))
        entry = dict(bytes=os.path.getsize(path), check=tally, rosbags=timing, plain_read=read_floor)
        if name == "mcap":
            chunks = mcap_chunks(path)
            total, dec = timed(lambda: zstd_chunks(chunks), max(args.runs, 5))
            dec["chunks"] = len(chunks)
            dec["uncompressed_bytes"] = total
            entry["zstd_chunks"] = dec
        out["files"][name] = entry
    out["load_average"] = list(os.getloadavg())
    print(json.dumps(out))


if __name__ == "__main__":
    main()
