#!/usr/bin/env python3
"""Writes bag/tests/fixtures/ros1_digests.json: what the `rosbags` ROS 1 reader finds in every
shared ROS 1 bag (the leg_tracker benchmark bag, the training bags, the out-of-order fixtures and
the fuzz seeds ok-*.bag), so that haunts-bag's own reader (tests/ros1_digests.rs) is checked
against a peer message for message without depending on it.

Per bag and topic: the message count, the first and last log time (ns), and a digest that pins
every message's log time and bytes whatever order they are read in: SHA-256 over the sorted
list of (log time as 8 little-endian bytes + SHA-256 of the message's bytes).

    python3 benches/peers/ros1_digests.py BENCHMARK_BAG > bag/tests/fixtures/ros1_digests.json

BENCHMARK_BAG is general_tracking_moving_1.bag unzipped (the bag tests unzip it into the
temporary folder: haunts-bag-tests-<size of the zip>/).
"""
import hashlib
import json
import sys
from importlib.metadata import version
from pathlib import Path

from rosbags.rosbag1 import Reader

ROOT = Path(__file__).resolve().parents[2]
DATA = ROOT.parent / "shared" / "data" / "leg_tracker"


def digests(path):
    per_topic = {}
    with Reader(path) as reader:
        for conn, stamp, raw in reader.messages():
            entry = stamp.to_bytes(8, "little") + hashlib.sha256(raw).digest()
            per_topic.setdefault(conn.topic, []).append((stamp, entry))
    out = {}
    for topic, items in sorted(per_topic.items()):
        items.sort(key=lambda x: x[1])
        h = hashlib.sha256()
        for _, entry in items:
            h.update(entry)
        times = [t for t, _ in items]
        out[topic] = dict(count=len(items), first=min(times), last=max(times), digest=h.hexdigest())
    return out


def main():
    bags = {"general_tracking_moving_1.bag": Path(sys.argv[1])}
    for p in sorted((DATA / "training" / "bags").glob("*.bag")):
        bags[f"training/{p.name}"] = p
    for p in sorted((ROOT / "bag" / "tests" / "fixtures").glob("*.bag")):
        bags[f"fixtures/{p.name}"] = p
    for p in sorted((ROOT / "fuzz" / "seeds" / "bag_ros1").glob("ok-*.bag")):
        if "unindexed" not in p.name:  # rosbags refuses a bag without an index
            bags[f"seeds/{p.name}"] = p
    result = {"peer": f"rosbags {version('rosbags')}", "bags": {k: digests(v) for k, v in bags.items()}}
    json.dump(result, sys.stdout, indent=1, sort_keys=True)
    print()


if __name__ == "__main__":
    main()
