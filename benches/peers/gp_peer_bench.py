"""Benchmark peers of haunts-gp: scikit-learn and GPy on the issue-3 workload, side by side.

Workload (issue 3, performance section; mirror it exactly in the Rust bench):
  n = 5000 training points in 2-D (`--n`), RBF kernel k(a, b) = σ² exp(-|a - b|² / (2ℓ²)) with
  σ² = 1, ℓ = 2, Gaussian observation noise σn² = 0.01, zero prior mean; prediction of the
  posterior mean and LATENT variance (no σn² added) on a 200 x 200 grid (`--grid`) over
  [0, 20]²: grid point k = j * 200 + i (i fastest) is x0 = (i + 0.5) * 0.1, x1 = (j + 0.5) * 0.1,
  each computed in f64 exactly as written.

Data: SplitMix64 with seed 3, no other RNG, so that Rust can regenerate it bit for bit:
  next_u64():  state = state + 0x9E3779B97F4A7C15 (mod 2^64); z = state;
               z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9 (mod 2^64);
               z = (z ^ (z >> 27)) * 0x94D049BB133111EB (mod 2^64);
               return z ^ (z >> 31)
  u():         (next_u64() >> 11) * 2^-53                                   in [0, 1)
  for each point i = 0 .. n-1, in this order, four draws:
      x0 = 20.0 * u();  x1 = 20.0 * u();  u1 = u();  u2 = u()
      z  = sqrt(-2.0 * ln(1.0 - u1)) * cos(TAU * u2)     (Box-Muller, cosine branch only;
                                                          TAU = 2π = 6.283185307179586)
      y  = sin(x0 / 2.0) * cos(x1 / 3.0) + 0.1 * z
  (libm sin/cos/ln/sqrt: glibc here; the script prints the first 3 points and the sha256 of
  the data file so a port can be checked.) The data is also written to
  target/gp_peer_data/n<n>.bin: 32-byte header = b"HGPDAT01", then little-endian u64 n, u64 d
  (= 2), u64 seed; then n*d f64 x row-major (x0, x1 of point 0, ...), then n f64 y; all
  little-endian. The predictions of each tool's first prediction run go to
  target/gp_peer_data/n<n>_predict_<tool>.bin: b"HGPPRD01", u64 m (grid points), u64 n,
  u64 0; then m f64 mean, then m f64 latent variance, in grid order.

Timed operations (time.perf_counter; each run in a fresh Python subprocess, whose
ru_maxrss is its peak memory; the median of `--runs` runs is reported):
  fit        fixed hyperparameters. sklearn: GaussianProcessRegressor(C(1.0) * RBF(2.0),
             alpha=0.01, optimizer=None).fit(X, y) (one Cholesky for the LML, a second one for
             the model). GPy: GPRegression(X, Y, RBF(2, variance=1, lengthscale=2),
             noise_var=0.01) construction (exact inference: Cholesky and the inverse of K).
  opt        hyperparameter optimisation from σ² = 0.5, ℓ = 1, σn² = 0.1, one start.
             sklearn: kernel C(0.5) * RBF(1.0) + WhiteKernel(0.1), alpha = 0,
             n_restarts_optimizer=0, optimizer = scipy.optimize.minimize(method="L-BFGS-B",
             jac=True, bounds) exactly as sklearn's "fmin_l_bfgs_b" (a callable doing the same
             call, to count iterations), log parameters, bounds (1e-5, 1e5). GPy: construction
             from the same start, then optimize("lbfgsb") (defaults: max_iters 1000,
             unbounded L-BFGS-B over softplus-transformed parameters). Both maximise
             log p(y | X) = log N(y | 0, K + σn² I); GPy's log_likelihood() adds 1e-8 to σn²,
             so `lml_exact` re-evaluates the same formula (scipy Cholesky) at each optimum.
  predict    mean and latent variance on the grid, after an untimed fixed-hyperparameter fit.
             sklearn: predict(grid, return_std=True), var = std²; GPy: predict_noiseless(grid).
             Checksums: math.fsum (exactly rounded, order independent) of the mean and of the
             variance.

Threads: OMP_NUM_THREADS, OPENBLAS_NUM_THREADS and MKL_NUM_THREADS are set to `--threads`
(default: the number of CPUs) in the workers' environment; threadpoolctl's view is recorded.

Usage (from the project root):
  python3 benches/peers/gp_peer_bench.py [--runs 3] [--quick] [--n 5000] [--grid 200]
      [--tools sklearn,gpy] [--tasks fit,opt,predict] [--threads N]
Human-readable lines go to stderr, one JSON object to stdout.
"""

import argparse
import hashlib
import json
import math
import os
import platform
import resource
import statistics
import struct
import subprocess
import sys
import time
from pathlib import Path

from splitmix import SplitMix64

PROJECT_ROOT = Path(__file__).resolve().parents[2]
DATA_DIR = PROJECT_ROOT / "target" / "gp_peer_data"
SEED = 3
DIM = 2
EXTENT = 20.0
VARIANCE, LENGTHSCALE, NOISE = 1.0, 2.0, 0.01
START_VARIANCE, START_LENGTHSCALE, START_NOISE = 0.5, 1.0, 0.1
TOOLS = ("sklearn", "gpy")
TASKS = ("fit", "opt", "predict")


def generate(n, seed=SEED):
    """The training set as flat lists: x (row-major, n*2) and y (n)."""
    rng = SplitMix64(seed)
    x, y = [], []
    for _ in range(n):
        x0 = 20.0 * rng.uniform()
        x1 = 20.0 * rng.uniform()
        u1 = rng.uniform()
        u2 = rng.uniform()
        z = math.sqrt(-2.0 * math.log(1.0 - u1)) * math.cos(math.tau * u2)
        x += [x0, x1]
        y.append(math.sin(x0 / 2.0) * math.cos(x1 / 3.0) + 0.1 * z)
    return x, y


def data_path(n):
    return DATA_DIR / f"n{n}.bin"


def write_data(n):
    x, y = generate(n)
    blob = b"HGPDAT01" + struct.pack("<3Q", n, DIM, SEED) + struct.pack(f"<{n * DIM}d", *x) \
        + struct.pack(f"<{n}d", *y)
    DATA_DIR.mkdir(parents=True, exist_ok=True)
    data_path(n).write_bytes(blob)
    return x, y, hashlib.sha256(blob).hexdigest()


def read_data(n):
    import numpy as np
    blob = data_path(n).read_bytes()
    assert blob[:8] == b"HGPDAT01" and struct.unpack("<3Q", blob[8:32]) == (n, DIM, SEED)
    x = np.frombuffer(blob, dtype="<f8", count=n * DIM, offset=32).reshape(n, DIM).copy()
    y = np.frombuffer(blob, dtype="<f8", count=n, offset=32 + 8 * n * DIM).copy()
    return x, y


def grid_points(side):
    import numpy as np
    step = EXTENT / side
    c = [(i + 0.5) * step for i in range(side)]  # (i + 0.5) * 0.1 for side 200
    return np.array([[c[i], c[j]] for j in range(side) for i in range(side)])


def pred_path(n, tool):
    return DATA_DIR / f"n{n}_predict_{tool}.bin"


# ---------------------------------------------------------------------------------------------
# Worker: one timed operation in a fresh process

def exact_lml(x, y, variance, lengthscale, noise):
    """log N(y | 0, K + noise I) for the RBF kernel, as sklearn computes it (scipy Cholesky)."""
    import numpy as np
    from scipy.linalg import cho_solve, cholesky
    from sklearn.gaussian_process.kernels import RBF, ConstantKernel as C
    k = (C(variance) * RBF(lengthscale))(x)
    k[np.diag_indices_from(k)] += noise
    low = cholesky(k, lower=True, check_finite=False)
    a = cho_solve((low, True), y, check_finite=False)
    return float(-0.5 * y @ a - np.log(np.diag(low)).sum() - len(y) / 2 * np.log(2 * np.pi))


def worker(task, tool, n, side, save_pred):
    import numpy as np
    import threadpoolctl
    import scipy.linalg  # noqa: F401  (load scipy's BLAS before asking threadpoolctl)

    x, y = read_data(n)
    out = {"task": task, "tool": tool, "n": n}
    if tool == "sklearn":
        import sklearn
        from sklearn.gaussian_process import GaussianProcessRegressor
        from sklearn.gaussian_process.kernels import RBF, ConstantKernel as C, WhiteKernel
        out["version"] = sklearn.__version__
    else:
        import GPy
        out["version"] = GPy.__version__

    if task == "predict":
        grid = grid_points(side)
        if tool == "sklearn":
            model = GaussianProcessRegressor(C(VARIANCE) * RBF(LENGTHSCALE), alpha=NOISE,
                                             optimizer=None).fit(x, y)
        else:
            model = GPy.models.GPRegression(x, y[:, None], GPy.kern.RBF(DIM, VARIANCE, LENGTHSCALE),
                                            noise_var=NOISE)

    rss_before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    t0 = time.perf_counter()
    if task == "fit":
        if tool == "sklearn":
            model = GaussianProcessRegressor(C(VARIANCE) * RBF(LENGTHSCALE), alpha=NOISE,
                                             optimizer=None).fit(x, y)
        else:
            model = GPy.models.GPRegression(x, y[:, None], GPy.kern.RBF(DIM, VARIANCE, LENGTHSCALE),
                                            noise_var=NOISE)
    elif task == "opt":
        if tool == "sklearn":
            import scipy.optimize
            stats = {}

            def lbfgsb(obj_func, initial_theta, bounds):  # = sklearn's "fmin_l_bfgs_b" branch
                res = scipy.optimize.minimize(obj_func, initial_theta, method="L-BFGS-B",
                                              jac=True, bounds=bounds)
                stats.update(nit=int(res.nit), nfev=int(res.nfev), message=str(res.message))
                return res.x, res.fun

            kernel = C(START_VARIANCE) * RBF(START_LENGTHSCALE) + WhiteKernel(START_NOISE)
            model = GaussianProcessRegressor(kernel, alpha=0.0, optimizer=lbfgsb,
                                             n_restarts_optimizer=0).fit(x, y)
        else:
            model = GPy.models.GPRegression(
                x, y[:, None], GPy.kern.RBF(DIM, START_VARIANCE, START_LENGTHSCALE),
                noise_var=START_NOISE)
            opt = model.optimize("lbfgsb")
    else:
        if tool == "sklearn":
            mean, std = model.predict(grid, return_std=True)
            var = std * std
        else:
            mean, var = model.predict_noiseless(grid)
            mean, var = mean[:, 0], var[:, 0]
    seconds = time.perf_counter() - t0
    out["seconds"] = seconds
    out["rss_before_mb"] = rss_before / 1024  # ru_maxrss is in KiB on Linux
    out["peak_rss_mb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024

    if task in ("fit", "opt"):
        if tool == "sklearn":
            k = model.kernel_
            if task == "opt":  # C * RBF + WhiteKernel
                params = {"variance": float(k.k1.k1.constant_value),
                          "lengthscale": float(k.k1.k2.length_scale),
                          "noise": float(k.k2.noise_level)}
            else:  # C * RBF, noise = alpha
                params = {"variance": float(k.k1.constant_value),
                          "lengthscale": float(k.k2.length_scale), "noise": NOISE}
            out["lml_reported"] = float(model.log_marginal_likelihood_value_)
            if task == "opt":
                out["theta"] = k.theta.tolist()
                out["optimizer"] = stats
        else:
            params = {"variance": float(model.kern.variance.values[0]),
                      "lengthscale": float(model.kern.lengthscale.values[0]),
                      "noise": float(model.likelihood.variance.values[0])}
            out["lml_reported"] = float(np.squeeze(model.log_likelihood()))
            if task == "opt":
                out["optimizer"] = {"funct_eval": int(opt.funct_eval), "status": str(opt.status)}
        out["params"] = params
        if task == "opt":  # untimed: the same LML definition at both tools' optimum
            out["lml_exact"] = exact_lml(x, y, params["variance"], params["lengthscale"],
                                         params["noise"])
    else:
        out["m"] = len(grid)
        out["mean_fsum"] = math.fsum(mean.tolist())
        out["var_fsum"] = math.fsum(var.tolist())
        out["mean_sum_numpy"] = float(np.sum(mean))
        out["min_var"] = float(np.min(var))
        if save_pred:
            blob = b"HGPPRD01" + struct.pack("<3Q", len(grid), n, 0) \
                + np.ascontiguousarray(mean, dtype="<f8").tobytes() \
                + np.ascontiguousarray(var, dtype="<f8").tobytes()
            pred_path(n, tool).write_bytes(blob)
    out["threadpools"] = [{"api": p["internal_api"], "num_threads": p["num_threads"],
                           "lib": os.path.basename(p["filepath"])}
                          for p in threadpoolctl.threadpool_info()]
    print(json.dumps(out))


# ---------------------------------------------------------------------------------------------
# Driver

def log(msg):
    print(msg, file=sys.stderr, flush=True)


def run_worker(task, tool, n, side, threads, save_pred):
    env = dict(os.environ, OMP_NUM_THREADS=str(threads), OPENBLAS_NUM_THREADS=str(threads),
               MKL_NUM_THREADS=str(threads), PYTHONWARNINGS="ignore")
    cmd = [sys.executable, str(Path(__file__).resolve()), "--worker", task, tool, "--n", str(n),
           "--grid", str(side)] + (["--save-pred"] if save_pred else [])
    proc = subprocess.run(cmd, env=env, capture_output=True, text=True)
    if proc.returncode != 0:
        raise RuntimeError(f"worker {task} {tool} failed (status {proc.returncode}):\n{proc.stderr}")
    return json.loads(proc.stdout.strip().splitlines()[-1])


def read_pred(n, tool):
    import numpy as np
    blob = pred_path(n, tool).read_bytes()
    m = struct.unpack("<3Q", blob[8:32])[0]
    mean = np.frombuffer(blob, dtype="<f8", count=m, offset=32)
    var = np.frombuffer(blob, dtype="<f8", count=m, offset=32 + 8 * m)
    return mean, var


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--runs", type=int, help="runs per measurement (default 3, --quick 1)")
    parser.add_argument("--quick", action="store_true", help="n = 1000 (unless --n), 1 run")
    parser.add_argument("--n", type=int, help="training points (default 5000)")
    parser.add_argument("--grid", type=int, default=200, help="grid side (default 200)")
    parser.add_argument("--tools", default=",".join(TOOLS), help="comma-separated: sklearn,gpy")
    parser.add_argument("--tasks", default=",".join(TASKS), help="comma-separated: fit,opt,predict")
    parser.add_argument("--threads", type=int, default=os.cpu_count(),
                        help="BLAS/OpenMP threads of the workers (default: CPU count)")
    parser.add_argument("--worker", nargs=2, metavar=("TASK", "TOOL"), help=argparse.SUPPRESS)
    parser.add_argument("--save-pred", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    n = args.n or (1000 if args.quick else 5000)

    if args.worker:
        worker(args.worker[0], args.worker[1], n, args.grid, args.save_pred)
        return

    runs = args.runs or (1 if args.quick else 3)
    tools = [t for t in args.tools.split(",") if t]
    tasks = [t for t in args.tasks.split(",") if t]
    assert set(tools) <= set(TOOLS) and set(tasks) <= set(TASKS), (tools, tasks)

    x, y, sha = write_data(n)
    log(f"data: SplitMix64 seed {SEED}, n = {n}, wrote {data_path(n)} (sha256 {sha})")
    for i in range(3):
        log(f"data: point {i}: x0 = {x[2 * i]!r}, x1 = {x[2 * i + 1]!r}, y = {y[i]!r}")
    log(f"data: fsum(y) = {math.fsum(y)!r}, fsum(x) = {math.fsum(x)!r}")

    versions = {"python": platform.python_version()}
    import numpy
    import scipy
    versions.update(numpy=numpy.__version__, scipy=scipy.__version__)
    report = {
        "workload": {"n": n, "dim": DIM, "seed": SEED, "grid": [args.grid, args.grid],
                     "m": args.grid * args.grid, "kernel": "rbf", "variance": VARIANCE,
                     "lengthscale": LENGTHSCALE, "noise": NOISE,
                     "opt_start": {"variance": START_VARIANCE, "lengthscale": START_LENGTHSCALE,
                                   "noise": START_NOISE},
                     "data_sha256": sha, "first_points": [[x[0], x[1], y[0]], [x[2], x[3], y[1]],
                                                          [x[4], x[5], y[2]]],
                     "y_fsum": math.fsum(y)},
        "runs": runs,
        "threads": args.threads,
        "cpus": os.cpu_count(),
        "load_average_start": list(os.getloadavg()),
        "versions": versions,
        "results": {},
    }

    for task in tasks:
        for tool in tools:
            results = []
            for r in range(runs):
                res = run_worker(task, tool, n, args.grid, args.threads, save_pred=(r == 0))
                log(f"{task:8} {tool:8} run {r + 1}/{runs}: {res['seconds']:9.3f} s, "
                    f"peak RSS {res['peak_rss_mb']:8.1f} MB"
                    + (f", lml {res['lml_reported']!r}" if "lml_reported" in res else "")
                    + (f", mean fsum {res['mean_fsum']!r}" if "mean_fsum" in res else ""))
                results.append(res)
            secs = [r["seconds"] for r in results]
            first = results[0]
            versions["scikit-learn" if tool == "sklearn" else "GPy"] = first["version"]
            entry = {"median_s": statistics.median(secs), "min_s": min(secs), "max_s": max(secs),
                     "all_s": secs, "peak_rss_mb": max(r["peak_rss_mb"] for r in results),
                     "rss_before_mb": first["rss_before_mb"], "threadpools": first["threadpools"]}
            for key in ("lml_reported", "lml_exact", "params", "theta", "optimizer", "m",
                        "mean_fsum", "var_fsum", "mean_sum_numpy", "min_var"):
                if key in first:
                    entry[key] = first[key]
            if task == "opt":
                entry["lml_exact_all_runs"] = [r["lml_exact"] for r in results]
            report["results"].setdefault(task, {})[tool] = entry
            log(f"{task:8} {tool:8} median {entry['median_s']:9.3f} s "
                f"(min {entry['min_s']:.3f}, max {entry['max_s']:.3f})"
                + (f", lml_exact {entry['lml_exact']!r}, params {entry['params']}"
                   if task == "opt" else ""))

    if "predict" in tasks and set(tools) == set(TOOLS):
        import numpy as np
        (ms, vs), (mg, vg) = read_pred(n, "sklearn"), read_pred(n, "gpy")
        diff = {"mean_max_abs": float(np.max(np.abs(ms - mg))),
                "var_max_abs": float(np.max(np.abs(vs - vg)))}
        report["predict_sklearn_vs_gpy"] = diff
        log(f"predict: sklearn vs GPy: max |mean diff| {diff['mean_max_abs']:.3e}, "
            f"max |var diff| {diff['var_max_abs']:.3e} (GPy adds 1e-8 to the noise)")
    report["load_average_end"] = list(os.getloadavg())
    print(json.dumps(report))


if __name__ == "__main__":
    main()
