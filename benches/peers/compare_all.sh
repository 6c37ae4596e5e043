#!/usr/bin/env bash
# Every side-by-side comparison of haunts with its peers, in sequence, in one command: EDT
# (SciPy, OpenCV, edt), the similarity matrix (NumPy + SciPy), GK clustering (NumPy), reading
# the shared ROS 1 bag and MCAP (rosbags) and, with
# --gp, the Gaussian process (scikit-learn; about 20 minutes more). Records `uptime` before
# each, and writes one markdown report (to stdout and to --out, default
# target/peers/compare_all.md): a summary table with the load before each comparison and its
# ratios, then each script's full output. Each script checks that both sides computed the same
# thing and fails otherwise; a failing comparison is reported as FAILED and the others still run
# (the exit status is then 1).
#
# Usage (from anywhere; runs from the project root):
#   benches/peers/compare_all.sh [--gp] [--runs N] [--out FILE]
# --runs N is passed to the EDT, similarity and GK peers (default: each script's own).
set -uo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
cd "$root"

gp=0
runs=()
out="${CARGO_TARGET_DIR:-target}/peers/compare_all.md"
while [[ $# -gt 0 ]]; do
    case "$1" in
        --gp) gp=1 ;;
        --runs) runs=(--runs "$2"); shift ;;
        --out) out="$2"; shift ;;
        *) echo "usage: $0 [--gp] [--runs N] [--out FILE]" >&2; exit 2 ;;
    esac
    shift
done
mkdir -p "$(dirname "$out")"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT

names=()
status=0
run() { # run NAME SCRIPT ARGS...: the script's stdout to $work/NAME.out
    local name="$1"; shift
    names+=("$name")
    uptime >"$work/$name.load"
    echo "== $name ($(cat "$work/$name.load")): $*" >&2
    if bash "$@" >"$work/$name.out"; then
        echo ok >"$work/$name.status"
    else
        echo FAILED >"$work/$name.status"
        status=1
    fi
}

run edt benches/peers/compare_edt.sh "${runs[@]}"
run similarity benches/peers/compare_similarity.sh "${runs[@]}"
run gk benches/peers/compare_gk.sh "${runs[@]}"
run bag benches/peers/compare_bag.sh "${runs[@]}"
if [[ $gp == 1 ]]; then
    run gp benches/peers/compare_gp.sh --tools sklearn --runs 3
fi

{
    echo "# haunts vs peers, $(date -u '+%Y-%m-%d %H:%M UTC'), $(nproc) cores"
    echo
    echo "Each comparison: criterion medians (haunts) and the peer's medians, measured one after the"
    echo "other in the same run; the load average is the one \`uptime\` printed before it started."
    echo "Ratios measured at a 1-minute load above the core count were measured under load."
    echo
    echo "| comparison | load before (1, 5, 15 min) | status | ratios (peer / haunts) |"
    echo "|---|---|---|---|"
    for name in "${names[@]}"; do
        load="$(sed 's/.*load average: //' "$work/$name.load")"
        # The ratio lines of the script's output (for the EDT, its table rows).
        ratios="$(grep -iE '(^|[^a-z])ratio([^a-z]|$)|^\| (distances|with)|rosbags/haunts' "$work/$name.out" \
            | sed -E 's/^\| //; s/ \|$//; s/\|/·/g; s/  +/ /g' | paste -sd ';' - | sed 's/;/; /g')"
        echo "| $name | $load | $(cat "$work/$name.status") | ${ratios:-–} |"
    done
    for name in "${names[@]}"; do
        echo
        echo "## $name"
        echo
        echo "Load before: $(cat "$work/$name.load")"
        echo
        echo '```'
        cat "$work/$name.out"
        echo '```'
    done
} | tee "$out"
echo "report written to $out" >&2
exit $status
