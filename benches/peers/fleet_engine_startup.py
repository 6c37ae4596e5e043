#!/usr/bin/env python3
"""Start-up of the two engines fleet/README.md compares: `python -c` to the first task's result
on a 2-worker local cluster, Dask distributed against Ray, median of 5 (BENCHMARKS.md, "A
fleet on Dask").

    python3 benches/peers/fleet_engine_startup.py DASK_VENV_PYTHON RAY_VENV_PYTHON

Each Python is a fresh virtual environment's with `dask[distributed]`, resp. `ray`, installed.
"""
import sys, time, subprocess, statistics
DASK = """
import time; t=time.monotonic()
from distributed import Client, LocalCluster
c = Client(LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None, host='127.0.0.1'))
assert c.submit(lambda x: x + 1, 1).result() == 2
print(time.monotonic() - t)
c.close()
"""
RAY = """
import time; t=time.monotonic()
import ray
ray.init(num_cpus=2, include_dashboard=False, logging_level='ERROR')
@ray.remote
def f(x): return x + 1
assert ray.get(f.remote(1)) == 2
print(time.monotonic() - t)
ray.shutdown()
"""
for name, py, code in [("dask", sys.argv[1], DASK), ("ray", sys.argv[2], RAY)]:
    ts = []
    for _ in range(5):
        t = time.monotonic()
        out = subprocess.run([py, "-c", code], capture_output=True, text=True)
        wall = time.monotonic() - t
        if out.returncode != 0:
            print(name, "failed", out.stderr[-500:]); break
        ts.append((float(out.stdout.strip().splitlines()[-1]), wall))
    if ts:
        print(name, "first task (median of 5) %.2f s, process wall %.2f s" % (statistics.median(t[0] for t in ts), statistics.median(t[1] for t in ts)), ts)
