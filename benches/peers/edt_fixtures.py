"""Reference exact Euclidean distance transforms of the two real ROS maps, from scipy.

Obstacles are the cells occupied under ROS 1 map_server (`(255 - p) / 255.0 > occupied_thresh`),
in the Rust grid convention: row-major, row 0 = BOTTOM row of the image. For every cell the
squared distance in cells to the nearest obstacle cell, `d2 = rint(d * d)` of
`scipy.ndimage.distance_transform_edt(~mask)`, is an exact integer; the fixture records its
sha256 (little-endian u32, row 0 first), max, sum and 2000 sampled cells. Writes
occupancy/tests/fixtures/edt_<name>.json for each map.

Usage (from the project root): python3 benches/peers/edt_fixtures.py [--data-dir DIR] [--out-dir DIR]
"""

import argparse
import hashlib

import numpy as np
import scipy
from scipy import ndimage

from rosmap import DEFAULT_DATA_DIR, FIXTURES_DIR, MAPS, load_map, obstacle_mask, write_json

N_SAMPLES = 2000
SAMPLE_SEED = 7


def squared_edt(mask):
    """Squared distances (u4, little-endian) from every cell to the nearest True cell of `mask`."""
    d = ndimage.distance_transform_edt(~mask)
    d2f = d * d
    d2 = np.rint(d2f).astype("<u4")
    # scipy takes sqrt of an exact integer sum of squares: squaring back must land on integers.
    assert np.max(np.abs(d2f - d2)) < 1e-6
    return d2


def brute_force_d2(mask, col, row):
    """Squared distance from cell (col, row) to the nearest obstacle, by exhaustive search."""
    rows, cols = np.nonzero(mask)
    return int(np.min((cols - col) ** 2 + (rows - row) ** 2))


def edt_record(m):
    """Fixture record of one loaded map."""
    mask = obstacle_mask(m)  # (height, width), row 0 = bottom
    assert mask.any(), f"{m['name']}: no obstacle cells"
    d2 = squared_edt(mask)
    sha = hashlib.sha256(np.ascontiguousarray(d2).tobytes()).hexdigest()
    # Reproducibility: a second, independent computation gives the same bytes.
    assert hashlib.sha256(squared_edt(mask.copy()).tobytes()).hexdigest() == sha

    height, width = mask.shape
    rng = np.random.default_rng(SAMPLE_SEED)
    flat = rng.choice(width * height, size=N_SAMPLES, replace=False)
    samples = []
    for i in flat:
        row, col = divmod(int(i), width)
        samples.append([col, row, int(d2[row, col])])
    # Spot-check scipy against brute force on the first samples.
    for col, row, v in samples[:50]:
        assert brute_force_d2(mask, col, row) == v, (m["name"], col, row)

    return {
        "name": m["name"],
        "scipy_version": scipy.__version__,
        "numpy_version": np.__version__,
        "width": width,
        "height": height,
        "occupied_thresh": m["occupied_thresh"],
        "obstacles": int(mask.sum()),
        "max_d2": int(d2.max()),
        "sum_d2": int(d2.sum(dtype=np.uint64)),
        "sha256": sha,
        "sample_method": f"numpy default_rng({SAMPLE_SEED}).choice(width*height, {N_SAMPLES}, "
                         "replace=False); index = row*width + col",
        "samples": samples,
    }


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data-dir", default=DEFAULT_DATA_DIR,
                        help="directory of the map YAML and PGM files (default: ../shared/data/maps)")
    parser.add_argument("--out-dir", default=FIXTURES_DIR, help="directory of the edt_<name>.json files")
    args = parser.parse_args()

    for name in MAPS:
        record = edt_record(load_map(args.data_dir, name))
        path = f"{args.out_dir}/edt_{name}.json"
        size = write_json(path, record)
        print(f"{name}: {record['width']}x{record['height']}, {record['obstacles']} obstacles, "
              f"max_d2 {record['max_d2']}, sum_d2 {record['sum_d2']}, sha256 {record['sha256']}")
        print(f"wrote {path} ({size} bytes)")


if __name__ == "__main__":
    main()
