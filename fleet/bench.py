#!/usr/bin/env python3
"""The fleet's wall time against a serial run, side by side in one run (BENCHMARKS.md,
"A fleet on Dask").

    HAUNTS=target/release/haunts .venv/bin/python fleet/bench.py [--days 20] [--patrols 5] [--runs 5]

Simulates the days once, then alternates, `--runs` times: serial (`haunts day` on each
recording in turn, then `haunts merge`), `fleet.py --workers 1` and `fleet.py --workers 2`
(each a fresh LocalCluster, its start-up included). Prints the median and every wall time of
each, the ratios of the medians, and checks that all of them wrote the same library.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
DAY_ARGS = ["--grid=-2,-2,20,14", "--tuning", "sim"]


def timed(argv) -> float:
    start = time.monotonic()
    subprocess.run(argv, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return time.monotonic() - start


def main() -> int:
    p = argparse.ArgumentParser()
    p.add_argument("--days", type=int, default=20)
    p.add_argument("--patrols", type=int, default=5)
    p.add_argument("--runs", type=int, default=5)
    args = p.parse_args()
    haunts = os.environ.get("HAUNTS") or shutil.which("haunts")
    if not haunts:
        sys.exit("bench.py: set HAUNTS to the haunts program")
    tmp = Path(tempfile.mkdtemp(prefix="haunts-fleet-bench-"))
    subprocess.run([haunts, "sim", "--days", str(args.days), "--patrols", str(args.patrols),
                    "-o", str(tmp / "bags")], check=True, stdout=subprocess.DEVNULL)
    bags = sorted(str(b) for b in (tmp / "bags").glob("*.mcap"))

    def serial(out: Path) -> float:
        start = time.monotonic()
        out.mkdir()
        for b in bags:
            subprocess.run([haunts, "day", b, "-o", str(out / (Path(b).stem + ".haunts")),
                            *DAY_ARGS], check=True, stdout=subprocess.DEVNULL,
                           stderr=subprocess.DEVNULL)
        subprocess.run([haunts, "merge", *sorted(str(a) for a in out.glob("*.haunts")),
                        "-o", str(out / "library.haunts")], check=True,
                       stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        return time.monotonic() - start

    def fleet(workers: int):
        def run(out: Path) -> float:
            return timed([sys.executable, str(HERE / "fleet.py"), *bags,
                          "--library", str(out / "library.haunts"), "--workers", str(workers),
                          "--day-args", " ".join(DAY_ARGS), "--haunts", haunts])
        return run

    ways = {"serial": serial, "fleet_1_worker": fleet(1), "fleet_2_workers": fleet(2)}
    times = {name: [] for name in ways}
    libraries = set()
    for run in range(args.runs):
        for name, way in ways.items():
            out = tmp / f"{name}-{run}"
            times[name].append(round(way(out), 3))
            libraries.add((out / "library.haunts").read_bytes())
            shutil.rmtree(out)
    shutil.rmtree(tmp)
    medians = {name: statistics.median(t) for name, t in times.items()}
    print(json.dumps({
        "days": args.days,
        "patrols": args.patrols,
        "median_s": medians,
        "runs_s": times,
        "serial_over_fleet_2": round(medians["serial"] / medians["fleet_2_workers"], 3),
        "serial_over_fleet_1": round(medians["serial"] / medians["fleet_1_worker"], 3),
        "same_library": len(libraries) == 1,
    }, sort_keys=True))
    return 0 if len(libraries) == 1 else 1


if __name__ == "__main__":
    sys.exit(main())
