#!/usr/bin/env bash
# A repeatable attack on the examples and the `haunts` CLI (issue 22, item 7).
#
# Builds the release examples (eval_tracking, hypertime, ta_map, carmen_map, bag_map,
# pipeline) and the `haunts` CLI once, generates bad inputs of every class of issue 22 —
# absurd numbers (1e300, 1e7, usize::MAX), NaN/inf fields, empty and garbage files,
# truncated files, single-line corruptions of each real file, missing optional files, huge
# resolutions, times in milliseconds, outliers and extents within the cell budget whose work
# is over the work budget — runs each under `timeout 60` and `prlimit --as=4G`,
# and classifies each run:
#   panic   exit 101 or "panicked" on stderr
#   hang    killed by the timeout
#   abort   killed by a signal (an allocation over the memory limit aborts)
#   silent  exit 0 where an error was due, or exit 0 with null/NaN in the JSON, a perfect
#           score on garbage, or a corrupted line neither refused nor counted as skipped
#   ok      a typed error with a non-zero exit, or a result that states its skips
# Prints the table and exits non-zero when any class but ok is non-zero. Not run by CI
# (minutes of runs); usage: fuzz/hostile.sh [WORKDIR]   (HOSTILE_LINES=N corruptions per
# file and kind, default 2; CARGO_TARGET_DIR is honoured).
set -u
ROOT=$(cd "$(dirname "$0")/.." && pwd)
DATA=${HAUNTS_DATA:-$ROOT/../shared/data}
WORK=${1:-$(mktemp -d /tmp/hostile.XXXXXX)}
LINES_PER=${HOSTILE_LINES:-2}
TARGET=${CARGO_TARGET_DIR:-$ROOT/target}
mkdir -p "$WORK"
cd "$ROOT" || exit 2

echo "building (release) ..." >&2
cargo build --release -q -p haunts --examples || exit 2
cargo build --release -q -p haunts-cli || exit 2
EX=$TARGET/release/examples
CLI=$TARGET/release/haunts

# ------------------------------------------------------------------ inputs
IN=$WORK/in
rm -rf "$IN" "$WORK/out" "$WORK/log"; mkdir -p "$IN" "$WORK/out" "$WORK/log"
python3 - "$DATA" "$IN" "$LINES_PER" <<'PY'
import gzip, os, random, shutil, sys
data, out, per = sys.argv[1], sys.argv[2], int(sys.argv[3])
rng = random.Random(22)
LT = os.path.join(data, "leg_tracker", "general_tracking_moving_1")

def lines(path, n=None, gz=False):
    op = gzip.open if gz else open
    with op(path, "rt") as f:
        out_ = []
        for i, l in enumerate(f):
            if n is not None and i >= n:
                break
            out_.append(l)
    return out_

def put(path, text):
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "w" if isinstance(text, str) else "wb") as f:
        f.write(text)

# Cut-down real files.
seq = {
    "scans.txt": lines(os.path.join(LT, "scans.txt"), 320),
    "odom.txt": lines(os.path.join(LT, "odom.txt"), 6000),
    "static_tf.txt": lines(os.path.join(LT, "static_tf.txt")),
    "ground_truth_people.txt": lines(os.path.join(LT, "ground_truth_people.txt")),
}
people = lines(os.path.join(data, "people", "2017_05_25.txt"), 3000)
test = lines(os.path.join(data, "people", "2017_05_26.txt"), 1500)
obsmat = lines(os.path.join(data, "trajectories", "eth", "seq_eth", "obsmat.txt"), 1500)
mapxml = open(os.path.join(data, "trajectories", "eth", "seq_eth", "map.xml")).read()
carmen = lines(os.path.join(data, "carmen", "intel-corrected.log.gz"), 1500, gz=True)

cases = []  # (name, expectation, kind): expectation fail | skip | any

def seq_dir(name, files, expect):
    d = os.path.join(out, "seq", name)
    for f, ls in files.items():
        if ls is not None:
            put(os.path.join(d, f), "".join(ls))
    cases.append(("eval_tracking", name, expect))

def replace_field(line, i, value):
    w = line.split()
    if i < len(w):
        w[i] = value
    return " ".join(w) + "\n"

# The field of each file that must be a finite number.
NUMERIC = {"scans.txt": 0, "odom.txt": 0, "static_tf.txt": 2, "ground_truth_people.txt": 0,
           "people": 0, "obsmat": 0, "carmen": None}

def corruptions(ls, numeric):
    """(kind, expectation, lines) single-line corruptions of a real file."""
    body = [i for i, l in enumerate(ls) if l.strip() and not l.startswith("#")]
    out_ = []
    for kind in ["nan", "inf", "garbage", "truncated", "1e300", "1e7", "-1e7"]:
        for _ in range(per):
            i = rng.choice(body)
            c = list(ls)
            if kind in ("nan", "inf", "1e300", "1e7", "-1e7"):
                if numeric is None:
                    w = c[i].split(); j = rng.randrange(1, len(w)) if len(w) > 1 else 0
                    c[i] = replace_field(c[i], j, kind)
                else:
                    c[i] = replace_field(c[i], numeric, kind)
            elif kind == "garbage":
                c[i] = "@@garbage\x01 line@@ x\n"
            else:
                c[i] = c[i][: max(1, len(c[i]) // 2)].rstrip() + "\n"
            expect = "skip" if kind in ("nan", "inf", "garbage") and numeric is not None else "any"
            out_.append((f"{kind}-l{i + 1}", expect, c))
    return out_

# ---- eval_tracking: folders of text files
seq_dir("real-cut", seq, "any")
seq_dir("no-static-tf", {**seq, "static_tf.txt": None}, "any")
seq_dir("no-odom", {**seq, "odom.txt": None, "static_tf.txt": None}, "any")
seq_dir("empty-scans", {**seq, "scans.txt": []}, "fail")
seq_dir("garbage-scans", {**seq, "scans.txt": ["garbage %d\n" % i for i in range(50)]}, "fail")
seq_dir("empty-truth", {**seq, "ground_truth_people.txt": []}, "fail")
seq_dir("garbage-truth", {**seq, "ground_truth_people.txt": ["a b c d\n"] * 20}, "fail")
seq_dir("no-scans", {**seq, "scans.txt": None}, "fail")
seq_dir("truncated-scans", {**seq, "scans.txt": seq["scans.txt"][:200] + [seq["scans.txt"][200][:777]]}, "any")
ms = [replace_field(l, 0, "%.3f" % (float(l.split()[0]) * 1000)) if not l.startswith("#") else l
      for l in seq["ground_truth_people.txt"]]
seq_dir("truth-in-ms", {**seq, "ground_truth_people.txt": ms}, "fail")
for f in ["scans.txt", "odom.txt", "static_tf.txt", "ground_truth_people.txt"]:
    for kind, expect, c in corruptions(seq[f], NUMERIC[f]):
        seq_dir(f"{f[:-4]}-{kind}", {**seq, f: c}, expect)

# ---- hypertime: train/test detection files
def det(name, train, testl, expect, args=""):
    put(os.path.join(out, "det", name, "train.txt"), "".join(train))
    put(os.path.join(out, "det", name, "test.txt"), "".join(testl))
    put(os.path.join(out, "det", name, "args"), args)
    cases.append(("hypertime", name, expect))

det("real-cut", people, test, "any")
det("empty-train", [], test, "fail")
det("empty-test", people, [], "fail")
det("garbage-test", people, ["garbage\n"] * 100, "fail")
det("garbage-train", ["x y z\n"] * 100, test, "fail")
det("outlier-1e7", people + ["1495706022.77 1e7 1e7 0 0 WP1\n"], test, "skip")
det("outlier-1e300", people + ["1495706022.77 1e300 0 0 0 WP1\n"], test, "skip")
# One far detection (issue 44): skipped and counted by the bounds rule, not a scoring grid or
# an hourly strip over the work budget.
det("outlier-1e5", people + ["1495706022.77 1e5 0 0 0 WP1\n"], test, "skip")
det("outlier-1e7-grid-2", people + ["1495706022.77 1e7 0 0 0 WP1\n"], test, "skip", "--grid 2")
det("test-outlier-1e4", people, test + [test[0].split()[0] + " 1e4 0 0 0 WP1\n"], "skip")
det("times-in-ms", [replace_field(l, 0, "%.0f" % (float(l.split()[0]) * 1000)) for l in people], test, "any")
det("cols-usize-max", people, test, "fail", "--cols 18446744073709551615,1,2")
det("grid-tiny", people, test, "fail", "--grid 0.00001")
det("grid-nan", people, test, "fail", "--grid nan")
det("grid-1e300", people, test, "fail", "--grid 1e300")
det("time-step-0", people, test, "fail", "--time-step 0")
det("clusters-huge", people, test, "fail", "--clusters 18446744073709551615")
det("periods-nan", people, test, "fail", "--periods nan")
for kind, expect, c in corruptions(people, 0):
    det(f"train-{kind}", c, test, expect)
for kind, expect, c in corruptions(test, 0):
    det(f"test-{kind}", people, c, expect)

# ---- ta_map: obsmat + map.xml
def ta(name, obs, xml, expect, args=""):
    d = os.path.join(out, "ta", name)
    put(os.path.join(d, "obsmat.txt"), "".join(obs))
    if xml is not None:
        put(os.path.join(d, "map.xml"), xml)
    put(os.path.join(d, "args"), args)
    cases.append(("ta_map", name, expect))

ta("real-cut", obsmat, mapxml, "any")
ta("no-map-xml", obsmat, None, "any")
ta("empty", [], mapxml, "fail")
ta("garbage", ["garbage\n"] * 50, mapxml, "fail")
ta("map-xml-garbage", obsmat, "<<<\x00garbage", "any")
ta("map-xml-1e300", obsmat, '<Map>\n<Line x1="0" y1="0" x2="1e300" y2="1e300"/>\n</Map>\n', "any")
ta("map-xml-pole-1e300", obsmat, '<Map>\n<Circle x="0" y="0" radius="1e300"/>\n</Map>\n', "any")
ta("map-xml-no-radius", obsmat, '<Map>\n<Circle x="0" y="0"/>\n</Map>\n', "fail")
ta("map-xml-nan", obsmat, '<Map>\n<Line x1="nan" y1="0" x2="1" y2="1"/>\n</Map>\n', "any")
ta("resolution-tiny", obsmat, mapxml, "fail", "--resolution 0.00001")
ta("resolution-nan", obsmat, mapxml, "fail", "--resolution nan")
ta("resolution-0", obsmat, mapxml, "fail", "--resolution 0")
ta("margin-1e300", obsmat, mapxml, "fail", "--margin 1e300")
# A 10 km map within the cell budget: its confidence raster is over the work budget.
ta("margin-500", obsmat, mapxml, "fail", "--margin 500")
ta("min-samples-max", obsmat, mapxml, "fail", "--min-samples 18446744073709551615")
ta("outlier-1e7", obsmat + ["   1.0e+04   9.9e+01   1.0e+07   0   1.0e+07   0   0   0\n"], mapxml, "skip")
for kind, expect, c in corruptions(obsmat, 0):
    ta(f"obsmat-{kind}", c, mapxml, expect)

# ---- carmen_map
def cm(name, ls, expect, args="", raw=None):
    d = os.path.join(out, "carmen", name)
    put(os.path.join(d, "log.log"), raw if raw is not None else "".join(ls))
    put(os.path.join(d, "args"), args)
    cases.append(("carmen_map", name, expect))

cm("real-cut", carmen, "any")
cm("empty", [], "fail")
cm("garbage", ["garbage line\n"] * 100, "fail")
cm("binary", None, "fail", raw=bytes(rng.randrange(256) for _ in range(5000)))
cm("resolution-tiny", carmen, "fail", "--resolution 0.0001")
cm("resolution-nan", carmen, "fail", "--resolution nan")
cm("resolution-1e300", carmen, "fail", "--resolution 1e300")
pose = [l for l in carmen if l.startswith("FLASER")][5].split()
n = int(pose[1]); pose[2 + n] = "1e5"
cm("pose-1e5", carmen + [" ".join(pose) + "\n"], "skip")
pose[2 + n] = "1e300"
cm("pose-1e300", carmen + [" ".join(pose) + "\n"], "skip")
for kind, expect, c in corruptions(carmen, None):
    cm(f"line-{kind}", c, expect)

# ---- bag_map and haunts day: the real MCAP, cut and broken
mcap = open(os.path.join(data, "leg_tracker", "general_tracking_moving_1.mcap"), "rb").read()
for name, blob, expect in [("real", mcap, "any"), ("truncated-half", mcap[: len(mcap) // 2], "any"),
                           ("truncated-1k", mcap[:1024], "fail"), ("empty", b"", "fail"),
                           ("garbage", bytes(rng.randrange(256) for _ in range(20000)), "fail"),
                           ("flipped", mcap[:500000] + bytes([mcap[500000] ^ 0xFF]) + mcap[500001:], "any")]:
    put(os.path.join(out, "bag", name + ".mcap"), blob)
    cases.append(("bag_map", name, expect))
    cases.append(("day", name, expect))
cases.append(("bag_map", "resolution-tiny", "fail"))
cases.append(("bag_map", "resolution-nan", "fail"))

with open(os.path.join(out, "cases.txt"), "w") as f:
    for c in cases:
        f.write("\t".join(c) + "\n")
PY
[ -s "$IN/cases.txt" ] || { echo "no inputs generated" >&2; exit 2; }

# Hand-written argument attacks (program, name, expectation, arguments...).
cat >> "$IN/cases.txt" <<'CASES'
pipeline	days-usize-max	fail	--days 18446744073709551615
pipeline	days-0	fail	--days 0
pipeline	days-garbage	fail	--days abc
pipeline	days-negative	fail	--days -1
pipeline	seed-garbage	fail	--seed x
sim	days-usize-max	fail	sim --days 18446744073709551615
sim	days-0	fail	sim --days 0
sim	days-garbage	fail	sim --days 1e300
merge	garbage	fail	merge @garbage
merge	empty	fail	merge @empty
merge	missing	fail	merge @missing
maps	garbage	fail	maps @garbage
maps	empty	fail	maps @empty
maps	missing	fail	maps @missing
day	missing-folder	fail	day @missing
day	out-no-dir	fail	day @real-out-no-dir
CASES

# ------------------------------------------------------------------ runs
declare -A COUNT=([tried]=0 [panic]=0 [hang]=0 [abort]=0 [silent]=0 [ok]=0)
FINDINGS=$WORK/findings.txt; : > "$FINDINGS"
head -c 20000 /dev/urandom > "$IN/garbage.bin"; : > "$IN/empty.bin"

run() { # program name expectation command...
    local prog=$1 name=$2 expect=$3; shift 3
    local log=$WORK/log/$prog-$name rc class
    timeout 60 prlimit --as=4294967296 -- "$@" > "$log.out" 2> "$log.err" < /dev/null
    rc=$?
    local all; all=$(cat "$log.out" "$log.err")
    if [ $rc -eq 101 ] || grep -q "panicked" "$log.err"; then class=panic
    elif [ $rc -eq 124 ]; then class=hang
    elif [ $rc -gt 128 ] || grep -q "memory allocation of" "$log.err"; then class=abort
    elif [ $rc -eq 0 ]; then
        class=ok
        if [ "$expect" = fail ]; then class=silent; fi
        # null / NaN / inf as JSON values, or a perfect score, are nonsense on hostile input.
        if tail -n 1 "$log.out" | grep -Eq '(:|\[|,) *(null|NaN|-?inf|Infinity)\b'; then class=silent; fi
        if [ "$expect" = skip ] && ! grep -Eiq 'skip[a-z_ ]*"?[:=]? *[1-9]|[1-9][0-9]* (lines? )?skipped|skipped[^0-9]{0,40}[1-9]' <<< "$all"; then class=silent; fi
    else class=ok
    fi
    COUNT[tried]=$((COUNT[tried] + 1)); COUNT[$class]=$((COUNT[$class] + 1))
    if [ $class != ok ]; then
        printf '%s\t%s\t%s\texit %s\t%s\n' "$class" "$prog" "$name" "$rc" \
            "$(tail -c 300 "$log.err" | tr '\n' ' ' | tail -c 200) | $(tail -n 1 "$log.out" | head -c 200)" >> "$FINDINGS"
    fi
}

O=$WORK/out
while IFS=$'\t' read -r prog name expect rest; do
    case $prog in
    eval_tracking) run "$prog" "$name" "$expect" "$EX/eval_tracking" "$IN/seq/$name" ;;
    hypertime) d=$IN/det/$name
        # shellcheck disable=SC2046
        run "$prog" "$name" "$expect" "$EX/hypertime" $(cat "$d/args") --train "$d/train.txt" --test "$d/test.txt" --out "$O/ht-$name" ;;
    ta_map) d=$IN/ta/$name
        # shellcheck disable=SC2046
        run "$prog" "$name" "$expect" "$EX/ta_map" --trajectories "$d/obsmat.txt" $(cat "$d/args") --out "$O/ta-$name" ;;
    carmen_map) d=$IN/carmen/$name
        # shellcheck disable=SC2046
        run "$prog" "$name" "$expect" "$EX/carmen_map" "$d/log.log" $(cat "$d/args") --out "$O/cm-$name" ;;
    bag_map) case $name in
        resolution-tiny) run "$prog" "$name" "$expect" "$EX/bag_map" "$IN/bag/real.mcap" --resolution 0.0001 --out "$O/bm-$name" ;;
        resolution-nan) run "$prog" "$name" "$expect" "$EX/bag_map" "$IN/bag/real.mcap" --resolution nan --out "$O/bm-$name" ;;
        *) run "$prog" "$name" "$expect" "$EX/bag_map" "$IN/bag/$name.mcap" --out "$O/bm-$name" ;;
        esac ;;
    pipeline)
        # shellcheck disable=SC2086
        run "$prog" "$name" "$expect" "$EX/pipeline" $rest --out "$O/pl-$name" ;;
    day) case $name in
        missing-folder) run cli-day "$name" "$expect" "$CLI" day "$IN/nothing-here" -o "$O/d.haunts" ;;
        real-out-no-dir) run cli-day "$name" "$expect" "$CLI" day "$IN/bag/real.mcap" -o "$O/no/such/dir/d.haunts" ;;
        *) run cli-day "$name" "$expect" "$CLI" day "$IN/bag/$name.mcap" -o "$O/day-$name.haunts" ;;
        esac ;;
    sim)
        # shellcheck disable=SC2086
        run cli-sim "$name" "$expect" "$CLI" $rest -o "$O/sim-$name" ;;
    merge|maps)
        f=${rest##* }; f=${f#@}
        case $f in garbage) p=$IN/garbage.bin ;; empty) p=$IN/empty.bin ;; *) p=$IN/missing.haunts ;; esac
        if [ "$prog" = merge ]; then run cli-merge "$name" "$expect" "$CLI" merge "$p" -o "$O/lib-$name.haunts"
        else run cli-maps "$name" "$expect" "$CLI" maps "$p" -o "$O/maps-$name"; fi ;;
    esac
done < "$IN/cases.txt"

# A day artifact and a library made by the CLI from the real recording, then broken.
if [ -s "$O/day-real.haunts" ]; then
    python3 - "$O/day-real.haunts" "$IN" <<'PY'
import sys
b = open(sys.argv[1], "rb").read()
d = sys.argv[2]
open(d + "/day-truncated.haunts", "wb").write(b[: len(b) // 2])
open(d + "/day-flipped.haunts", "wb").write(b[:100] + bytes([b[100] ^ 1]) + b[101:])
open(d + "/day-newer.haunts", "wb").write(b[:8] + b"\x63\x00\x00\x00" + b[12:])
PY
    for v in truncated flipped newer; do
        run cli-merge "day-$v" fail "$CLI" merge "$IN/day-$v.haunts" -o "$O/lib-$v.haunts"
    done
    run cli-merge real any "$CLI" merge "$O/day-real.haunts" -o "$O/lib.haunts"
    if [ -s "$O/lib.haunts" ]; then
        head -c 300 "$O/lib.haunts" > "$IN/lib-truncated.haunts"
        run cli-maps lib-truncated fail "$CLI" maps "$IN/lib-truncated.haunts" -o "$O/maps-trunc"
        run cli-maps real any "$CLI" maps "$O/lib.haunts" -o "$O/maps-real"
    fi
fi

printf '\n| inputs tried | panics | hangs | aborts | silent | ok |\n|---:|---:|---:|---:|---:|---:|\n'
printf '| %d | %d | %d | %d | %d | %d |\n\n' "${COUNT[tried]}" "${COUNT[panic]}" "${COUNT[hang]}" \
    "${COUNT[abort]}" "${COUNT[silent]}" "${COUNT[ok]}"
if [ -s "$FINDINGS" ]; then echo "findings ($FINDINGS):"; cat "$FINDINGS"; fi
echo "inputs and logs: $WORK"
[ $((COUNT[panic] + COUNT[hang] + COUNT[abort] + COUNT[silent])) -eq 0 ]
