"""Reference cell values of the two real ROS maps under ROS 1 map_server and Nav2 map_server.

For each map (willow, y4) and each interpretation (`ros1`: map_server/src/image_loader.cpp,
`nav2`: nav2_map_server/src/map_io.cpp) and mode (`trinary`, `scale`, `raw`), every pixel is
turned into an OccupancyGrid cell value exactly as the C++ does it (float64, same order of
operations), and the cell values are summarised as counts and a sum. Writes
occupancy/tests/fixtures/maps.json.

Both maps are single-channel 8-bit images without alpha, so only the grey value matters and
each interpretation is a function of the pixel value alone: it is evaluated once per value
0..=255 with Python floats (IEEE float64, like C double) into a 256-entry table, which is
also written to the fixture (`lut`) for debugging.

Usage (from the project root): python3 benches/peers/map_fixtures.py [--data-dir DIR] [--out FILE]
"""

import argparse
import math
from importlib.metadata import version

import numpy as np

from rosmap import DEFAULT_DATA_DIR, FIXTURES_DIR, MAPS, load_map, write_json

INTERPRETATIONS = ("ros1", "nav2")
MODES = ("trinary", "scale", "raw")


def ros1_value(p, mode, negate, occ_th, free_th):
    """ROS 1 map_server value of grey level `p` (image_loader.cpp, one channel, opaque)."""
    color_avg = p
    if negate:
        color_avg = 255 - color_avg
    if mode == "raw":
        # `value = color_avg` stored into an int8 data array: 128..=255 wrap to negative.
        return color_avg if color_avg <= 127 else color_avg - 256
    occ = (255 - color_avg) / 255.0
    if occ > occ_th:
        return 100
    if occ < free_th:
        return 0
    if mode == "trinary":
        return -1
    ratio = (occ - free_th) / (occ_th - free_th)
    return int(1 + 98 * ratio)  # double -> int conversion truncates toward zero


def cpp_round(x):
    """C++ std::round: nearest integer, halfway cases away from zero (exact for doubles)."""
    r = math.floor(abs(x))
    if abs(x) - r >= 0.5:  # exact: abs(x) - floor(abs(x)) has no rounding error
        r += 1
    return int(math.copysign(r, x))


def nav2_value(p, mode, negate, occ_th, free_th):
    """Nav2 map_server value of grey level `p` (map_io.cpp, one channel, opaque).

    Nav2 reads pixels through Magick++ as `quantum / QuantumRange`; for an 8-bit image that is
    the correctly rounded p/255, the same double as `p / 255.0` here.
    """
    shade = p / 255.0
    if mode == "raw":
        # Negate is not applied in raw mode.
        v = cpp_round(shade * 255)
        return v if 0 <= v <= 100 else -1
    occ = shade if negate else 1.0 - shade
    if occ_th < occ:
        return 100
    if occ < free_th:
        return 0
    if mode == "trinary":
        return -1
    return round((occ - free_th) / (occ_th - free_th) * 100.0)  # half to even, like rint


VALUE_FUNCTIONS = {"ros1": ros1_value, "nav2": nav2_value}


def lookup_table(interpretation, mode, m):
    """Cell value of every grey level 0..=255 for map `m` as a list of 256 ints."""
    f = VALUE_FUNCTIONS[interpretation]
    return [f(p, mode, m["negate"], m["occupied_thresh"], m["free_thresh"]) for p in range(256)]


def summarise(counts_by_pixel, lut):
    """Histogram summary of the cell values, given the pixel-value counts and the value table."""
    summary = {"unknown": 0, "free": 0, "occupied": 0, "other": 0, "out_of_range": 0, "sum": 0}
    for p, n in enumerate(counts_by_pixel):
        if n == 0:
            continue
        v = lut[p]
        summary["sum"] += v * n
        if v == -1:
            summary["unknown"] += n
        elif v == 0:
            summary["free"] += n
        elif v == 100:
            summary["occupied"] += n
        elif 1 <= v <= 99:
            summary["other"] += n
        else:  # only reachable in ROS 1 raw mode (int8-wrapped values)
            summary["out_of_range"] += n
    return summary


def map_record(m):
    """Fixture record of one loaded map."""
    counts = np.bincount(m["pixels"].ravel(), minlength=256)
    counts = [int(n) for n in counts]
    record = {k: m[k] for k in (
        "name", "yaml", "image", "image_sha256", "width", "height", "resolution", "origin",
        "negate", "occupied_thresh", "free_thresh", "free_thresh_defaulted")}
    luts = {i: {mode: lookup_table(i, mode, m) for mode in MODES} for i in INTERPRETATIONS}
    for i in INTERPRETATIONS:
        record[i] = {mode: summarise(counts, luts[i][mode]) for mode in MODES}
    # Direct per-pixel evaluation (vectorised lookup) must agree with the histogram route.
    for i in INTERPRETATIONS:
        for mode in MODES:
            cells = np.asarray(luts[i][mode], dtype=np.int64)[m["pixels"]]
            assert int(cells.sum()) == record[i][mode]["sum"], (m["name"], i, mode)
            total = sum(record[i][mode][k] for k in ("unknown", "free", "occupied", "other", "out_of_range"))
            assert total == m["width"] * m["height"], (m["name"], i, mode)
    record["lut"] = luts
    record["pixel_histogram"] = {str(p): n for p, n in enumerate(counts) if n}
    return record


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data-dir", default=DEFAULT_DATA_DIR,
                        help="directory of the map YAML and PGM files (default: ../shared/data/maps)")
    parser.add_argument("--out", default=FIXTURES_DIR / "maps.json", help="output JSON file")
    args = parser.parse_args()

    fixture = {
        "generator": "benches/peers/map_fixtures.py",
        "numpy": np.__version__,
        "pillow": version("pillow"),
        "pyyaml": version("pyyaml"),
        "maps": [map_record(load_map(args.data_dir, name)) for name in MAPS],
    }
    size = write_json(args.out, fixture)
    for r in fixture["maps"]:
        print(f"{r['name']}: {r['width']}x{r['height']} @ {r['resolution']} m, origin {r['origin']}")
        for i in INTERPRETATIONS:
            for mode in MODES:
                print(f"  {i:4} {mode:7} {r[i][mode]}")
    print(f"wrote {args.out} ({size} bytes)")


if __name__ == "__main__":
    main()
