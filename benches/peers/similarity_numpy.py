"""Benchmark peer: the similarity matrix of haunts-similarity, the straightforward NumPy/SciPy way.

The input is the one of the Rust criterion benchmark `similarity_matrix/70_maps_400x400`
(similarity/benches/matrix.rs): 70 maps of 400x400 cells, a room with two inner walls and ten
L-shaped pieces of furniture placed by a SplitMix64 generator (layout seed = day % 7, jitter
seed = 1000 + day), rebuilt here bit for bit. The matrix is seed 000 III-C's distance-field
difference with ct = 10 cells: entry (x, y) sums, over the occupied cells of map y, the
Euclidean distance in cells to the nearest occupied cell of map x when it is strictly greater
than ct; the diagonal is zero. Computed with one scipy.ndimage.distance_transform_edt per map,
each map's occupied cells gathered once (`np.flatnonzero`), and per ordered pair a gather of
x's distances at y's cells and a masked sum of those (no full-mask AND per pair).

Times the whole matrix (distance transforms included) with time.perf_counter: one warm-up, then
`--runs` runs. Checks its checksum (printed to stderr) against the one the Rust bench prints
when `--rust-checksum` and friends are given, exiting with status 1 on a mismatch, and prints
one JSON line to stdout.

Usage (from the project root): python3 benches/peers/similarity_numpy.py [--runs N]
    [--rust-checksum S --rust-checksum-d2 D --rust-terms T --rust-occupied O]
"""

import argparse
import json
import statistics
import sys
import time

import numpy as np
import scipy
from scipy import ndimage

from splitmix import SplitMix64

N_MAPS = 70
SIZE = 400
CUTOFF = 10.0  # ct in cells: 0.5 m at 0.05 m
# Relative tolerance of the float checksum: numpy sums each entry pairwise, the Rust code left
# to right, so the last bits of an entry may differ. The exact checks are on d2 and the terms.
REL_TOL = 1e-12


def day(index):
    """The occupied mask of day `index`, indexed [row, col] (row 0 = bottom, as the Rust grid)."""
    n = SIZE
    m = np.zeros((n, n), dtype=bool)
    m[0, :] = m[n - 1, :] = m[:, 0] = m[:, n - 1] = True
    inner = np.arange(n) % 100 < 70
    m[200, inner] = True  # Cell::new(i, 200): row 200
    m[inner, 150] = True  # Cell::new(150, i): column 150
    layout, jitter = SplitMix64(index % 7), SplitMix64(1000 + index)
    for _ in range(10):
        c0 = layout.range(10, 360)
        r0 = layout.range(10, 360)
        dc = jitter.range(0, 3)
        dr = jitter.range(0, 3)
        m[r0 + dr, c0 + dc:c0 + dc + 30] = True
        m[r0 + dr:r0 + dr + 30, c0 + dc] = True
    return m


def similarity_matrix(masks):
    """The directed differences, entry [x, y] = occupied cells of y in the distance field of x.

    Each map's occupied cells are gathered once (flat indices, row-major); a pair then sums
    the far-away entries of x's flattened field at y's cells, with no full-grid work per pair."""
    fields = [ndimage.distance_transform_edt(~m) for m in masks]
    cells = [np.flatnonzero(m) for m in masks]
    n = len(masks)
    out = np.zeros((n, n))
    for x in range(n):
        flat = fields[x].ravel()
        for y in range(n):
            if x != y:
                v = flat[cells[y]]
                out[x, y] = v[v > CUTOFF].sum()
    return out, fields


def checksums(matrix, fields, masks):
    """Sum of the off-diagonal entries (row-major, left to right, as the Rust bench), the exact
    sum of their squared distances and the number of summed cells."""
    n = len(masks)
    total = 0.0
    for x in range(n):
        for y in range(n):
            if x != y:
                total += float(matrix[x, y])
    sum_d2 = terms = 0
    for x in range(n):
        d2 = np.rint(fields[x] * fields[x]).astype(np.int64)
        far = fields[x] > CUTOFF
        for y in range(n):
            if x != y:
                sel = masks[y] & far
                sum_d2 += int(d2[sel].sum())
                terms += int(np.count_nonzero(sel))
    return total, sum_d2, terms


def left_to_right_entries(fields, masks):
    """Each entry summed left to right in row-major cell order, as the Rust code sums it."""
    n = len(masks)
    out = np.zeros((n, n))
    for x in range(n):
        far = fields[x] > CUTOFF
        for y in range(n):
            if x != y:
                v = fields[x][masks[y] & far]
                out[x, y] = np.cumsum(v)[-1] if v.size else 0.0
    return out


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--runs", type=int, default=5, help="number of timed runs (default 5)")
    parser.add_argument("--rust-checksum", type=float, help="sum_offdiag printed by the Rust bench")
    parser.add_argument("--rust-checksum-d2", type=int, help="sum_offdiag_d2 printed by the Rust bench")
    parser.add_argument("--rust-terms", type=int, help="terms printed by the Rust bench")
    parser.add_argument("--rust-occupied", type=int, help="occupied printed by the Rust bench")
    args = parser.parse_args()
    if args.runs < 1:
        parser.error("--runs must be at least 1")

    masks = [day(i) for i in range(N_MAPS)]
    occupied = int(sum(np.count_nonzero(m) for m in masks))

    times = []
    matrix, fields = similarity_matrix(masks)  # warm-up, and the result checked below
    for _ in range(args.runs):
        t0 = time.perf_counter()
        similarity_matrix(masks)
        times.append(time.perf_counter() - t0)

    checksum, checksum_d2, terms = checksums(matrix, fields, masks)
    # The same checksum with every entry summed in the Rust order: equal to the bit.
    checksum_ltr = checksums(left_to_right_entries(fields, masks), fields, masks)[0]
    print(f"numpy:  sum_offdiag={checksum!r} sum_offdiag_d2={checksum_d2} terms={terms} "
          f"occupied={occupied} (entries summed left to right: {checksum_ltr!r})", file=sys.stderr)

    problems = []
    if args.rust_checksum is not None:
        print(f"rust:   sum_offdiag={args.rust_checksum!r} sum_offdiag_d2={args.rust_checksum_d2} "
              f"terms={args.rust_terms} occupied={args.rust_occupied}", file=sys.stderr)
        rel = abs(checksum - args.rust_checksum) / abs(args.rust_checksum)
        print(f"        relative difference of sum_offdiag: {rel:.3g} (tolerance {REL_TOL:g}); "
              f"left to right: {'bitwise equal' if checksum_ltr == args.rust_checksum else 'DIFFERENT'}",
              file=sys.stderr)
        if rel > REL_TOL:
            problems.append(f"sum_offdiag {checksum!r} != rust {args.rust_checksum!r}")
    for name, mine, rust in [("sum_offdiag_d2", checksum_d2, args.rust_checksum_d2),
                             ("terms", terms, args.rust_terms),
                             ("occupied", occupied, args.rust_occupied)]:
        if rust is not None and mine != rust:
            problems.append(f"{name} {mine} != rust {rust}")
    if problems:
        print("error: the NumPy matrix differs from the Rust one: " + "; ".join(problems),
              file=sys.stderr)
        sys.exit(1)

    print(json.dumps({
        "tool": "numpy+scipy",
        "median_s": statistics.median(times),
        "min_s": min(times),
        "runs": args.runs,
        "checksum": checksum,
        "checksum_d2": checksum_d2,
        "terms": terms,
        "occupied": occupied,
        "maps": N_MAPS,
        "shape": [SIZE, SIZE],
        "numpy": np.__version__,
        "scipy": scipy.__version__,
        "threads": 1,
    }))


if __name__ == "__main__":
    main()
