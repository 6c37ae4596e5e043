#!/usr/bin/env bash
# Compare haunts-gp with scikit-learn (and GPy) on issue 3's workload, side by side in one run:
# RBF σ² = 1, ℓ = 2, σn² = 0.01, n = 5000 2-D points (SplitMix64 seed 3, the same bits on both
# sides), predictions of mean + latent variance on the 200 × 200 grid over [0, 20]².
#
# Runs `cargo bench -p haunts-gp --bench gp` (criterion medians from target/criterion), keeps the
# lines the bench prints to stderr (log likelihoods, prediction checksums, fast-mode errors),
# then runs benches/peers/gp_peer_bench.py and prints both sides, the checks that they computed
# the same thing, and the ratios peer / haunts against the faster peer.
#
# Usage (from anywhere; runs from the project root):
#   benches/peers/compare_gp.sh [gp_peer_bench.py options]
# e.g. benches/peers/compare_gp.sh --tools sklearn --runs 3   (GPy is slower in every task here)
set -euo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
cd "$root"

if ! python3 -c 'import sklearn, numpy, scipy' 2>/dev/null; then
    echo "error: the Python peer needs scikit-learn (and GPy for --tools gpy);" >&2
    echo "       install them with: pip install -r benches/peers/requirements-gp.txt" >&2
    exit 1
fi

crit="${CARGO_TARGET_DIR:-target}/criterion"
ids=(gp_fit/n5000_fixed gp_fit/n5000_optimised gp_predict/grid200_exact gp_predict/grid200_fast
    gp_sparse/n1M_m500_fit_and_grid200)
for id in "${ids[@]}"; do rm -f "$crit/$id/new/estimates.json"; done # never report a stale result

log="$(mktemp)"
trap 'rm -f "$log"' EXIT
echo "== haunts: cargo bench -p haunts-gp --bench gp" >&2
cargo bench -p haunts-gp --bench gp 2>&1 | tee "$log" >&2
for id in "${ids[@]}"; do
    if [[ ! -f "$crit/$id/new/estimates.json" ]]; then
        echo "error: criterion wrote no $crit/$id/new/estimates.json" >&2
        exit 1
    fi
done

echo "== peers: python3 benches/peers/gp_peer_bench.py $*" >&2
peer_json="$(python3 benches/peers/gp_peer_bench.py "$@")"

python3 - "$crit" "$log" "$peer_json" <<'EOF_PY'
import json
import re
import sys

crit, log_path, peer = sys.argv[1], sys.argv[2], json.loads(sys.argv[3])
log = open(log_path).read()

def median_s(bench_id):
    with open(f"{crit}/{bench_id}/new/estimates.json") as f:
        return json.load(f)["median"]["point_estimate"] * 1e-9

def field(prefix, key):
    m = re.search(rf"^{prefix}.* {key}=([^ \n]+)", log, re.M)
    return m.group(1) if m else None

ours = {
    "fit": median_s("gp_fit/n5000_fixed"),
    "opt": median_s("gp_fit/n5000_optimised"),
    "predict": median_s("gp_predict/grid200_exact"),
    "predict_fast": median_s("gp_predict/grid200_fast"),
}
sparse = median_s("gp_sparse/n1M_m500_fit_and_grid200")
res = peer["results"]
print(f"workload: n={peer['workload']['n']} grid={peer['workload']['grid']} threads={peer['threads']} "
      f"versions={peer['versions']}")
print(f"check fit:     lml haunts {field('gp fit:', 'lml')}  scikit-learn "
      f"{res.get('fit', {}).get('sklearn', {}).get('lml_reported')}")
print(f"check opt:     lml haunts {field('gp opt:', 'lml')}  scikit-learn "
      f"{res.get('opt', {}).get('sklearn', {}).get('lml_exact')}  GPy "
      f"{res.get('opt', {}).get('gpy', {}).get('lml_exact')}")
print(f"check predict: sum mean haunts {field('gp predict:', 'sum_mean')}  scikit-learn "
      f"{res.get('predict', {}).get('sklearn', {}).get('mean_fsum')}; sum var haunts "
      f"{field('gp predict:', 'sum_var')}  scikit-learn {res.get('predict', {}).get('sklearn', {}).get('var_fsum')}")
print(f"fast mode:     nodes {field('gp predict:', 'fast_nodes')} max |mean error| "
      f"{field('gp predict:', 'fast_max_mean_error')} max |variance error| "
      f"{field('gp predict:', 'fast_max_variance_error')} (prior variance 1); peak RSS of the bench "
      f"process at that point {field('gp predict:', 'peak_rss_mb')} MB")
for task, key in [("fit", "fit"), ("opt", "opt"), ("predict", "predict"), ("predict", "predict_fast")]:
    peers = {tool: r["median_s"] for tool, r in res.get(task, {}).items()}
    if not peers:
        continue
    best_tool = min(peers, key=peers.get)
    mem = {tool: r.get("peak_rss_mb") for tool, r in res.get(task, {}).items()}
    print(f"{key:13s} haunts {ours[key]:9.3f} s | " +
          " | ".join(f"{t} {s:9.3f} s (peak {mem[t]:.0f} MB)" for t, s in peers.items()) +
          f" | ratio {best_tool}/haunts {peers[best_tool] / ours[key]:.2f}x")
print(f"sparse        haunts {sparse:9.3f} s (n = 1e6, m = 500, VFE fit + exact grid prediction; "
      f"{field('gp sparse:', 'vfe_bound')} = VFE bound)")
EOF_PY
