"""NumPy peer of haunts-affordance's Gustafson–Kessel clustering (issue 7's performance target).

Workload (mirror of affordance/benches/gk.rs; change both together):
  k = 30 clusters, fuzzifier m = 2, volume rho = 1, n = 50 000 points in 4-D hypertime
  (x, y, cos 2πt/24h, sin 2πt/24h), the default regularisation of haunts' GkParams: identity
  blending gamma = 0, eigenvalue ratio beta = 100, eigenvalue floor eps = 1e-9.

Data: SplitMix64 with seed 7, no other RNG, so that Rust regenerates it bit for bit:
  next_u64():  state = state + 0x9E3779B97F4A7C15 (mod 2^64); z = state;
               z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9 (mod 2^64);
               z = (z ^ (z >> 27)) * 0x94D049BB133111EB (mod 2^64);
               return z ^ (z >> 31)
  u():         (next_u64() >> 11) * 2^-53                                   in [0, 1)
  12 places, in order: px = 40 u(); py = 20 u(); hour = 24 u()
  each point, in order: place = next_u64() mod 12; u1, u2, u3, u4 = u() (four draws);
      r = sqrt(-2 ln(1 - u1))
      x = px + 1.5 * r * cos(TAU * u2);   y = py + r * sin(TAU * u2)
      t = hour + 1.5 * sqrt(-2 ln(1 - u3)) * cos(TAU * u4)          (hours)
      phase = TAU * t / 24;  point = (x, y, cos(phase), sin(phase))
  (TAU = 2π = 6.283185307179586; libm, glibc here, on both sides. The sha256 of the points as
  little-endian f64, row-major, is printed by both sides and compared by compare_gk.sh.)
  Initial centres: rows i * (n // k), i = 0 .. k-1; initial covariances the identity, so the
  first norm matrices are rho^(1/d) I.

One iteration (haunts' GkParams::fit docs; seed 001 eqs. 2-7), vectorised over all points
and clusters at once:
  1. d2[i, j] = (x_j - c_i)^T A_i (x_j - c_i), clipped below at 0;
  2. u[i, j] = 1 / sum_k (d2[i, j] / d2[k, j])^(1/(m-1)), computed as r_i / sum_k r_k with
     r_i = (min_k d2[k, j] / d2[i, j])^(1/(m-1)); a point at distance 0 from one or more
     prototypes shares its membership equally among them;
  3. w = u^m; objective J = sum w * d2 (with the prototypes before the update);
     c_i = sum_j w x_j / sum_j w; F_i = sum_j w (x_j - c_i)(x_j - c_i)^T / sum_j w;
  4. regularisation: F <- (1 - gamma) F + gamma nu I (nu = det(F_0)^(1/d) of the whole data
     set), eigenvalues raised to max(lambda_max / beta, eps); A_i = (rho det F_i)^(1/d) F_i^-1
     from the eigen-decomposition (np.linalg.eigh), so det A_i = rho.
  A cluster whose total weight is 0 keeps its prototype (never happens here).

Timed (time.perf_counter): one iteration, on a state `--warmup` (3) iterations in, each
iteration timed on its own, `--runs` (30) of them; the median is reported. Checked: `--check`
(10) iterations from the initial centres, untimed: every objective, the final centres and the
largest membership change.

Threads: OMP_NUM_THREADS / OPENBLAS_NUM_THREADS / MKL_NUM_THREADS are set to `--threads`
(default 2) before NumPy is imported (only the batched matmuls and eigh use BLAS/LAPACK).

Usage (from the project root):
  python3 benches/peers/gk_numpy.py [--runs 30] [--warmup 3] [--check 10] [--threads 2]
Human-readable lines go to stderr, one JSON object to stdout.
"""

import argparse
import hashlib
import json
import math
import os
import platform
import statistics
import struct
import sys
import time

from splitmix import SplitMix64

SEED = 7
N, DIM, K = 50_000, 4, 30
PLACES = 12
M, VOLUME = 2.0, 1.0
IDENTITY_BLEND, MAX_CONDITION, MIN_EIGENVALUE = 0.0, 1e2, 1e-9


def generate(n=N, seed=SEED):
    """The points as a flat row-major list of n * 4 floats (see the module docstring)."""
    rng = SplitMix64(seed)
    places = []
    for _ in range(PLACES):
        px = 40.0 * rng.uniform()
        py = 20.0 * rng.uniform()
        hour = 24.0 * rng.uniform()
        places.append((px, py, hour))
    out = []
    for _ in range(n):
        px, py, hour = places[rng.next_u64() % PLACES]
        u1, u2, u3, u4 = rng.uniform(), rng.uniform(), rng.uniform(), rng.uniform()
        r = math.sqrt(-2.0 * math.log(1.0 - u1))
        x = px + 1.5 * r * math.cos(math.tau * u2)
        y = py + r * math.sin(math.tau * u2)
        t = hour + 1.5 * math.sqrt(-2.0 * math.log(1.0 - u3)) * math.cos(math.tau * u4)
        phase = math.tau * t / 24.0
        out += [x, y, math.cos(phase), math.sin(phase)]
    return out


def data_scale(np, x):
    """nu = det(F_0)^(1/d) of the whole data set (its mean variance if singular)."""
    f0 = np.cov(x, rowvar=False, bias=True)
    lam = np.linalg.eigvalsh(f0)
    if np.all(lam > 0):
        return float(np.exp(np.log(lam).sum() / x.shape[1]))
    return max(float(lam.sum() / x.shape[1]), 0.0)


def norm_matrices(np, f):
    """Regularised covariances and their norm-inducing matrices A = (rho det F)^(1/d) F^-1."""
    d = f.shape[-1]
    lam, vec = np.linalg.eigh(f)
    floor = np.maximum(lam.max(axis=1) / MAX_CONDITION, MIN_EIGENVALUE)
    lam = np.maximum(lam, floor[:, None])
    scale = np.exp((math.log(VOLUME) + np.log(lam).sum(axis=1)) / d)
    a = (vec * (scale[:, None] / lam)[:, None, :]) @ vec.transpose(0, 2, 1)
    f_reg = (vec * lam[:, None, :]) @ vec.transpose(0, 2, 1)
    return f_reg, a


def iterate(np, x, centres, a, nu, u_old):
    """One GK iteration; returns (centres, covariances, norm matrices, memberships, J)."""
    k, d = centres.shape
    diff = x[None, :, :] - centres[:, None, :]                       # (k, n, d)
    d2 = np.einsum("knd,knd->kn", diff @ a, diff)                    # (x-c)^T A (x-c)
    np.maximum(d2, 0.0, out=d2)
    dmin = d2.min(axis=0)                                            # (n,)
    with np.errstate(divide="ignore", invalid="ignore"):
        r = dmin / d2
    if M != 2.0:
        r **= 1.0 / (M - 1.0)
    u = r / r.sum(axis=0)
    on_prototype = dmin <= 0.0                                       # points on a prototype
    if on_prototype.any():
        zero = d2[:, on_prototype] <= 0.0
        u[:, on_prototype] = zero / zero.sum(axis=0)
    w = u * u if M == 2.0 else u ** M
    objective = float(np.sum(w * d2))
    total = w.sum(axis=1)                                            # (k,)
    new_centres = (w @ x) / total[:, None]
    diff = x[None, :, :] - new_centres[:, None, :]
    f = (w[:, :, None] * diff).transpose(0, 2, 1) @ diff / total[:, None, None]
    if IDENTITY_BLEND > 0.0:
        f = (1.0 - IDENTITY_BLEND) * f + IDENTITY_BLEND * nu * np.eye(d)
    f_reg, a_new = norm_matrices(np, f)
    keep = ~(total > 0.0)
    new_centres[keep], a_new[keep] = centres[keep], a[keep]
    change = math.inf if u_old is None else float(np.abs(u - u_old).max())
    return new_centres, f_reg, a_new, u, objective, change


def start(np, x):
    centres = x[[i * (N // K) for i in range(K)]].copy()
    a = np.broadcast_to(np.eye(DIM) * VOLUME ** (1.0 / DIM), (K, DIM, DIM)).copy()
    return centres, a


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--runs", type=int, default=30, help="timed iterations (median reported)")
    ap.add_argument("--warmup", type=int, default=3, help="iterations before timing")
    ap.add_argument("--check", type=int, default=10, help="iterations of the agreement check")
    ap.add_argument("--threads", type=int, default=2, help="BLAS threads")
    args = ap.parse_args()
    for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ[var] = str(args.threads)
    import numpy as np

    t0 = time.perf_counter()
    flat = generate()
    blob = struct.pack(f"<{len(flat)}d", *flat)
    x = np.frombuffer(blob, dtype="<f8").reshape(N, DIM).copy()
    sha = hashlib.sha256(blob).hexdigest()
    nu = data_scale(np, x)
    print(f"data: n={N} dim={DIM} sha256={sha} ({time.perf_counter() - t0:.1f} s)", file=sys.stderr)

    centres, a = start(np, x)
    u, objectives, change = None, [], math.inf
    for _ in range(args.check):
        centres, _, a, u, objective, change = iterate(np, x, centres, a, nu, u)
        objectives.append(objective)
    check_centres = centres.copy()
    print(f"check: {args.check} iterations, objective {objectives[-1]!r}, change {change!r}",
          file=sys.stderr)

    centres, a = start(np, x)
    u = None
    for _ in range(args.warmup):
        centres, _, a, u, _, _ = iterate(np, x, centres, a, nu, u)
    times = []
    for _ in range(args.runs):
        t = time.perf_counter()
        centres, _, a, u, _, _ = iterate(np, x, centres, a, nu, u)
        times.append(time.perf_counter() - t)
    median = statistics.median(times)
    print(f"numpy GK iteration: median {median * 1e3:.1f} ms over {args.runs} "
          f"(min {min(times) * 1e3:.1f}, max {max(times) * 1e3:.1f})", file=sys.stderr)

    try:
        from threadpoolctl import threadpool_info
        pools = [{k: p.get(k) for k in ("internal_api", "version", "num_threads")}
                 for p in threadpool_info()]
    except ImportError:
        pools = None
    print(json.dumps({
        "tool": "numpy",
        "versions": {"python": platform.python_version(), "numpy": np.__version__},
        "threads": args.threads,
        "threadpools": pools,
        "cpus": os.cpu_count(),
        "load_average": os.getloadavg(),
        "workload": {"n": N, "dim": DIM, "k": K, "m": M, "seed": SEED, "data_sha256": sha,
                     "first_point": flat[:DIM]},
        "runs": args.runs,
        "median_s": median,
        "min_s": min(times),
        "max_s": max(times),
        "all_s": times,
        "check": {"iterations": args.check, "objectives": objectives, "change": change,
                  "centres": check_centres.ravel().tolist()},
    }))


if __name__ == "__main__":
    main()
