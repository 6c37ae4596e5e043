#!/usr/bin/env python3
"""Peer check of haunts-bag's MCAP writer: decodes with the Python `mcap-ros2-support` decoder
(`mcap_ros2.decoder.DecoderFactory`, which parses the file's `ros2msg` schemas itself) the MCAP
that `cargo run -p haunts-bag --example peer_mcap` writes (one LaserScan, OccupancyGrid, Path,
TFMessage, PoseArray and MarkerArray of known content), and writes what it decoded as the JSON fixture
`bag/tests/fixtures/mcap_ros2_peer.json`: per message its topic, schema name, log time, the
CDR bytes as hex, and the decoded fields (float32 values as the doubles Python holds, exact;
byte arrays as lists of integers). `bag/tests/peer_fixture.rs` checks that haunts still writes
those very bytes and that the decoded fields equal the messages it meant.

Run from the project root (builds and runs the example unless --mcap is given):

    python3 benches/peers/mcap_ros2_check.py
"""
import argparse
import json
import subprocess
import tempfile
from importlib.metadata import version
from pathlib import Path

from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory

FIXTURE = Path("bag/tests/fixtures/mcap_ros2_peer.json")


def plain(value):
    """The decoded object as JSON values: generated classes by their slots, in order."""
    if isinstance(value, (bool, int, float, str)) or value is None:
        return value
    if isinstance(value, (bytes, bytearray)):
        return list(value)
    if isinstance(value, (list, tuple)):
        return [plain(v) for v in value]
    if hasattr(value, "tolist"):  # array.array / numpy
        return plain(value.tolist())
    slots = getattr(type(value), "__slots__", None)
    if slots is None:
        raise TypeError(f"cannot turn {type(value)!r} into JSON")
    return {name: plain(getattr(value, name)) for name in slots}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--mcap", type=Path, help="an MCAP written by the peer_mcap example")
    ap.add_argument("--out", type=Path, default=FIXTURE)
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        path = args.mcap
        if path is None:
            path = Path(tmp) / "peer.mcap"
            subprocess.run(["cargo", "run", "--quiet", "-p", "haunts-bag", "--example", "peer_mcap",
                            "--", str(path)], check=True)
        messages, schemas = [], {}
        with open(path, "rb") as f:
            reader = make_reader(f, decoder_factories=[DecoderFactory()])
            profile = reader.get_header().profile
            for schema, channel, message, decoded in reader.iter_decoded_messages():
                schemas[schema.name] = dict(encoding=schema.encoding, data=schema.data.decode())
                messages.append(dict(
                    topic=channel.topic,
                    message_encoding=channel.message_encoding,
                    schema=schema.name,
                    log_time=message.log_time,
                    publish_time=message.publish_time,
                    cdr_hex=message.data.hex(),
                    decoded=plain(decoded),
                ))
    out = dict(
        generator="benches/peers/mcap_ros2_check.py",
        versions={p: version(p) for p in ("mcap", "mcap-ros2-support")},
        profile=profile,
        schemas=schemas,
        messages=messages,
    )
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(out, indent=1, ensure_ascii=False) + "\n")
    print(f"decoded {len(messages)} messages ({', '.join(m['schema'] for m in messages)}) into {args.out}")


if __name__ == "__main__":
    main()
