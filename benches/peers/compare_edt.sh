#!/usr/bin/env bash
# Compare the haunts exact EDT with scipy.ndimage.distance_transform_edt on the same input,
# the 4000x4000 tiled willow map.
#
# Runs the criterion benchmark `edt/willow_tiled_4000` (cargo bench --bench edt), reads its
# median from target/criterion/edt/willow_tiled_4000/new/estimates.json, then runs
# benches/peers/edt_scipy.py, and prints both medians and the ratio scipy / haunts.
#
# Usage (from anywhere; runs from the project root): benches/peers/compare_edt.sh [edt_scipy.py options]
# e.g. benches/peers/compare_edt.sh --runs 5
set -euo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
cd "$root"

# Fail fast, before the long cargo build, if the Python peer cannot run.
if ! python3 -c 'import numpy, scipy, PIL, yaml' 2>/dev/null; then
    echo "error: the Python peer needs numpy, scipy, Pillow and PyYAML;" >&2
    echo "       install them with: pip install -r benches/peers/requirements.txt" >&2
    exit 1
fi

estimates="${CARGO_TARGET_DIR:-target}/criterion/edt/willow_tiled_4000/new/estimates.json"
rm -f "$estimates" "${estimates/willow_tiled_4000\//willow_tiled_4000_1thread/}" # never report a stale result

echo "== haunts: cargo bench --bench edt -- willow_tiled_4000" >&2
cargo bench --bench edt -- willow_tiled_4000 >&2
if [[ ! -f "$estimates" ]]; then
    echo "error: criterion wrote no $estimates (is the benchmark id edt/willow_tiled_4000?)" >&2
    exit 1
fi

echo "== scipy: python3 benches/peers/edt_scipy.py $*" >&2
scipy_json="$(python3 benches/peers/edt_scipy.py "$@")"

python3 - "$estimates" "$scipy_json" <<'EOF'
import json
import os
import sys

def median_s(path):
    with open(path) as f:
        return json.load(f)["median"]["point_estimate"] * 1e-9  # criterion reports ns

haunts_s = median_s(sys.argv[1])
# The same input on a one-thread rayon pool, when the filter ran it too.
one_thread = sys.argv[1].replace("willow_tiled_4000/", "willow_tiled_4000_1thread/")
scipy = json.loads(sys.argv[2])
scipy_s = scipy["median_s"]
print(f"input:   willow tiled to {scipy['shape'][0]}x{scipy['shape'][1]}")
print(f"haunts:  median {haunts_s * 1e3:10.2f} ms  (criterion edt/willow_tiled_4000, all cores)")
if os.path.exists(one_thread):
    one_s = median_s(one_thread)
    print(f"haunts:  median {one_s * 1e3:10.2f} ms  (criterion edt/willow_tiled_4000_1thread)")
print(f"scipy:   median {scipy_s * 1e3:10.2f} ms  (scipy {scipy['scipy']}, {scipy['runs']} runs, 1 thread)")
print(f"ratio scipy/haunts: {scipy_s / haunts_s:.2f}x (all cores)")
if os.path.exists(one_thread):
    print(f"ratio scipy/haunts: {scipy_s / one_s:.2f}x (one thread each)")
EOF
