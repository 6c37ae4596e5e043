"""Benchmark peers: exact EDTs (SciPy, OpenCV, `edt`) on the 4000x4000 tiled willow map.

The input is the one of the Rust criterion benchmark `edt/willow_tiled_4000`: the willow
obstacle mask (cells occupied under ROS 1 map_server, row 0 = bottom row of the image) tiled
with `np.tile(mask, (ceil(4000/h), ceil(4000/w)))[:4000, :4000]`. Every tool computes the
exact Euclidean distance of every cell to the nearest obstacle cell:

- `scipy`: `scipy.ndimage.distance_transform_edt(~mask)`, float64 distances; with indices,
  `return_indices=True` (the nearest obstacle's row and column). One thread only.
- `opencv`: `cv2.distanceTransform(free, cv2.DIST_L2, cv2.DIST_MASK_PRECISE)` on the uint8
  image free = 1, obstacle = 0 (Felzenszwalb-Huttenlocher, float32 distances), threads set
  with `cv2.setNumThreads`. OpenCV offers NO exact indices: `distanceTransformWithLabels`
  ignores `DIST_MASK_PRECISE` and returns the approximate 5x5-mask distances, so it is not
  timed "with indices".
- `edt`: the `edt` package's `edt.edtsq(~mask, parallel=threads)` (squared distances as
  float32, exact integers below 2^24), threads by its `parallel=`. It offers NO indices.

Each (tool, indices, threads) is one warm-up call then `--runs` timed calls
(time.perf_counter), the variants interleaved run by run so that load from other processes
falls on all of them alike. With `--check FILE` (the haunts squared distances, little-endian
u32, row-major, row 0 = bottom: what `cargo bench --bench edt` writes when
HAUNTS_EDT_D2_OUT is set) every tool's result is first checked EXACTLY against haunts':
SciPy's and OpenCV's distances squared and rounded to the nearest integer, and `edt`'s
float32 squares as integers, must equal haunts' u32 at every cell, and the distances must lie
within float rounding of sqrt(d2) (SciPy: 1e-12 relative, float64; OpenCV: 2^-22 relative,
float32); SciPy's indices must name an obstacle cell at exactly that squared distance. Exits
with status 1 on any difference.

Usage (from the project root): python3 benches/peers/edt_scipy.py [--runs N]
    [--tools scipy,opencv,edt] [--threads 1,2] [--with-indices] [--check FILE]
"""

import argparse
import json
import math
import os
import statistics
import sys
import time

import numpy as np
import scipy
from scipy import ndimage

from rosmap import DEFAULT_DATA_DIR, load_map, obstacle_mask

SIZE = 4000
TOOLS = ("scipy", "opencv", "edt")


def tiled_willow(data_dir):
    """The SIZE x SIZE benchmark mask (True = obstacle), row 0 = bottom."""
    mask = obstacle_mask(load_map(data_dir, "willow"))
    h, w = mask.shape
    return np.ascontiguousarray(np.tile(mask, (math.ceil(SIZE / h), math.ceil(SIZE / w)))[:SIZE, :SIZE])


def variants(tools, threads, with_indices, mask):
    """(name, tool, indices, threads, call) for every timed variant; `call()` returns the
    result the check reads: ("d", distances), ("d2", squared distances) or ("di", (d, idx))."""
    free = ~mask
    out = []
    if "scipy" in tools:
        out.append(("scipy", "scipy", False, 1, lambda: ("d", ndimage.distance_transform_edt(free))))
        if with_indices:
            out.append(("scipy_indices", "scipy", True, 1,
                        lambda: ("di", ndimage.distance_transform_edt(free, return_indices=True))))
    if "opencv" in tools:
        import cv2
        free_u8 = np.ascontiguousarray(free.astype(np.uint8))
        for t in threads:
            def call(t=t):
                cv2.setNumThreads(t)
                return ("d", cv2.distanceTransform(free_u8, cv2.DIST_L2, cv2.DIST_MASK_PRECISE))
            out.append((f"opencv_{t}t", "opencv", False, t, call))
    if "edt" in tools:
        import edt
        for t in threads:
            out.append((f"edt_{t}t", "edt", False, t,
                        lambda t=t: ("d2", edt.edtsq(free, black_border=False, parallel=t))))
    return out


def check(name, result, d2_ref, mask):
    """Problems of one tool's result against haunts' squared distances (empty if exact)."""
    kind, value = result
    problems = []
    if kind == "di":
        d, idx = value
    elif kind == "d":
        d, idx = value, None
    else:
        d, idx = None, None
    if d is None:
        if not np.array_equal(value.astype(np.float64), value.astype(np.float64).round()):
            problems.append(f"{name}: squared distances not integers")
        d2 = value.astype(np.int64)
    else:
        d64 = d.astype(np.float64)
        d2 = np.rint(d64 * d64).astype(np.int64)
        exact = np.sqrt(d2_ref.astype(np.float64))
        rel = 1e-12 if d.dtype == np.float64 else 2.0 ** -22
        err = np.abs(d64 - exact) - rel * exact
        if err.max() > 0:
            problems.append(f"{name}: a distance is {np.abs(d64 - exact).max():.3g} from sqrt(d2)")
    diff = np.count_nonzero(d2 != d2_ref)
    if diff:
        problems.append(f"{name}: {diff} cells differ from haunts' squared distances")
    if idx is not None:
        rows, cols = idx
        if not mask[rows, cols].all():
            problems.append(f"{name}: an index is not an obstacle")
        rr, cc = np.indices(mask.shape)
        nd2 = (rows - rr).astype(np.int64) ** 2 + (cols - cc).astype(np.int64) ** 2
        if not np.array_equal(nd2, d2_ref):
            problems.append(f"{name}: an index is not at the nearest obstacle's distance")
    return problems


def versions(tools):
    v = {"numpy": np.__version__, "scipy": scipy.__version__}
    if "opencv" in tools:
        import cv2
        v["opencv"] = cv2.__version__
    if "edt" in tools:
        from importlib.metadata import version
        v["edt"] = version("edt")
    return v


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--runs", type=int, default=15, help="number of timed runs (default 15)")
    parser.add_argument("--tools", default=",".join(TOOLS),
                        help="comma-separated subset of scipy,opencv,edt (default: all)")
    parser.add_argument("--threads", default=None,
                        help="comma-separated thread counts for opencv and edt (default: 1 and the CPU count)")
    parser.add_argument("--with-indices", action="store_true",
                        help="also time the variants that return nearest-obstacle indices (scipy)")
    parser.add_argument("--check", metavar="FILE",
                        help="haunts' squared distances (u32 LE) to check every result against")
    parser.add_argument("--data-dir", default=DEFAULT_DATA_DIR,
                        help="directory of the map YAML and PGM files (default: ../shared/data/maps)")
    args = parser.parse_args()
    if args.runs < 1:
        parser.error("--runs must be at least 1")
    tools = [t for t in args.tools.split(",") if t]
    if any(t not in TOOLS for t in tools):
        parser.error(f"--tools: choose from {','.join(TOOLS)}")
    cpus = os.cpu_count() or 1
    threads = sorted({int(t) for t in args.threads.split(",")} if args.threads else {1, cpus})

    mask = tiled_willow(args.data_dir)
    runs = variants(tools, threads, args.with_indices, mask)
    problems = []
    d2_ref = None
    if args.check:
        d2_ref = np.fromfile(args.check, dtype="<u4").astype(np.int64)
        if d2_ref.size != mask.size:
            print(f"error: {args.check} holds {d2_ref.size} cells, expected {mask.size}", file=sys.stderr)
            sys.exit(1)
        d2_ref = d2_ref.reshape(mask.shape)
    times = {name: [] for name, *_ in runs}
    for name, _, _, _, call in runs:  # warm-up, and the result checked
        result = call()
        if d2_ref is not None:
            found = check(name, result, d2_ref, mask)
            print(f"check {name}: {'exact' if not found else '; '.join(found)}", file=sys.stderr)
            problems += found
        del result
    checked = d2_ref is not None
    if problems:
        print("error: a peer's EDT differs from haunts': " + " | ".join(problems), file=sys.stderr)
        sys.exit(1)
    for _ in range(args.runs):
        for name, _, _, _, call in runs:
            t0 = time.perf_counter()
            call()
            times[name].append(time.perf_counter() - t0)

    result = {
        "tools": tools,
        "versions": versions(tools),
        "shape": list(mask.shape),
        "obstacles": int(np.count_nonzero(mask)),
        "runs": args.runs,
        "cpus": cpus,
        "load_average": list(os.getloadavg()),
        "checked_against_haunts": checked,
        "results": [
            {"name": name, "tool": tool, "indices": indices, "threads": t,
             "median_s": statistics.median(times[name]), "min_s": min(times[name]),
             "max_s": max(times[name])}
            for name, tool, indices, t, _ in runs
        ],
    }
    print(json.dumps(result))


if __name__ == "__main__":
    main()
