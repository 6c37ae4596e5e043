#!/usr/bin/env bash
# Every fuzz target of this folder, built and run for a few seconds each (issue 49, item 6).
#
# Built on the toolchain at hand (stable is enough) with the coverage instrumentation that
# `cargo fuzz build --sanitizer none` gives, set by hand, so CI needs neither nightly nor
# cargo-fuzz: `--cfg fuzzing`, SanitizerCoverage (inline 8-bit counters, PC table, compare
# tracing, stack depth), debug assertions and overflow checks. `--target` is given so that
# the flags reach the fuzzed code only, never build scripts or proc macros. No AddressSanitizer:
# the readers are safe Rust, and the sanitizer build (nightly, `cargo +nightly fuzz`) costs a
# second build of every dependency; the longer runs in README.md use it.
#
# Each target starts from its committed seeds (`seeds/<target>/`, read only; new inputs go to
# a temporary corpus) with the options of README.md's runs. A crash, a timeout (10 s for one
# input), an allocation over 2 GB or a leak stops the run: the input is saved in
# `$FUZZ_OUT/<target>/` and the script exits non-zero.
#
# The mutations start from libFuzzer's seed `FUZZ_SEED` (default 1), so that CI explores the
# same inputs on every run (as far as its time allows) and a failure reproduces; give another
# seed (or 0, libFuzzer's random one) for a longer run that explores further.
#
# Usage: fuzz/ci.sh [SECONDS_PER_TARGET] [TARGET...]   (default 5 s, every target)
# FUZZ_TARGET_DIR moves the build (default: the root workspace's target directory + /fuzz-ci),
# FUZZ_OUT the crash inputs (default a temporary folder, kept on failure).
set -euo pipefail
HERE=$(cd "$(dirname "$0")" && pwd)
cd "$HERE"
SECONDS_PER=${1:-5}
shift || true

if [ $# -gt 0 ]; then
    TARGETS=("$@")
else
    mapfile -t TARGETS < <(sed -n '/^\[\[bin\]\]/,/^name/ s/^name = "\(.*\)"/\1/p' Cargo.toml)
fi
[ ${#TARGETS[@]} -gt 0 ] || { echo "fuzz/ci.sh: no [[bin]] targets in fuzz/Cargo.toml" >&2; exit 2; }

if [ -z "${FUZZ_TARGET_DIR:-}" ]; then
    root_target=$(cd .. && cargo metadata --format-version 1 --no-deps \
        | python3 -c 'import json, sys; print(json.load(sys.stdin)["target_directory"])')
    FUZZ_TARGET_DIR=$root_target/fuzz-ci
fi
HOST=$(rustc -vV | sed -n 's/^host: //p')
OUT=${FUZZ_OUT:-$(mktemp -d /tmp/haunts-fuzz.XXXXXX)}

export RUSTFLAGS="--cfg fuzzing -Cpasses=sancov-module \
-Cllvm-args=-sanitizer-coverage-level=4 \
-Cllvm-args=-sanitizer-coverage-inline-8bit-counters \
-Cllvm-args=-sanitizer-coverage-pc-table \
-Cllvm-args=-sanitizer-coverage-trace-compares \
-Cllvm-args=-sanitizer-coverage-stack-depth \
-Cdebug-assertions -Coverflow-checks"
echo "fuzz/ci.sh: building ${#TARGETS[@]} targets into $FUZZ_TARGET_DIR" >&2
bins=()
for t in "${TARGETS[@]}"; do bins+=(--bin "$t"); done
cargo build --release --locked --target "$HOST" --target-dir "$FUZZ_TARGET_DIR" "${bins[@]}"
BIN=$FUZZ_TARGET_DIR/$HOST/release

failed=()
for t in "${TARGETS[@]}"; do
    corpus=$OUT/$t/corpus
    mkdir -p "$corpus"
    dict=()
    case $t in
        map_yaml) dict=(-dict=dicts/map_yaml.dict) ;;
        carmen) dict=(-dict=dicts/carmen.dict) ;;
    esac
    log=$OUT/$t/log
    if "$BIN/$t" "$corpus" "seeds/$t" "${dict[@]}" -max_total_time="$SECONDS_PER" \
        -rss_limit_mb=2048 -timeout=10 -max_len=65536 -print_final_stats=1 \
        -seed="${FUZZ_SEED:-1}" \
        -artifact_prefix="$OUT/$t/" >"$log" 2>&1; then
        runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log")
        echo "fuzz $t: ${runs:-?} inputs in ${SECONDS_PER} s, no crash" >&2
    else
        echo "fuzz $t: FAILED; its log ($log) ends:" >&2
        tail -30 "$log" >&2
        failed+=("$t")
    fi
done

if [ ${#failed[@]} -gt 0 ]; then
    echo "fuzz/ci.sh: ${#failed[@]} target(s) failed: ${failed[*]}; inputs kept in $OUT" >&2
    exit 1
fi
[ -n "${FUZZ_OUT:-}" ] || rm -rf "$OUT"
echo "fuzz/ci.sh: ${#TARGETS[@]} targets ran ${SECONDS_PER} s each, no crash" >&2
