"""Shared helpers of the peer scripts: locating the data, loading ROS map files, JSON output.

A ROS map is a YAML file next to an 8-bit greyscale image (here binary PGM, P5, with `#`
comment lines in the header). The image is returned as a numpy uint8 array `p` with row 0
at the TOP of the image, as stored in the file.
"""

import hashlib
import json
from pathlib import Path

import numpy as np
import yaml
from PIL import Image

# benches/peers/rosmap.py -> project root (/work/main).
PROJECT_ROOT = Path(__file__).resolve().parents[2]
# Real data lives next to the project: ../shared/data/maps relative to the project root.
DEFAULT_DATA_DIR = PROJECT_ROOT / ".." / "shared" / "data" / "maps"
FIXTURES_DIR = PROJECT_ROOT / "occupancy" / "tests" / "fixtures"

# The two maps the fixtures are built from, by short name.
MAPS = {
    "willow": "willow-2010-02-18-0.10.yaml",
    "y4": "y4_aaf-cropped.yaml",
}

# ROS map_saver writes free_thresh 0.196 by default; used when the YAML has no such key.
DEFAULT_FREE_THRESH = 0.196


def load_map(data_dir, name):
    """Load map `name` (a key of MAPS) from `data_dir`.

    Returns a dict with the YAML metadata (floats as parsed, `free_thresh_defaulted` set when
    the key is absent) and the image as `pixels`, a (height, width) uint8 array, row 0 = top.
    PyYAML keeps the last of duplicated keys (willow repeats `free_thresh` with equal values).
    """
    yaml_path = Path(data_dir) / MAPS[name]
    with open(yaml_path, encoding="utf-8") as f:
        meta = yaml.safe_load(f)
    image_path = yaml_path.parent / meta["image"]
    with Image.open(image_path) as img:
        if img.mode != "L":
            raise ValueError(f"{image_path}: expected an 8-bit greyscale image, got mode {img.mode}")
        pixels = np.asarray(img.convert("L"), dtype=np.uint8)
    defaulted = "free_thresh" not in meta
    return {
        "name": name,
        "yaml": yaml_path.name,
        "image": image_path.name,
        "image_sha256": hashlib.sha256(image_path.read_bytes()).hexdigest(),
        "width": int(pixels.shape[1]),
        "height": int(pixels.shape[0]),
        "resolution": float(meta["resolution"]),
        "origin": [float(v) for v in meta["origin"]],
        "negate": int(meta["negate"]),
        "occupied_thresh": float(meta["occupied_thresh"]),
        "free_thresh": DEFAULT_FREE_THRESH if defaulted else float(meta["free_thresh"]),
        "free_thresh_defaulted": defaulted,
        "pixels": pixels,
    }


def obstacle_mask(m):
    """Obstacle cells of map `m`: occupied under ROS 1 map_server (trinary or scale).

    `occ = (255 - color_avg) / 255.0 > occupied_thresh`, evaluated in float64, with negate
    applied as in ROS 1. The result is flipped so that row 0 is the BOTTOM row of the image,
    the row-major nav_msgs/OccupancyGrid convention of the Rust grid.
    """
    color_avg = m["pixels"].astype(np.int64)
    if m["negate"]:
        color_avg = 255 - color_avg
    occ = (255 - color_avg) / 255.0
    return np.flipud(occ > m["occupied_thresh"])


def write_json(path, obj):
    """Write `obj` as JSON with a 1-space indent, but lists of numbers kept on one line.

    Keeps the fixtures readable in diffs without one line per number.
    """
    placeholders = {}

    def pack(value):
        if isinstance(value, dict):
            return {k: pack(v) for k, v in value.items()}
        if isinstance(value, list):
            if all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in value):
                key = f"@@{len(placeholders)}@@"
                placeholders[key] = json.dumps(value, separators=(",", ":"))
                return key
            return [pack(v) for v in value]
        return value

    text = json.dumps(pack(obj), indent=1)
    for key, inline in placeholders.items():
        text = text.replace(f'"{key}"', inline, 1)
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    Path(path).write_text(text + "\n", encoding="utf-8")
    return len(text) + 1
