#!/usr/bin/env bash
# Compare haunts-affordance's Gustafson–Kessel clustering with a vectorised NumPy GK on issue 7's
# workload, side by side in one run: k = 30, m = 2, 50 000 4-D hypertime points (SplitMix64
# seed 7, the same bits on both sides), the same initial centres, one iteration timed.
#
# Runs `cargo bench -p haunts-affordance --bench gk` (criterion medians from target/criterion;
# the bench also prints a `gk check:` line: 10 iterations from the initial centres), then
# benches/peers/gk_numpy.py, and prints both medians, the ratio NumPy / haunts, and whether both
# sides computed the same thing: the same data (sha256), objectives within a relative 1e-9 and
# centres within 1e-8 · (1 + |c|) after 10 iterations (the two sum in different orders, and
# haunts forms the covariances about the old centre, so they agree to rounding, not bits).
# Exits non-zero if they do not agree.
#
# Usage (from anywhere; runs from the project root):
#   benches/peers/compare_gk.sh [gk_numpy.py options, e.g. --runs 30 --threads 2]
set -euo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
cd "$root"

if ! python3 -c 'import numpy' 2>/dev/null; then
    echo "error: the NumPy peer needs numpy: pip install -r benches/peers/requirements-gk.txt" >&2
    exit 1
fi

crit="${CARGO_TARGET_DIR:-target}/criterion"
ids=(gk/iteration_k30_m2_n50000_d4 gk/iteration_k30_m2_n50000_d4_one_thread)
for id in "${ids[@]}"; do rm -f "$crit/$id/new/estimates.json"; done # never report a stale result

log="$(mktemp)"
trap 'rm -f "$log"' EXIT
echo "== $(date -u +%FT%TZ) load $(cut -d' ' -f1-3 /proc/loadavg): cargo bench -p haunts-affordance --bench gk" >&2
cargo bench -p haunts-affordance --bench gk 2>&1 | tee "$log" >&2
for id in "${ids[@]}"; do
    if [[ ! -f "$crit/$id/new/estimates.json" ]]; then
        echo "error: criterion wrote no $crit/$id/new/estimates.json" >&2
        exit 1
    fi
done

echo "== $(date -u +%FT%TZ) load $(cut -d' ' -f1-3 /proc/loadavg): python3 benches/peers/gk_numpy.py $*" >&2
peer_json="$(python3 benches/peers/gk_numpy.py "$@")"

python3 - "$crit" "$log" "$peer_json" <<'EOF_PY'
import json
import re
import sys

crit, log_path, peer = sys.argv[1], sys.argv[2], json.loads(sys.argv[3])
m = re.search(r"^gk check: (\{.*\})$", open(log_path).read(), re.M)
if not m:
    sys.exit("error: the bench printed no `gk check:` line")
ours = json.loads(m.group(1))

def median_s(bench_id):
    with open(f"{crit}/{bench_id}/new/estimates.json") as f:
        return json.load(f)["median"]["point_estimate"] * 1e-9

ok = True
def check(name, good, detail):
    global ok
    ok &= good
    print(f"check {name:10s} {'ok  ' if good else 'FAIL'} {detail}")

w = peer["workload"]
print(f"workload: n={w['n']} dim={w['dim']} k={w['k']} m={w['m']} seed={w['seed']}; "
      f"versions={peer['versions']}; NumPy BLAS threads={peer['threads']}, "
      f"rayon threads={ours['threads']}, cpus={peer['cpus']}")
check("data", ours["data_sha256"] == w["data_sha256"],
      f"sha256 haunts {ours['data_sha256'][:16]}… numpy {w['data_sha256'][:16]}…")
pc = peer["check"]
it = ours["iterations"]
check("iterations", it == pc["iterations"], f"haunts {it}, numpy {pc['iterations']}")
rel = max(abs(a - b) / abs(b) for a, b in zip(ours["objectives"], pc["objectives"]))
check("objective", rel <= 1e-9,
      f"after {it} iterations haunts {ours['objectives'][-1]!r} numpy {pc['objectives'][-1]!r}; "
      f"largest relative difference over the iterations {rel:.2e} (tolerance 1e-9)")
scaled = max(abs(a - b) / (1 + abs(b)) for a, b in zip(ours["centres"], pc["centres"]))
check("centres", len(ours["centres"]) == len(pc["centres"]) and scaled <= 1e-8,
      f"{len(pc['centres'])} values, largest |difference| / (1 + |c|) {scaled:.2e} (tolerance 1e-8)")
check("change", abs(ours["change"] - pc["change"]) <= 1e-8,
      f"largest membership change in iteration {it}: haunts {ours['change']!r} numpy {pc['change']!r}")

all_cores = median_s("gk/iteration_k30_m2_n50000_d4")
one = median_s("gk/iteration_k30_m2_n50000_d4_one_thread")
numpy = peer["median_s"]
print(f"one GK iteration (k=30, m=2, n=50000, 4-D), medians:")
print(f"  haunts, all cores ({ours['threads']}) {all_cores * 1e3:8.2f} ms   ratio numpy/haunts {numpy / all_cores:6.2f}x"
      f"   target <= 17 ms: {'met' if all_cores <= 0.017 else 'NOT met'}")
print(f"  haunts, one thread  {one * 1e3:8.2f} ms   ratio numpy/haunts {numpy / one:6.2f}x")
print(f"  numpy ({peer['threads']} BLAS threads) {numpy * 1e3:8.2f} ms   (min {peer['min_s'] * 1e3:.1f}, "
      f"max {peer['max_s'] * 1e3:.1f}, {peer['runs']} iterations; load {peer['load_average'][0]:.2f} at its end)")
sys.exit(0 if ok else 1)
EOF_PY
