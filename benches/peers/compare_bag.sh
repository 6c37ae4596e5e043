#!/usr/bin/env bash
# Compare haunts-bag's reading with the Python `rosbags` reader on issue 16's workload, side by
# side in one run: read and decode every LaserScan (/scan), Odometry (/odom) and TFMessage (/tf)
# message of the shared ROS 1 bag (unzipped into the temporary folder by the bench) and of its
# MCAP twin.
#
# Records `uptime`, runs `cargo bench -p haunts-bag --bench read` (criterion medians from
# target/criterion; the bench prints a `bag check:` line per file), then
# benches/peers/bag_rosbags.py, checks that both sides decoded the same messages (counts, beam
# and transform totals, the sum of odometry x), and prints MB/s, the ratio rosbags / haunts
# (goal >= 10x) and the floors: a plain read of the file and, for the MCAP, the zstd
# decompression of its chunks alone. Exits non-zero if the two sides disagree.
#
# Usage (from anywhere; runs from the project root):
#   benches/peers/compare_bag.sh [bag_rosbags.py options, e.g. --runs 5]
set -euo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
cd "$root"

if ! python3 -c 'import rosbags, mcap, zstandard' 2>/dev/null; then
    echo "error: the peer needs rosbags, mcap and zstandard: pip install -r benches/peers/requirements-bag.txt" >&2
    exit 1
fi
zip="../shared/data/leg_tracker/general_tracking_moving_1.bag.zip"
mcap="../shared/data/leg_tracker/general_tracking_moving_1.mcap"
if [[ ! -f "$zip" || ! -f "$mcap" ]]; then
    echo "error: needs $zip and $mcap" >&2
    exit 1
fi

crit="${CARGO_TARGET_DIR:-target}/criterion"
ids=(bag_read_ros1/one_pass bag_read_ros1/per_topic bag_read_mcap/one_pass bag_read_mcap/per_topic)
for id in "${ids[@]}"; do rm -f "$crit/$id/new/estimates.json"; done # never report a stale result

log="$(mktemp)"
trap 'rm -f "$log"' EXIT
echo "== $(date -u +%FT%TZ) uptime: $(uptime)" >&2
echo "== cargo bench -p haunts-bag --bench read" >&2
cargo bench -p haunts-bag --bench read 2>&1 | tee "$log" >&2
for id in "${ids[@]}"; do
    if [[ ! -f "$crit/$id/new/estimates.json" ]]; then
        echo "error: criterion wrote no $crit/$id/new/estimates.json" >&2
        exit 1
    fi
done

# Where the bench (tests/support/bag.rs) unzipped the bag: beside the zip's size.
bag="$(python3 -c 'import os,sys,tempfile; print(os.path.join(tempfile.gettempdir(), "haunts-bag-tests-%d" % os.path.getsize(sys.argv[1]), "general_tracking_moving_1.bag"))' "$zip")"
echo "== $(date -u +%FT%TZ) uptime: $(uptime)" >&2
echo "== python3 benches/peers/bag_rosbags.py --bag $bag --mcap $mcap $*" >&2
peer_json="$(python3 benches/peers/bag_rosbags.py --bag "$bag" --mcap "$mcap" "$@")"
echo "== $(date -u +%FT%TZ) uptime: $(uptime)" >&2

python3 - "$crit" "$log" "$peer_json" <<'EOF_PY'
import json
import re
import sys

crit, log_path, peer = sys.argv[1], sys.argv[2], json.loads(sys.argv[3])
ours = {}
for m in re.finditer(r"^bag check: (\{.*\})$", open(log_path).read(), re.M):
    d = json.loads(m.group(1))
    ours[d["file"]] = d

def median_s(bench_id):
    with open(f"{crit}/{bench_id}/new/estimates.json") as f:
        return json.load(f)["median"]["point_estimate"] * 1e-9

ok = True
print(f"versions: {peer['versions']}")
for name, entry in peer["files"].items():
    if name not in ours:
        sys.exit(f"error: the bench printed no `bag check:` line for {name}")
    size = entry["bytes"]
    mb = size / 1e6
    same = all(
        (abs(ours[name][k] - v) <= 1e-9 * (1 + abs(v))) if isinstance(v, float) else ours[name][k] == v
        for k, v in entry["check"].items()
    ) and ours[name]["bytes"] == size
    ok &= same
    print(f"{name}: {mb:.2f} MB; same messages decoded: {'ok' if same else 'FAIL'} {entry['check']}")
    peer_s = entry["rosbags"]["median_s"]
    for route in ("one_pass", "per_topic"):
        s = median_s(f"bag_read_{name}/{route}")
        print(f"  haunts {route:9s} {s * 1e3:8.1f} ms {mb / s:8.1f} MB/s   rosbags/haunts {peer_s / s:6.1f}x"
              f"   goal >= 10x: {'met' if peer_s / s >= 10 else 'NOT met'}")
    print(f"  rosbags           {peer_s * 1e3:8.1f} ms {mb / peer_s:8.1f} MB/s   "
          f"(median of {entry['rosbags']['runs']}, min {entry['rosbags']['min_s'] * 1e3:.0f}, "
          f"max {entry['rosbags']['max_s'] * 1e3:.0f} ms)")
    r = entry["plain_read"]["median_s"]
    print(f"  floor: plain read {r * 1e3:8.2f} ms {mb / r:8.1f} MB/s")
    if "zstd_chunks" in entry:
        z = entry["zstd_chunks"]
        print(f"  floor: zstd of {z['chunks']} chunks {z['median_s'] * 1e3:.1f} ms {mb / z['median_s']:.1f} MB/s "
              f"of file ({z['uncompressed_bytes'] / 1e6:.1f} MB out, {z['uncompressed_bytes'] / 1e6 / z['median_s']:.0f} MB/s)")
print(f"load average at the peer's end: {peer['load_average']}")
sys.exit(0 if ok else 1)
EOF_PY
