#!/usr/bin/env python3
"""Writes the seed corpora under fuzz/seeds/ (committed; re-run to regenerate).

map_image seeds start with one configuration byte (see fuzz_targets/map_image.rs),
followed by the image bytes. The regression test occupancy/tests/fuzz_regressions.rs
checks every seed's outcome, so keep the two in step.

CARMEN seeds copy a few lines of /work/shared/data/carmen/*.log.gz when available.
"""
import gzip
import os
import struct
import zlib

HERE = os.path.dirname(os.path.abspath(__file__))
SEEDS = os.path.join(HERE, "..", "seeds")
DATA = "/work/shared/data"


def write(target, name, data):
    d = os.path.join(SEEDS, target)
    os.makedirs(d, exist_ok=True)
    if isinstance(data, str):
        data = data.encode()
    with open(os.path.join(d, name), "wb") as f:
        f.write(data)


# ---------------------------------------------------------------- map_yaml
for name in ["willow-2010-02-18-0.10.yaml", "y4_aaf-cropped.yaml"]:
    with open(os.path.join(DATA, "maps", name), "rb") as f:
        write("map_yaml", "ok-" + name, f.read())
write("map_yaml", "ok-full-scale.yaml",
      "image: /maps/full.png\nmode: scale\nresolution: 0.025\norigin: [-10.5, 3, 0]\n"
      "negate: true\noccupied_thresh: 0.9\nfree_thresh: 0.1\n")
write("map_yaml", "ok-raw-comments.yaml",
      "# a hand-made map\nimage: raw.pgm   # relative\nmode: raw\nresolution: 1\n"
      "origin:\n  - 1.0\n  - -2.0\n  - 0.0\nnegate: False\noccupied_thresh: 1\n"
      "free_thresh: 0\nextra_field: {a: 1}\n")
write("map_yaml", "ok-minimal.yaml",
      "image: m.pgm\nresolution: 0.05\norigin: [0, 0, 0]\noccupied_thresh: 0.65\n")
write("map_yaml", "ok-yaw.yaml",
      "image: m.pgm\nresolution: 0.05\norigin: [1, 2, 0.5]\nnegate: 0\n"
      "occupied_thresh: 0.65\nfree_thresh: 0.196\n")
write("map_yaml", "ok-repeated.yaml",
      "image: m.pgm\nresolution: 0.05\norigin: [0, 0, 0]\nnegate: 0\n"
      "occupied_thresh: 0.65\nfree_thresh: 0.196\nresolution: 0.05\n")
write("map_yaml", "bad-syntax.yaml", "image: [m.pgm\nresolution: 0.05\n")
write("map_yaml", "bad-not-a-mapping.yaml", "- image\n- m.pgm\n")
write("map_yaml", "bad-conflicting.yaml",
      "image: m.pgm\nresolution: 0.05\nresolution: 0.1\norigin: [0, 0, 0]\n"
      "occupied_thresh: 0.65\n")
write("map_yaml", "bad-missing-image.yaml",
      "resolution: 0.05\norigin: [0, 0, 0]\noccupied_thresh: 0.65\n")
write("map_yaml", "bad-origin.yaml",
      "image: m.pgm\nresolution: 0.05\norigin: [0, nan, 0]\noccupied_thresh: 0.65\n")
write("map_yaml", "bad-resolution.yaml",
      "image: m.pgm\nresolution: -0.05\norigin: [0, 0, 0]\noccupied_thresh: 0.65\n")
write("map_yaml", "bad-thresholds.yaml",
      "image: m.pgm\nresolution: 0.05\norigin: [0, 0, 0]\noccupied_thresh: 0.3\n"
      "free_thresh: 0.4\n")

# ---------------------------------------------------------------- map_image
# Configuration byte: bit 0 Nav2, bits 1-2 mode (0 trinary, 1 scale, 2 raw), bit 3 negate,
# bits 4-5 thresholds, bits 6-7 geometry (2 = NaN resolution).
ROS1, NAV2 = 0, 1
TRINARY, SCALE, RAW = 0, 2, 4
NEGATE = 8
NAN_RES = 0x80


def png(width, height, colour_type, bit_depth, rows, palette=None):
    def chunk(kind, body):
        return (struct.pack(">I", len(body)) + kind + body
                + struct.pack(">I", zlib.crc32(kind + body) & 0xFFFFFFFF))
    raw = b"".join(b"\0" + r for r in rows)
    out = b"\x89PNG\r\n\x1a\n"
    out += chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, bit_depth, colour_type, 0, 0, 0))
    if palette:
        out += chunk(b"PLTE", palette)
    out += chunk(b"IDAT", zlib.compress(raw))
    out += chunk(b"IEND", b"")
    return out


p5 = b"P5\n# CREATOR: seed\n3 2\n255\n" + bytes([0, 205, 254, 255, 100, 10])
write("map_image", "ok-p5-8bit-3x2-ros1-trinary", bytes([ROS1 | TRINARY]) + p5)
write("map_image", "ok-p2-8bit-3x2-nav2-scale",
      bytes([NAV2 | SCALE]) + b"P2\n3 2\n255\n0 128 255\n# comment\n205 50 254\n")
write("map_image", "ok-p5-16bit-2x2-ros1-raw",
      bytes([ROS1 | RAW]) + b"P5 2 2 65535\n" + struct.pack(">4H", 0, 12850, 65535, 25700))
write("map_image", "ok-p2-16bit-2x3-nav2-trinary-negate",
      bytes([NAV2 | TRINARY | NEGATE]) + b"P2 2 3 1000\n0 1000\n500 999\n1 300\n")
write("map_image", "ok-png-grey8-2x2-ros1-scale",
      bytes([ROS1 | SCALE]) + png(2, 2, 0, 8, [bytes([0, 128]), bytes([205, 254])]))
write("map_image", "ok-png-greyalpha8-2x1-nav2-scale",
      bytes([NAV2 | SCALE]) + png(2, 1, 4, 8, [bytes([128, 255, 128, 0])]))
write("map_image", "ok-png-rgb8-1x2-ros1-trinary",
      bytes([ROS1 | TRINARY]) + png(1, 2, 2, 8, [bytes([0, 0, 0]), bytes([255, 255, 255])]))
write("map_image", "ok-png-rgba16-1x1-nav2-raw",
      bytes([NAV2 | RAW]) + png(1, 1, 6, 16, [struct.pack(">4H", 100, 100, 100, 65535)]))
write("map_image", "ok-png-palette4-2x1-ros1-trinary",
      bytes([ROS1 | TRINARY]) + png(2, 1, 3, 4, [bytes([0x01])], palette=b"\0\0\0\xff\xff\xff"))
write("map_image", "bad-p5-truncated", bytes([ROS1]) + b"P5 2 2 255\n\0\0")
write("map_image", "bad-p5-huge-header-truncated", bytes([ROS1]) + b"P5 65535 65535 255\n\0")
write("map_image", "bad-p5-too-many-cells", bytes([ROS1]) + b"P5 4294967295 4294967295 255\n\0")
write("map_image", "bad-p2-pixel-above-maxval", bytes([NAV2]) + b"P2 2 1 9\n3 12\n")
write("map_image", "bad-p5-maxval", bytes([ROS1]) + b"P5 1 1 70000\n\0\0")
write("map_image", "bad-p6-unsupported", bytes([ROS1]) + b"P6 1 1 255\n\0\0\0")
write("map_image", "bad-png-crc", bytes([ROS1]) + png(1, 1, 0, 8, [b"\0"])[:29] + b"\0\0\0\0")
write("map_image", "bad-nan-resolution", bytes([ROS1 | NAN_RES]) + p5)

# ---------------------------------------------------------------- carmen
def carmen_lines(name, first, count):
    path = os.path.join(DATA, "carmen", name)
    with gzip.open(path, "rb") as f:
        lines = f.read().split(b"\n")
    return b"\n".join(lines[first - 1:first - 1 + count]) + b"\n"


# intel: comment, PARAMs and ODOMs (lines 1-6), then the first FLASER with NEFF (174-177).
write("carmen", "ok-intel-head.log",
      carmen_lines("intel-corrected.log.gz", 1, 6) + carmen_lines("intel-corrected.log.gz", 174, 4))
# csail: the first FLASER (361 beams, max-range readings) and the ODOM lines around it.
write("carmen", "ok-csail-flaser.log", carmen_lines("csail-corrected.log.gz", 183, 8))
write("carmen", "ok-rlaser.log",
      "RLASER 3 1.0 2.0 81.9 0.5 0.25 0.1 0.6 0.3 0.2 12.5 host 12.5\n"
      "RLASER 0 0 0 0 0 0 0 13.0 host 13.0\n")
write("carmen", "ok-robotlaser1.log",
      "ROBOTLASER1 0 -1.5 3.0 1.0 30.0 0.01 0 4 1 2 3 4 4 9 9 9 9 0 0 0 1 1 0 0.2 0.1 1 1 0 14.0 host 14.0\n"
      "ROBOTLASER1 0 -1.5708 3.1416 0.0174533 81.9 0.01 0 3 1.5 2.5 81.9 0 0.1 0.2 0.0 0.1 0.2 0.0 0 0 0 0 0 15.0 host 15.0\n")
write("carmen", "ok-odom.log",
      "ODOM 1.5 2.5 0.3 0.4 0.05 0 15.0 host 15.0\nODOM 0 0 0 nan inf 0 16.0 host 16.0\n")
write("carmen", "bad-lines.log",
      ("FLASER 3 1.0 2.0\n"
       "FLASER x 1.0\n"
       "FLASER 1 1.0 nan 0 0 0 0 0 1.0 h 1.0\n"
       "ODOM 1 2\n"
       "ROBOTLASER1 0 -1.5 3.0 0.0 30.0 0.01 0 1 1 0 0 0 0 0 0 0 0 0 0 0 0 1.0 h 1.0\n"
       "SYNC 1 2 3\n").encode()
      + b"RLASER \xff\xfe\n")
