#!/usr/bin/env python3
"""A fleet's recordings through `haunts` on Dask distributed: one `haunts day` task per
recording, then one `haunts merge` of their artifacts into the library.

    fleet.py REC... --library LIB [--workers N] [--scheduler ADDRESS] [--day-args "..."]

Without `--scheduler` a `LocalCluster` of N worker processes (one thread each) runs the
tasks on this machine; with it, the cluster at ADDRESS does, and every path given must be
the same file on every worker (a shared volume). The `haunts` run is the one on each
worker's `PATH` (`--haunts` names another).

Each day task runs `haunts day REC -o DAYS/<name>.haunts DAY_ARGS` (`--days-dir`, default
`days/` beside the library). A task whose worker died, or whose `haunts` was killed by a
signal, is submitted again, up to `--retries` times, and counted in `retried` (the merge
too); a day that
`haunts day` refused to align (`--like`, exit status 3) is not merged and is counted in
`refused`, as is a day the merge refused; a day whose `haunts day` failed (exit status 1:
an unreadable recording, say) is reported in `failed` with its message, and the others go
on. The merge is one task, after every day, over the artifacts sorted by path: `haunts
merge` orders days by their first scan, so the library does not depend on the order in
which days finished (byte for byte: `test_fleet.py`).

A progress bar goes to stderr; the last line of stdout is a JSON summary: `days` (given),
`done` (artifacts written), `retried`, `refused` (with reasons), `failed`, `merged`,
`library`, `seconds` (wall, from start to the merge's end), `workers`. Exit status 0 when
the merge ran and no day failed, 1 otherwise.
"""

from __future__ import annotations

import argparse
import json
import os
import shlex
import shutil
import signal
import subprocess
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

# `haunts day`'s exit status for a day it could not align onto `--like`'s library.
NOT_ALIGNED = 3


class WorkerLost(RuntimeError):
    """The `haunts` process died of a signal (the worker's machine, not the recording)."""


def run_haunts(argv: list[str]) -> dict:
    """Runs one `haunts` command on a worker; its exit status, last stdout line, stderr.

    A `haunts` killed by a signal raises `WorkerLost`, so the driver submits it again;
    a `haunts` that exited is a result, whatever its status.
    """
    proc = subprocess.run(argv, capture_output=True, text=True)
    if proc.returncode < 0:
        raise WorkerLost(f"{argv[0]} {argv[1]} killed by signal {-proc.returncode}")
    lines = proc.stdout.strip().splitlines()
    report = None
    if lines:
        try:
            report = json.loads(lines[-1])
        except json.JSONDecodeError:
            report = None
    return {"status": proc.returncode, "report": report, "stderr": proc.stderr[-2000:]}


@dataclass
class Day:
    recording: Path
    artifact: Path
    attempts: int = 0
    outcome: dict | None = None


@dataclass
class Summary:
    days: int = 0
    done: int = 0
    retried: int = 0
    refused: list = field(default_factory=list)
    failed: list = field(default_factory=list)
    merged: dict | None = None

    def line(self, library: Path, seconds: float, workers) -> str:
        return json.dumps(
            {
                "days": self.days,
                "done": self.done,
                "retried": self.retried,
                "refused": self.refused,
                "failed": self.failed,
                "merged": self.merged,
                "library": str(library),
                "seconds": round(seconds, 3),
                "workers": workers,
            },
            sort_keys=True,
        )


class Progress:
    """One line on stderr, redrawn: `days  7/20 [######......] retried 1 refused 0`."""

    def __init__(self, total: int, stream=sys.stderr):
        self.total, self.stream = total, stream
        self.tty = stream.isatty()

    def draw(self, done: int, summary: Summary, final: bool = False):
        width = 30
        filled = width * done // max(self.total, 1)
        text = (
            f"days {done:>{len(str(self.total))}}/{self.total} "
            f"[{'#' * filled}{'.' * (width - filled)}] "
            f"retried {summary.retried} refused {len(summary.refused)} "
            f"failed {len(summary.failed)}"
        )
        if self.tty:
            self.stream.write("\r" + text + ("\n" if final else ""))
        else:
            # A log file gets one line per finished day, not carriage returns.
            self.stream.write(text + "\n")
        self.stream.flush()


def parse_args(argv=None):
    p = argparse.ArgumentParser(
        description="A fleet's recordings through haunts day on Dask, then one haunts merge."
    )
    p.add_argument("recordings", nargs="+", type=Path, metavar="REC")
    p.add_argument("--library", required=True, type=Path, metavar="LIB")
    p.add_argument("--workers", type=int, default=os.cpu_count() or 1, metavar="N",
                   help="LocalCluster worker processes (default: the CPU count)")
    p.add_argument("--scheduler", metavar="ADDRESS",
                   help="a running Dask scheduler (tcp://host:8786) instead of a LocalCluster")
    p.add_argument("--day-args", default="", metavar='"..."',
                   help="options for every haunts day (one shell-quoted string)")
    p.add_argument("--merge-args", default="", metavar='"..."',
                   help="options for haunts merge (for example --wait 600)")
    p.add_argument("--days-dir", type=Path, metavar="DIR",
                   help="where the day artifacts go (default: days/ beside the library)")
    p.add_argument("--haunts", default="haunts", metavar="PROGRAM",
                   help="the haunts program (default: haunts on the workers' PATH)")
    p.add_argument("--retries", type=int, default=2, metavar="N",
                   help="times a day is submitted again after its worker failed (default 2)")
    args = p.parse_args(argv)
    if args.workers < 1:
        p.error("--workers must be at least 1")
    if args.retries < 0:
        p.error("--retries must be 0 or more")
    names = [artifact_name(r) for r in args.recordings]
    clash = sorted({n for n in names if names.count(n) > 1})
    if clash:
        p.error(f"recordings with the same file name would write one artifact: {clash}")
    return args


def artifact_name(recording: Path) -> str:
    return (recording.stem if recording.suffix else recording.name) + ".haunts"


def start_client(args):
    # Imported here, so that --help works without Dask installed.
    import dask
    from distributed import Client, LocalCluster

    if args.scheduler:
        return Client(args.scheduler), None
    # A worker that dies takes its task with it: let the driver see that at once (and count
    # the retry) instead of the scheduler resubmitting it silently.
    # One task per worker at a time (not Dask's 1.1 worker saturation, which hands a busy
    # worker a second day): days are long, a free worker should take the next, and a worker
    # that dies loses only the day it was running.
    dask.config.set({
        "distributed.scheduler.allowed-failures": 0,
        "distributed.scheduler.worker-saturation": 1.0,
    })
    cluster = LocalCluster(
        n_workers=args.workers,
        threads_per_worker=1,
        processes=True,
        dashboard_address=None,
        # Loopback only: a local fleet opens no port on the machine's network.
        host="127.0.0.1",
    )
    return Client(cluster), cluster


def run(args) -> tuple[Summary, float]:
    from distributed import as_completed

    start = time.monotonic()
    library = args.library.resolve()
    days_dir = (args.days_dir or library.parent / "days").resolve()
    days_dir.mkdir(parents=True, exist_ok=True)
    day_args = shlex.split(args.day_args)
    haunts = args.haunts
    if args.scheduler is None:
        # A local fleet runs the driver's own haunts: found here, or an error before any task.
        haunts = shutil.which(args.haunts)
        if haunts is None:
            raise SystemExit(f"fleet.py: {args.haunts!r} not found on PATH (give --haunts)")
    days = [
        Day(recording=r.resolve(), artifact=days_dir / artifact_name(r))
        for r in args.recordings
    ]
    summary = Summary(days=len(days))
    client, cluster = start_client(args)
    try:
        def submit(day: Day):
            day.attempts += 1
            argv = [haunts, "day", str(day.recording), "-o", str(day.artifact), *day_args]
            # pure=False: a resubmission is a new task, not the failed one's result.
            future = client.submit(run_haunts, argv, pure=False, retries=0)
            by_key[future.key] = day
            return future

        by_key: dict = {}
        progress = Progress(len(days))
        pending = as_completed([submit(d) for d in days], with_results=False)
        finished = 0
        for future in pending:
            day = by_key.pop(future.key)
            try:
                outcome = future.result()
            except Exception as e:  # the worker died (KilledWorker), or haunts was killed
                if day.attempts <= args.retries:
                    summary.retried += 1
                    pending.add(submit(day))
                    progress.draw(finished, summary)
                    continue
                outcome = {"status": None, "report": None,
                           "stderr": f"{type(e).__name__}: {e}"}
            day.outcome = outcome
            finished += 1
            status = outcome["status"]
            if status == 0:
                summary.done += 1
            elif status == NOT_ALIGNED:
                summary.done += 1
                reason = (outcome["report"] or {}).get("refused") or "not aligned"
                summary.refused.append({"recording": str(day.recording), "reason": reason})
            else:
                summary.failed.append({
                    "recording": str(day.recording),
                    "status": status,
                    "attempts": day.attempts,
                    "error": outcome["stderr"].strip().splitlines()[-1:] or [""],
                })
            progress.draw(finished, summary, final=finished == len(days))

        # The days to merge, in path order; `haunts merge` orders them by their first scan.
        ok = sorted(str(d.artifact) for d in days if d.outcome and d.outcome["status"] == 0)
        if ok:
            argv = [haunts, "merge", *ok, "-o", str(library), *shlex.split(args.merge_args)]
            # The merge too survives a worker lost under it (the library is saved atomically
            # and the merge holds its lock, so running it again is safe).
            for attempt in range(args.retries + 1):
                try:
                    outcome = client.submit(run_haunts, argv, pure=False).result()
                    break
                except Exception as e:  # the worker died, or haunts was killed
                    if attempt == args.retries:
                        outcome = {"status": None, "report": None,
                                   "stderr": f"{type(e).__name__}: {e}"}
                    else:
                        summary.retried += 1
            if outcome["status"] != 0 or outcome["report"] is None:
                summary.failed.append({"merge": str(library), "status": outcome["status"],
                                       "error": outcome["stderr"].strip().splitlines()[-1:]})
            else:
                report = outcome["report"]
                summary.merged = {k: report.get(k) for k in ("saved", "layouts", "days")}
                summary.merged["ingested"] = len(report.get("ingested", []))
                summary.merged["duplicates"] = len(report.get("duplicates", []))
                for r in report.get("refused", []):
                    summary.refused.append({"artifact": r.get("file"), "reason": r.get("reason")})
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
    return summary, time.monotonic() - start


def main(argv=None) -> int:
    args = parse_args(argv)
    # Ctrl-C ends the run (Dask's workers are torn down by the `finally`).
    signal.signal(signal.SIGTERM, signal.default_int_handler)
    summary, seconds = run(args)
    workers = args.scheduler or args.workers
    print(summary.line(args.library, seconds, workers))
    return 0 if summary.merged is not None and not summary.failed else 1


if __name__ == "__main__":
    sys.exit(main())
