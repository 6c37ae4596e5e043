#!/usr/bin/env python3
"""The fleet driver against a serial run (issue 51): 20 simulated days through `fleet.py` on
a 2-worker LocalCluster, with random delays on the day tasks and one worker killed under
its task, give the same day artifacts and the same library, byte for byte, as `haunts day`
on each recording one after the other and one `haunts merge`.

    HAUNTS=/path/to/haunts python3 fleet/test_fleet.py      # default: haunts on PATH

Needs `fleet/requirements.txt` installed (`.ci/run` makes a virtual environment for it).
FLEET_DAYS changes the number of days (default 20).
"""

from __future__ import annotations

import json
import os
import random
import shutil
import subprocess
import sys
import tempfile
import time
import unittest
from pathlib import Path

HERE = Path(__file__).resolve().parent
FLEET = HERE / "fleet.py"
DAYS = int(os.environ.get("FLEET_DAYS", "20"))
# The office's grid, as `haunts sim` prints it: every day on the same cells.
DAY_ARGS = ["--grid=-2,-2,20,14", "--tuning", "sim"]

# A stand-in for `haunts` on the workers: it appends its recording to a log when it ends,
# sleeps the delay the test gave that recording, and for the recordings named in `kill` (or
# "merge") kills its own worker process (its parent) the first time, before running anything.
WRAPPER = """#!{python}
import json, os, signal, subprocess, sys, time
plan = json.load(open({plan!r}))
argv = sys.argv[1:]
name = os.path.basename(argv[1]) if argv and argv[0] == "day" else argv[0]
if name in plan["kill"]:
    marker = os.path.join(plan["dir"], name + ".killed")
    if not os.path.exists(marker):
        open(marker, "w").close()
        os.kill(os.getppid(), signal.SIGKILL)
        sys.exit(0)
time.sleep(plan["delay"].get(name, 0.0))
status = subprocess.call([plan["haunts"], *argv])
with open(os.path.join(plan["dir"], "finished"), "a") as f:
    f.write(name + "\\n")
sys.exit(status)
"""


def haunts_program() -> str:
    given = os.environ.get("HAUNTS")
    if given:
        # Named (as CI does): it must be there; never a silent skip.
        if not os.access(given, os.X_OK):
            raise AssertionError(f"HAUNTS={given} is not an executable program")
        return str(Path(given).resolve())
    found = shutil.which("haunts")
    if not found:
        raise unittest.SkipTest("no haunts program: set HAUNTS or put haunts on PATH")
    return str(Path(found).resolve())


def run(argv, **kw) -> subprocess.CompletedProcess:
    proc = subprocess.run(argv, capture_output=True, text=True, **kw)
    if proc.returncode != 0:
        raise AssertionError(
            f"{argv[:3]} exited {proc.returncode}:\n{proc.stdout[-3000:]}\n{proc.stderr[-3000:]}"
        )
    return proc


def last_json(proc) -> dict:
    return json.loads(proc.stdout.strip().splitlines()[-1])


class FleetTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.haunts = haunts_program()
        cls.tmp = Path(tempfile.mkdtemp(prefix="haunts-fleet-"))
        cls.bags = cls.tmp / "bags"
        run([cls.haunts, "sim", "--days", str(DAYS), "--patrols", "1", "-o", str(cls.bags)])
        cls.recordings = sorted(cls.bags.glob("*.mcap"))
        assert len(cls.recordings) == DAYS, cls.recordings
        # The reference: every day one after the other, then one merge.
        cls.serial = cls.tmp / "serial"
        cls.serial.mkdir()
        for r in cls.recordings:
            run([cls.haunts, "day", str(r), "-o", str(cls.serial / (r.stem + ".haunts")),
                 *DAY_ARGS])
        artifacts = sorted(str(p) for p in cls.serial.glob("*.haunts"))
        cls.serial_merge = last_json(
            run([cls.haunts, "merge", *artifacts, "-o", str(cls.serial / "library.haunts")])
        )

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.tmp, ignore_errors=True)

    def fleet(self, name, recordings, kill=(), delays=None, extra=("--workers", "2")):
        """fleet.py over `recordings` through the wrapper; (summary, exit status, folder)."""
        out = self.tmp / name
        out.mkdir()
        plan = {"haunts": self.haunts, "dir": str(out), "kill": list(kill),
                "delay": delays or {}}
        (out / "plan.json").write_text(json.dumps(plan))
        wrapper = out / "haunts"
        wrapper.write_text(WRAPPER.format(python=sys.executable, plan=str(out / "plan.json")))
        wrapper.chmod(0o755)
        proc = subprocess.run(
            [sys.executable, str(FLEET), *map(str, recordings),
             "--library", str(out / "library.haunts"), *extra,
             "--day-args", " ".join(DAY_ARGS), "--haunts", str(wrapper)],
            capture_output=True, text=True, timeout=1800,
        )
        self.assertTrue(proc.stdout.strip(), f"no summary; stderr:\n{proc.stderr[-3000:]}")
        return json.loads(proc.stdout.strip().splitlines()[-1]), proc.returncode, out

    def test_fleet_equals_serial_byte_for_byte(self):
        rng = random.Random(51)
        names = [r.name for r in self.recordings]
        delays = {n: rng.uniform(0.0, 1.5) for n in names}
        killed = names[3]
        summary, status, out = self.fleet("fleet", self.recordings, kill=[killed, "merge"],
                                          delays=delays)
        self.assertEqual(status, 0, summary)
        self.assertEqual(summary["days"], DAYS)
        self.assertEqual(summary["done"], DAYS)
        self.assertEqual(summary["failed"], [])
        self.assertEqual(summary["refused"], [])
        # The workers killed under a day and under the merge: each ran again (counted when the
        # driver resubmitted it; at least the one whose KilledWorker it saw).
        self.assertIn(summary["retried"], (1, 2), summary)
        self.assertTrue((out / (killed + ".killed")).exists())
        self.assertTrue((out / "merge.killed").exists())
        self.assertEqual(summary["merged"]["ingested"], DAYS)
        self.assertEqual(summary["merged"]["saved"], True)
        self.assertEqual(summary["merged"]["days"], self.serial_merge["days"])
        self.assertEqual(summary["merged"]["layouts"], self.serial_merge["layouts"])
        # Every day finished, out of order (else the test would prove nothing about order).
        # Dask runs a task at least once: a day whose worker died may also have been run
        # again by the scheduler beside the driver's resubmission, which is harmless (the
        # same bytes, saved atomically), so only each day's first finish is compared.
        finished = (out / "finished").read_text().split()
        first = list(dict.fromkeys(n for n in finished if n.endswith(".mcap")))
        self.assertEqual(sorted(first), names)
        self.assertNotEqual(first, names, "the days finished in path order")
        # Every artifact and the library, byte for byte.
        for r in self.recordings:
            mine = out / "days" / (r.stem + ".haunts")
            self.assertEqual(mine.read_bytes(), (self.serial / mine.name).read_bytes(),
                             f"{mine.name} differs from the serial run's")
        self.assertEqual((out / "library.haunts").read_bytes(),
                         (self.serial / "library.haunts").read_bytes(),
                         "the fleet's library differs from the serial merge's")

    def test_a_bad_recording_fails_alone(self):
        garbage = self.tmp / "garbage.mcap"
        garbage.write_bytes(b"\x89MCAP0\r\n" + bytes(range(256)) * 4)
        some = self.recordings[:2]
        summary, status, out = self.fleet("bad", [*some, garbage])
        self.assertEqual(status, 1, summary)
        self.assertEqual(summary["done"], 2)
        self.assertEqual(summary["retried"], 0)
        self.assertEqual(len(summary["failed"]), 1, summary)
        failure = summary["failed"][0]
        self.assertEqual(failure["recording"], str(garbage))
        self.assertEqual(failure["status"], 1)
        self.assertIn("garbage.mcap", failure["error"][0])
        # The good days were merged: the same library as merging those two serially.
        self.assertEqual(summary["merged"]["ingested"], 2)
        ref = self.tmp / "bad-ref.haunts"
        run([self.haunts, "merge", *(str(self.serial / (r.stem + ".haunts")) for r in some),
             "-o", str(ref)])
        self.assertEqual((out / "library.haunts").read_bytes(), ref.read_bytes())

    def test_a_running_cluster_by_its_address(self):
        """`--scheduler`: a scheduler and two workers started as a user would (`dask
        scheduler`, `dask worker`, on loopback), the same library as the serial merge."""
        folder = self.tmp / "cluster"
        folder.mkdir()
        file = folder / "scheduler.json"
        module = [sys.executable, "-m"]
        procs = [subprocess.Popen(
            [*module, "distributed.cli.dask_scheduler", "--host", "127.0.0.1", "--port", "0",
             "--no-dashboard", "--scheduler-file", str(file)],
            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)]
        try:
            for _ in range(300):
                if file.exists() and file.stat().st_size > 0:
                    break
                time.sleep(0.1)
            address = json.loads(file.read_text())["address"]
            procs.append(subprocess.Popen(
                [*module, "distributed.cli.dask_worker", "--scheduler-file", str(file),
                 "--nworkers", "2", "--nthreads", "1", "--no-dashboard",
                 "--host", "127.0.0.1"],
                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
            some = self.recordings[:3]
            summary, status, out = self.fleet("by-address", some,
                                              extra=("--scheduler", address))
        finally:
            for p in reversed(procs):
                p.terminate()
                p.wait(timeout=30)
        self.assertEqual(status, 0, summary)
        self.assertEqual((summary["done"], summary["retried"], summary["workers"]),
                         (3, 0, address))
        ref = self.tmp / "by-address-ref.haunts"
        run([self.haunts, "merge", *(str(self.serial / (r.stem + ".haunts")) for r in some),
             "-o", str(ref)])
        self.assertEqual((out / "library.haunts").read_bytes(), ref.read_bytes())


class ManifestTest(unittest.TestCase):
    """fleet/k8s/ against the API schemas kubernetes-validate ships (offline), and what the
    schemas cannot say: the Job is Indexed and its pods use their index, the manifests name
    the image Containerfile builds and the one volume claim."""

    K8S = HERE / "k8s"
    VERSIONS = ["1.33.0", "1.37.0"]  # 1.33: backoffLimitPerIndex and podFailurePolicy GA

    def validate(self, *files, version="1.37.0") -> subprocess.CompletedProcess:
        # The one beside this Python (the virtual environment's), else the one on PATH.
        program = shutil.which("kubernetes-validate", path=os.path.dirname(sys.executable))
        program = program or shutil.which("kubernetes-validate")
        self.assertIsNotNone(program, "kubernetes-validate is not installed (requirements.txt)")
        return subprocess.run([program, "--strict", "--quiet", "-k", version,
                               *map(str, files)], capture_output=True, text=True)

    def load(self, name):
        import yaml
        return yaml.safe_load((self.K8S / name).read_text())

    def test_manifests_validate(self):
        files = sorted(self.K8S.glob("*.yaml"))
        self.assertEqual([f.name for f in files],
                         ["days-job.yaml", "merge-job.yaml", "volume.yaml"])
        for version in self.VERSIONS:
            proc = self.validate(*files, version=version)
            self.assertEqual(proc.returncode, 0, f"{version}: {proc.stdout}{proc.stderr}")

    def test_the_validator_refuses_a_wrong_field(self):
        bad = Path(tempfile.mkdtemp(prefix="haunts-k8s-")) / "days-job.yaml"
        text = (self.K8S / "days-job.yaml").read_text()
        for wrong in [text.replace("  parallelism: 4", "  paralelism: 4"),
                      text.replace("parallelism: 4", "parallelism: four")]:
            self.assertNotEqual(wrong, text)
            bad.write_text(wrong)
            proc = self.validate(bad)
            self.assertNotEqual(proc.returncode, 0, proc.stdout)
        shutil.rmtree(bad.parent)

    def test_what_the_schema_cannot_check(self):
        days, merge, volume = (self.load(n) for n in
                               ("days-job.yaml", "merge-job.yaml", "volume.yaml"))
        self.assertEqual(days["spec"]["completionMode"], "Indexed")
        pod = days["spec"]["template"]["spec"]
        self.assertEqual(pod["restartPolicy"], "Never")
        script = " ".join(pod["containers"][0]["args"])
        self.assertIn("JOB_COMPLETION_INDEX", script)
        self.assertIn("haunts day", script)
        self.assertIn("haunts merge", " ".join(merge["spec"]["template"]["spec"]
                                             ["containers"][0]["args"]))
        # One image, the one Containerfile's build command tags.
        containerfile = (HERE / "Containerfile").read_text()
        tag = containerfile.split("docker build -f fleet/Containerfile -t ")[1].split()[0]
        for job in (days, merge):
            spec = job["spec"]["template"]["spec"]
            self.assertEqual([c["image"] for c in spec["containers"]], [tag])
            claims = [v["persistentVolumeClaim"]["claimName"] for v in spec["volumes"]]
            self.assertEqual(claims, [volume["metadata"]["name"]])
        # The day pods write where the merge reads.
        self.assertIn("/data/days/$name.haunts", script)
        self.assertIn("/data/days/*.haunts", merge["spec"]["template"]["spec"]
                      ["containers"][0]["args"][0])


if __name__ == "__main__":
    unittest.main(verbosity=2)
