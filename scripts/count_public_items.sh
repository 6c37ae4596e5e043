#!/usr/bin/env bash
# Counts the public items of every published crate from rustdoc JSON (issue 20's measure of
# the API's size): functions, struct fields, structs, enums, traits, constants, type
# aliases and modules whose visibility is public, one per item; `impl` blocks and `use`
# re-exports are left out (a re-exported item counts once, where it is defined).
# Needs a nightly toolchain (`-Z unstable-options --output-format json`).
#   bash scripts/count_public_items.sh [TARGET_DIR]   # default: target/public-items
set -euo pipefail
cd "$(dirname "$0")/.."
target=${1:-target/public-items}
rm -rf "$target/doc"
for manifest in */Cargo.toml Cargo.toml; do
    grep -q '^\[package\]' "$manifest" || continue
    grep -q '^publish = false' "$manifest" && continue
    grep -q '^\[lib\]\|src/lib.rs' "$manifest" || [ -f "$(dirname "$manifest")/src/lib.rs" ] || continue
    name=$(sed -n 's/^name = "\(.*\)"/\1/p' "$manifest" | head -1)
    CARGO_TARGET_DIR="$target" cargo +nightly rustdoc -q -p "$name" --lib -- \
        -Z unstable-options --output-format json
done
python3 - "$target/doc" <<'PY'
import glob, json, os, sys
total = 0
for path in sorted(glob.glob(os.path.join(sys.argv[1], "*.json"))):
    index = json.load(open(path))["index"]
    n = 0
    for item in index.values():
        if item.get("crate_id") != 0 or item.get("visibility") != "public":
            continue
        inner = item["inner"]
        kind = next(iter(inner)) if isinstance(inner, dict) else inner
        if kind not in ("impl", "use"):
            n += 1
    total += n
    print(f"{os.path.basename(path)[:-5]:<20} {n:>5}")
print(f"{'total':<20} {total:>5}")
PY
