#!/usr/bin/env bash
# Compare the haunts exact EDT with the exact EDTs of SciPy, OpenCV (DIST_MASK_PRECISE) and the
# `edt` package on the same input, the 4000x4000 tiled willow map, at equal threads.
#
# Runs the criterion benchmarks `edt/willow_tiled_4000{,_1thread,_nearest,_nearest_1thread}`
# (cargo bench --bench edt, with HAUNTS_EDT_D2_OUT set so that the bench also writes haunts'
# squared distances), reads their medians from target/criterion/edt/*/new/estimates.json, then
# runs benches/peers/edt_scipy.py --with-indices --check <that file> (it exits 1 unless every
# peer's result equals haunts'), and prints a markdown table: per variant (distances only, with
# nearest-obstacle indices) and thread count, the medians and the ratio peer / haunts, with
# `uptime` before each side.
#
# Usage (from anywhere; runs from the project root): benches/peers/compare_edt.sh [edt_scipy.py options]
# e.g. benches/peers/compare_edt.sh --runs 5
set -euo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
cd "$root"

# Fail fast, before the long cargo build, if the Python peers cannot run.
if ! python3 -c 'import numpy, scipy, PIL, yaml, cv2, edt' 2>/dev/null; then
    echo "error: the Python peers need numpy, scipy, Pillow, PyYAML, opencv-python-headless and edt;" >&2
    echo "       install them with: pip install -r benches/peers/requirements.txt -r benches/peers/requirements-edt.txt" >&2
    exit 1
fi

target="${CARGO_TARGET_DIR:-target}"
dir="$target/criterion/edt"
ids=(willow_tiled_4000 willow_tiled_4000_1thread willow_tiled_4000_nearest willow_tiled_4000_nearest_1thread)
for id in "${ids[@]}"; do rm -f "$dir/$id/new/estimates.json"; done # never report a stale result
mkdir -p "$target/edt_peer"
d2="$target/edt_peer/willow_tiled_4000_d2.u32"
rm -f "$d2"

cargo bench --bench edt --no-run >&2 # compile first: the load before the run is the bench's
load_haunts="$(uptime)"
echo "== haunts ($load_haunts): cargo bench --bench edt -- willow_tiled_4000" >&2
HAUNTS_EDT_D2_OUT="$d2" cargo bench --bench edt -- willow_tiled_4000 >&2
for id in "${ids[@]}"; do
    if [[ ! -f "$dir/$id/new/estimates.json" ]]; then
        echo "error: criterion wrote no $dir/$id/new/estimates.json" >&2
        exit 1
    fi
done

load_peers="$(uptime)"
echo "== peers ($load_peers): python3 benches/peers/edt_scipy.py --with-indices --check $d2 $*" >&2
if ! peers_json="$(python3 benches/peers/edt_scipy.py --with-indices --check "$d2" "$@")"; then
    echo "error: edt_scipy.py failed or a peer's result differs from haunts' (see above)" >&2
    exit 1
fi

python3 - "$dir" "$peers_json" "$load_haunts" "$load_peers" <<'EOF'
import json
import os
import sys

def median_s(id):
    with open(os.path.join(sys.argv[1], id, "new", "estimates.json")) as f:
        return json.load(f)["median"]["point_estimate"] * 1e-9  # criterion reports ns

peers = json.loads(sys.argv[2])
cpus = peers["cpus"]
haunts = {
    (False, 1): median_s("willow_tiled_4000_1thread"),
    (False, cpus): median_s("willow_tiled_4000"),
    (True, 1): median_s("willow_tiled_4000_nearest_1thread"),
    (True, cpus): median_s("willow_tiled_4000_nearest"),
}
v = peers["versions"]
print(f"EDT, willow tiled to {peers['shape'][0]}x{peers['shape'][1]} ({peers['obstacles']} obstacles); "
      f"SciPy {v['scipy']}, OpenCV {v.get('opencv', '-')}, edt {v.get('edt', '-')}, NumPy {v['numpy']}; "
      f"every peer's result {'checked equal to haunts' if peers['checked_against_haunts'] else 'NOT checked'}")
print(f"load before haunts: {sys.argv[3].strip()}")
print(f"load before peers:  {sys.argv[4].strip()}")
print()
print("| variant | threads | haunts | SciPy | OpenCV precise | edt | fastest peer / haunts |")
print("|---|---|---|---|---|---|---|")
for indices in (False, True):
    for threads in sorted({1, cpus}):
        cells = {}
        for r in peers["results"]:
            if r["indices"] == indices and r["threads"] == threads:
                cells[r["tool"]] = r["median_s"]
        h = haunts[(indices, threads)]
        fmt = lambda tool: f"{cells[tool] * 1e3:.1f} ms" if tool in cells else "–"
        if cells:
            best = min(cells, key=cells.get)
            ratio = f"**{cells[best] / h:.2f}×** ({best})"
        else:
            ratio = "–"
        what = "with nearest indices" if indices else "distances"
        print(f"| {what} | {threads} | {h * 1e3:.1f} ms | {fmt('scipy')} | {fmt('opencv')} | {fmt('edt')} | {ratio} |")
print()
print("SciPy runs on one thread only; OpenCV's precise transform and edt offer no nearest-obstacle indices.")
EOF
