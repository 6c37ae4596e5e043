#!/usr/bin/env bash
# Compare the haunts similarity matrix (haunts-similarity, seed 000 III-C distance-field
# difference, ct = 10 cells) with a straightforward NumPy/SciPy implementation on the same
# input, the 70 synthetic 400x400 maps of the criterion benchmark similarity_matrix/70_maps_400x400.
#
# Runs `cargo bench -p haunts-similarity --bench matrix -- 70_maps_400x400`, keeps the checksum
# line the bench prints to stderr, reads the medians from
# target/criterion/similarity_matrix/70_maps_400x400{,_1thread}/new/estimates.json, then runs
# benches/peers/similarity_numpy.py with the Rust checksum (it exits 1 unless its matrix agrees),
# and prints both medians and the ratios numpy / haunts.
#
# Usage (from anywhere; runs from the project root):
#   benches/peers/compare_similarity.sh [similarity_numpy.py options]
# e.g. benches/peers/compare_similarity.sh --runs 5
set -euo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
cd "$root"

# Fail fast, before the long cargo build, if the Python peer cannot run.
if ! python3 -c 'import numpy, scipy.ndimage' 2>/dev/null; then
    echo "error: the Python peer needs numpy and scipy;" >&2
    echo "       install them with: pip install -r benches/peers/requirements.txt" >&2
    exit 1
fi

dir="${CARGO_TARGET_DIR:-target}/criterion/similarity_matrix"
estimates="$dir/70_maps_400x400/new/estimates.json"
one_thread="$dir/70_maps_400x400_1thread/new/estimates.json"
prepared="$dir/70_maps_400x400_prepared/new/estimates.json"
rm -f "$estimates" "$one_thread" "$prepared" # never report a stale result

log="$(mktemp)"
trap 'rm -f "$log"' EXIT

cargo bench -p haunts-similarity --bench matrix --no-run >&2 # compile first: the load before the run is the bench's
load_haunts="$(uptime)"
echo "== haunts ($load_haunts): cargo bench -p haunts-similarity --bench matrix -- 70_maps_400x400" >&2
cargo bench -p haunts-similarity --bench matrix -- 70_maps_400x400 2>&1 | tee "$log" >&2
for f in "$estimates" "$one_thread"; do
    if [[ ! -f "$f" ]]; then
        echo "error: criterion wrote no $f (are the benchmark ids similarity_matrix/70_maps_400x400{,_1thread}?)" >&2
        exit 1
    fi
done

# "similarity checksum: maps=70 sum_offdiag=... sum_offdiag_d2=... terms=... occupied=..."
checksum_line="$(grep -m1 '^similarity checksum:' "$log" || true)"
if [[ -z "$checksum_line" ]]; then
    echo "error: the bench printed no 'similarity checksum:' line to stderr" >&2
    exit 1
fi
field() { sed -n "s/.* $1=\([^ ]*\).*/\1/p" <<<"$checksum_line"; }

load_numpy="$(uptime)"
echo "== numpy+scipy ($load_numpy): python3 benches/peers/similarity_numpy.py $*" >&2
if ! numpy_json="$(python3 benches/peers/similarity_numpy.py "$@" \
    --rust-checksum "$(field sum_offdiag)" --rust-checksum-d2 "$(field sum_offdiag_d2)" \
    --rust-terms "$(field terms)" --rust-occupied "$(field occupied)")"; then
    echo "error: similarity_numpy.py failed or its checksum differs from the Rust bench's (see above)" >&2
    exit 1
fi

echo "load before haunts: $load_haunts"
echo "load before numpy:  $load_numpy"
python3 - "$estimates" "$one_thread" "$prepared" "$numpy_json" "$checksum_line" <<'EOF_PY'
import json
import os
import sys

def median_s(path):
    with open(path) as f:
        return json.load(f)["median"]["point_estimate"] * 1e-9  # criterion reports ns

haunts_s, one_s = median_s(sys.argv[1]), median_s(sys.argv[2])
numpy = json.loads(sys.argv[4])
numpy_s = numpy["median_s"]
print(f"input:    {numpy['maps']} maps of {numpy['shape'][0]}x{numpy['shape'][1]} cells, "
      f"{numpy['occupied']} occupied cells, ct = 10 cells")
print(f"checksum: {sys.argv[5].split(': ', 1)[1]} (rust)")
print(f"checksum: sum_offdiag={numpy['checksum']!r} sum_offdiag_d2={numpy['checksum_d2']} "
      f"terms={numpy['terms']} occupied={numpy['occupied']} (numpy)")
print(f"haunts:   median {haunts_s * 1e3:10.2f} ms  (criterion similarity_matrix/70_maps_400x400, all cores)")
print(f"haunts:   median {one_s * 1e3:10.2f} ms  (criterion similarity_matrix/70_maps_400x400_1thread)")
if os.path.exists(sys.argv[3]):
    print(f"haunts:   median {median_s(sys.argv[3]) * 1e3:10.2f} ms  "
          "(criterion similarity_matrix/70_maps_400x400_prepared: pair sums only, all cores)")
print(f"numpy:    median {numpy_s * 1e3:10.2f} ms  (numpy {numpy['numpy']} + scipy {numpy['scipy']}, "
      f"{numpy['runs']} runs, 1 thread, distance transforms included; occupied cells gathered once per map)")
print(f"ratio numpy/haunts: {numpy_s / haunts_s:.2f}x (all cores)")
print(f"ratio numpy/haunts: {numpy_s / one_s:.2f}x (one thread each)")
EOF_PY
