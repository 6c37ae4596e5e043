"""Benchmark peer: scipy.ndimage.distance_transform_edt on the 4000x4000 tiled willow map.

The input is the one of the Rust criterion benchmark `edt/willow_tiled_4000`: the willow
obstacle mask (cells occupied under ROS 1 map_server, row 0 = bottom row of the image) tiled
with `np.tile(mask, (ceil(4000/h), ceil(4000/w)))[:4000, :4000]`. Times the float64 distance
transform of `~mask` (distances only, and with `--with-indices` also `return_indices=True`),
one warm-up call then `--runs` timed calls with time.perf_counter, and prints one JSON line.
scipy's EDT is single-threaded.

Usage (from the project root): python3 benches/peers/edt_scipy.py [--runs N] [--with-indices]
"""

import argparse
import json
import math
import statistics
import time

import numpy as np
import scipy
from scipy import ndimage

from rosmap import DEFAULT_DATA_DIR, load_map, obstacle_mask

SIZE = 4000


def tiled_willow(data_dir):
    """The SIZE x SIZE benchmark mask (True = obstacle), row 0 = bottom."""
    mask = obstacle_mask(load_map(data_dir, "willow"))
    h, w = mask.shape
    return np.ascontiguousarray(np.tile(mask, (math.ceil(SIZE / h), math.ceil(SIZE / w)))[:SIZE, :SIZE])


def time_runs(f, runs):
    """One warm-up call of `f`, then `runs` timed calls; returns median, min and max seconds."""
    f()
    times = []
    for _ in range(runs):
        t0 = time.perf_counter()
        f()
        times.append(time.perf_counter() - t0)
    return {"median_s": statistics.median(times), "min_s": min(times), "max_s": max(times)}


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--runs", type=int, default=15, help="number of timed runs (default 15)")
    parser.add_argument("--with-indices", action="store_true",
                        help="also time return_indices=True (reported under \"with_indices\")")
    parser.add_argument("--data-dir", default=DEFAULT_DATA_DIR,
                        help="directory of the map YAML and PGM files (default: ../shared/data/maps)")
    args = parser.parse_args()
    if args.runs < 1:
        parser.error("--runs must be at least 1")

    free = ~tiled_willow(args.data_dir)
    result = {
        "tool": "scipy.ndimage.distance_transform_edt",
        "scipy": scipy.__version__,
        "numpy": np.__version__,
        "shape": list(free.shape),
        "obstacles": int(free.size - np.count_nonzero(free)),
        "runs": args.runs,
        **time_runs(lambda: ndimage.distance_transform_edt(free), args.runs),
        "threads": 1,
    }
    if args.with_indices:
        result["with_indices"] = time_runs(
            lambda: ndimage.distance_transform_edt(free, return_indices=True), args.runs)
    print(json.dumps(result))


if __name__ == "__main__":
    main()
