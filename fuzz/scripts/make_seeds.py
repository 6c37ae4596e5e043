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


# ------------------------------------------- leg_tracker, trajectory, detections (byte 0 = config)
LT = os.path.join(DATA, "leg_tracker", "general_tracking_moving_1")


def head_lines(path, count, first=1):
    """Lines first..first+count-1 (1-based) of a text file, as bytes."""
    out = []
    with open(path, "rb") as f:
        for i, line in enumerate(f, 1):
            if i >= first + count:
                break
            if i >= first:
                out.append(line)
    return b"".join(out)


def cut_scan_line(line, keep=12):
    """A scans.txt line cut down to `keep` ranges (the count rewritten)."""
    w = line.split()
    return b" ".join(w[:7] + [str(keep).encode()] + w[8:8 + keep]) + b"\n"


scans = head_lines(os.path.join(LT, "scans.txt"), 4)
scan_lines = scans.splitlines(keepends=True)
write("leg_tracker", "ok-scans.txt", b"\x00" + scan_lines[0] + b"".join(cut_scan_line(l) for l in scan_lines[1:]))
write("leg_tracker", "bad-scans-count.txt", b"\x00" + scan_lines[1][:400] + b"\n")
write("leg_tracker", "ok-odom.txt", b"\x01" + head_lines(os.path.join(LT, "odom.txt"), 6))
write("leg_tracker", "ok-static-tf.txt", b"\x02" + head_lines(os.path.join(LT, "static_tf.txt"), 3))
write("leg_tracker", "ok-ground-truth.txt", b"\x03" + head_lines(os.path.join(LT, "ground_truth_people.txt"), 6))
write("leg_tracker", "bad-ground-truth-nan.txt", b"\x03" + b"1403024492.47 1 nan 2\n1e300 18446744073709551616 1 2\n")

OBS = os.path.join(DATA, "trajectories", "eth", "seq_eth", "obsmat.txt")
write("trajectory", "ok-eth-obsmat.txt", b"\x01" + head_lines(OBS, 8))
write("trajectory", "ok-eth-obsmat-25hz.txt", b"\x03" + head_lines(OBS, 8, 200))
write("trajectory", "ok-delimited.csv", b"\x0a" + b"t,id,x,y\n1.0,1,0.5,0.5\n1.4,1,0.6,0.5\n1.0,2,3,4\n")
write("trajectory", "bad-delimited-columns.txt", b"\x30" + b"1 2 3 4\n5 6 7\n")

PEOPLE = os.path.join(DATA, "people", "2017_05_25.txt")
write("detections", "ok-people.txt", b"\x00" + head_lines(PEOPLE, 8))
write("detections", "ok-people-semicolon.txt", b"\x04" + head_lines(PEOPLE, 4).replace(b" ", b";"))
write("detections", "bad-people-nan-inf.txt", b"\x00" + b"1495706022.77 nan 1\ninf 1 2\n1e309 1 2\n")

# ------------------------------------------------ layout_library (byte 0 bit 0 = wrap payload)
import hashlib  # noqa: E402


def library_payload():
    """A 2 × 2-cell library with one layout of one day (the format of layout/file.rs)."""
    p = struct.pack("<dddII", 0.5, 0.0, 0.0, 2, 2)
    p += struct.pack("<BdBdBdI", 1, 1.0, 0, 5.0, 0, 0.5, 1)
    p += struct.pack("<QI", 1, 1)
    p += struct.pack("<I", 1)
    label = b"2026-01-01"
    p += struct.pack("<QI", 0, len(label)) + label + struct.pack("<Bd", 0, 0.0)
    p += struct.pack("<4I", 1, 0, 0, 0) + struct.pack("<4I", 0, 1, 1, 0)
    p += struct.pack("<4Q", 0, 1, 0, 0) + struct.pack("<4Q", 1, 1, 1, 0)
    return p


def library_file(payload):
    return (b"HAUNTLIB" + struct.pack("<IQ", 1, len(payload)) + payload
            + hashlib.sha256(payload).digest())


write("layout_library", "ok-payload.bin", b"\x01" + library_payload())
write("layout_library", "ok-file.bin", b"\x00" + library_file(library_payload()))
write("layout_library", "bad-checksum.bin", b"\x00" + library_file(library_payload())[:-1] + b"\x00")
write("layout_library", "bad-truncated.bin", b"\x01" + library_payload()[:40])
# A resolution of 1e308 behind a valid checksum (issue 49: it once looped `haunts maps`).
write("layout_library", "bad-payload-resolution-1e308.bin",
      b"\x01" + struct.pack("<d", 1e308) + library_payload()[8:])
# An origin at x = 1e300 behind a valid checksum: beyond GridGeometry::MAX_ORIGIN.
write("layout_library", "bad-payload-origin-1e300.bin",
      b"\x01" + library_payload()[:8] + struct.pack("<d", 1e300) + library_payload()[16:])

# scene_map: the OpenTraj map.xml of both ETH scenes, absurd but valid tags, bad tags.
for scene in ["seq_eth", "seq_hotel"]:
    with open(os.path.join(DATA, "trajectories", "eth", scene, "map.xml")) as f:
        write("scene_map", "ok-" + scene.replace("_", "-") + ".xml", f.read())
write("scene_map", "ok-absurd.xml",
      '<Map>\n<Line x1="0" y1="0" x2="1e300" y2="1e300"/>\n'
      '<Circle x="1" y="-1" radius="1e300"/>\n</Map>\n')
write("scene_map", "bad-nan.xml", '<Map>\n<Line x1="nan" y1="0" x2="1" y2="1"/>\n</Map>\n')
write("scene_map", "bad-no-radius.xml", '<Map>\n<Circle x="1" y="2"/>\n</Map>\n')
# day_artifact: written by the facade's tests/artifact_fuzz_regressions.rs
# (HAUNTS_WRITE_SEEDS=1 cargo test -p haunts --features serde --test artifact_fuzz_regressions).
