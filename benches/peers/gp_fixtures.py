"""Reference Gaussian-process regressions from scikit-learn and GPy, for the tests of haunts-gp.

Every case draws its data from a seeded `numpy.random.default_rng` and writes one JSON file to
gp/tests/fixtures/:

- sklearn_*.json, exact GP with fixed hyperparameters: `GaussianProcessRegressor(kernel,
  alpha=noise, optimizer=None, normalize_y=False)`. The observation noise variance σn² is
  sklearn's `alpha` (added to the diagonal of K(X, X) only), so `predict(return_std=True)`
  returns the standard deviation of the LATENT function, var = k(x, x) - k*ᵀ (K + σn² I)⁻¹ k*,
  without σn² (checked below against a direct computation). `lml` is
  `log_marginal_likelihood_value_` and `lml_gradient` is
  `log_marginal_likelihood(kernel_.theta, eval_gradient=True)[1]`, the gradient with respect
  to sklearn's log hyperparameters `kernel_.theta`, in sklearn's order (`theta_names`).
  The data-mean case fits sklearn on y - mean(y) and adds mean(y) back to the predicted mean.
- sklearn_opt_*.json, hyperparameter optimisation: kernel C*RBF + WhiteKernel (the noise is
  the WhiteKernel's hyperparameter, alpha = 0 exactly), optimizer="fmin_l_bfgs_b",
  n_restarts_optimizer=0, from a recorded starting theta with sklearn's default bounds.
- gpy_vfe_2d_300.json / gpy_fitc_2d_300.json, sparse GPs of GPy with every parameter fixed:
  `SparseGPRegression` (VarDTC inference = Titsias' collapsed VFE bound) and
  `SparseGP(..., inference_method=FITC())`, on given inducing points Z. GPy's RBF is
  k(a, b) = variance * exp(-|a - b|² / (2 lengthscale²)) (sklearn's C(variance) * RBF(lengthscale)).
  GPy adds a constant jitter to K(Z, Z) (VarDTC 1e-8, FITC 1e-6, recorded as `kuu_jitter`);
  the `no_jitter` object holds the same outputs computed with that jitter set to 0.
- gpy_vfe_opt_2d_300.json, GPy's optimised VFE bound (kernel variance, lengthscale and noise;
  the inducing points of gpy_vfe_2d_300 held fixed), best of a run and seeded restarts.

Each sklearn fixture also carries `accuracy`: sklearn's results against an independent
re-implementation in numpy extended precision (long double: kernel, Cholesky, solves; the LML
gradient by central differences of the extended-precision LML), so that a test tolerance can be
chosen knowing how exact the reference itself is. Each GPy fixture carries `check`: GPy against
the textbook dense formulas in float64.

Usage (from the project root): python3 benches/peers/gp_fixtures.py [--out-dir DIR] [--only NAME]
"""

import argparse
import math
import platform
import sys
import warnings
from pathlib import Path

import numpy as np
import scipy
import sklearn
from scipy.linalg import cho_solve, cholesky, solve_triangular
from sklearn.gaussian_process import GaussianProcessRegressor
from sklearn.gaussian_process.kernels import (
    RBF,
    ConstantKernel as C,
    ExpSineSquared,
    Matern,
    Product,
    Sum,
    WhiteKernel,
)

from rosmap import PROJECT_ROOT, write_json

try:
    import GPy
    import paramz
except ImportError:  # the sparse fixtures are then skipped with a message
    GPy = None

FIXTURES_DIR = PROJECT_ROOT / "gp" / "tests" / "fixtures"
LD = np.longdouble


def versions(with_gpy=False):
    v = {
        "script": "benches/peers/gp_fixtures.py",
        "python": platform.python_version(),
        "numpy": np.__version__,
        "scipy": scipy.__version__,
        "scikit-learn": sklearn.__version__,
    }
    if with_gpy:
        v["GPy"] = GPy.__version__
        v["paramz"] = paramz.__version__
    return v


# ---------------------------------------------------------------------------------------------
# Kernel description

FORMULAS = {
    "constant": "constant_value",
    "rbf": "exp(-0.5 * sum_i ((a_i - b_i) / length_scale_i)^2)",
    "matern": "nu=1.5: (1 + sqrt(3) r) exp(-sqrt(3) r); nu=2.5: (1 + sqrt(5) r + 5 r^2 / 3) "
              "exp(-sqrt(5) r); r = sqrt(sum_i ((a_i - b_i) / length_scale_i)^2)",
    "exp_sine_squared": "exp(-2 sin^2(pi |a - b| / periodicity) / length_scale^2)",
    "white": "noise_level if the two arguments are the same training point (K(X, X) diagonal and "
             "diag(X)), else 0; sklearn's K(X_test, X_train) is 0 even where points coincide",
}


def spec(k):
    """Natural-unit description of a sklearn kernel, nested like its k1/k2 parameter names."""
    t = type(k)
    if t is Sum or t is Product:
        return {"type": "sum" if t is Sum else "product", "k1": spec(k.k1), "k2": spec(k.k2)}
    if t is C:
        return {"type": "constant", "formula": FORMULAS["constant"],
                "constant_value": float(k.constant_value)}
    if t is Matern:  # before RBF: Matern subclasses RBF
        return {"type": "matern", "formula": FORMULAS["matern"], "nu": float(k.nu),
                "ard": bool(k.anisotropic),
                "length_scale": np.atleast_1d(k.length_scale).astype(float).tolist()}
    if t is RBF:
        return {"type": "rbf", "formula": FORMULAS["rbf"], "ard": bool(k.anisotropic),
                "length_scale": np.atleast_1d(k.length_scale).astype(float).tolist()}
    if t is ExpSineSquared:
        return {"type": "exp_sine_squared", "formula": FORMULAS["exp_sine_squared"],
                "length_scale": float(k.length_scale), "periodicity": float(k.periodicity)}
    if t is WhiteKernel:
        return {"type": "white", "formula": FORMULAS["white"], "noise_level": float(k.noise_level)}
    raise TypeError(f"no description for {t.__name__}")


def theta_names(k):
    """One name per entry of k.theta (ARD length scales get [i])."""
    names = []
    for h in k.hyperparameters:
        if h.fixed:
            continue
        if h.n_elements == 1:
            names.append(h.name)
        else:
            names.extend(f"{h.name}[{i}]" for i in range(h.n_elements))
    return names


def kernel_record(k):
    return {
        "sklearn": repr(k),
        "spec": spec(k),
        "theta": k.theta.tolist(),
        "theta_names": theta_names(k),
        "hyperparameters": [{"name": h.name, "n_elements": h.n_elements,
                             "bounds": np.asarray(h.bounds, dtype=float).tolist()}
                            for h in k.hyperparameters if not h.fixed],
        "bounds": k.bounds.tolist(),  # log space, one row per theta entry
    }


# ---------------------------------------------------------------------------------------------
# Extended-precision reference (independent of sklearn)

def ld_kernel(s, a, b, same):
    """K(a, b) in long double from a spec; `same` = a and b are the same training set."""
    t = s["type"]
    if t == "sum":
        return ld_kernel(s["k1"], a, b, same) + ld_kernel(s["k2"], a, b, same)
    if t == "product":
        return ld_kernel(s["k1"], a, b, same) * ld_kernel(s["k2"], a, b, same)
    if t == "constant":
        return np.full((len(a), len(b)), LD(s["constant_value"]))
    if t == "white":
        return np.eye(len(a), dtype=LD) * LD(s["noise_level"]) if same else np.zeros((len(a), len(b)), LD)
    if t in ("rbf", "matern"):
        ls = np.asarray(s["length_scale"], dtype=LD)
        d = (a[:, None, :] - b[None, :, :]) / ls
        r2 = np.sum(d * d, axis=2)
        if t == "rbf":
            return np.exp(-r2 / 2)
        r = np.sqrt(r2)
        if s["nu"] == 1.5:
            q = np.sqrt(LD(3)) * r
            return (1 + q) * np.exp(-q)
        if s["nu"] == 2.5:
            q = np.sqrt(LD(5)) * r
            return (1 + q + q * q / 3) * np.exp(-q)
        raise ValueError(s["nu"])
    if t == "exp_sine_squared":
        r = np.sqrt(np.sum((a[:, None, :] - b[None, :, :]) ** 2, axis=2))
        sn = np.sin(np.pi * r / LD(s["periodicity"])) / LD(s["length_scale"])
        return np.exp(-2 * sn * sn)
    raise ValueError(t)


def ld_cholesky(a):
    n = a.shape[0]
    low = np.zeros_like(a)
    for j in range(n):
        row = low[j, :j]
        low[j, j] = np.sqrt(a[j, j] - row @ row)
        low[j + 1:, j] = (a[j + 1:, j] - low[j + 1:, :j] @ row) / low[j, j]
    return low


def ld_forward(low, b):
    x = np.zeros_like(b)
    for i in range(low.shape[0]):
        x[i] = (b[i] - low[i, :i] @ x[:i]) / low[i, i]
    return x


def ld_backward(low, b):  # solves low^T x = b
    n = low.shape[0]
    x = np.zeros_like(b)
    for i in range(n - 1, -1, -1):
        x[i] = (b[i] - low[i + 1:, i] @ x[i + 1:]) / low[i, i]
    return x


def ld_lml(s, x, y, noise):
    k = ld_kernel(s, x, x, True) + np.eye(len(x), dtype=LD) * LD(noise)
    low = ld_cholesky(k)
    a = ld_backward(low, ld_forward(low, y))
    return -y @ a / 2 - np.sum(np.log(np.diag(low))) - len(x) / LD(2) * np.log(2 * LD(np.pi)), low, a


def with_theta(s, theta, names):
    """Copy of spec s with the log hyperparameters `theta` (sklearn names) put in."""
    import copy
    s = copy.deepcopy(s)
    for name, v in zip(names, theta):
        node, path = s, name.split("__")
        for p in path[:-1]:
            node = node[p]
        leaf = path[-1]
        if leaf.endswith("]"):
            leaf, i = leaf[:-1].split("[")
            node[leaf][int(i)] = np.exp(LD(v))
        elif leaf == "length_scale" and isinstance(node[leaf], list):
            node[leaf] = [np.exp(LD(v))] * len(node[leaf])
        else:
            node[leaf] = np.exp(LD(v))
    return s


def rel_err(got, ref):
    got, ref = np.asarray(got, dtype=LD), np.asarray(ref, dtype=LD)
    d = np.abs(got - ref)
    return {"max_abs": float(np.max(d)), "max_rel": float(np.max(d / np.abs(ref))),
            "max_abs_over_max_ref": float(np.max(d) / np.max(np.abs(ref)))}


def accuracy(kernel, x, y, xt, noise, mean, var, lml, grad):
    """sklearn's answer against an extended-precision computation from the kernel spec."""
    s = spec(kernel)
    xl, yl, tl = x.astype(LD), y.astype(LD), xt.astype(LD)
    ref_lml, low, a = ld_lml(s, xl, yl, noise)
    ks = ld_kernel(s, tl, xl, False)
    ref_mean = ks @ a
    v = ld_forward(low, ks.T)
    kss = np.array([ld_kernel(s, tl[i:i + 1], tl[i:i + 1], True)[0, 0] for i in range(len(tl))])
    ref_var = kss - np.sum(v * v, axis=0)
    names = theta_names(kernel)

    def central(i, h):
        tp, tm = kernel.theta.astype(LD), kernel.theta.astype(LD)
        tp[i] += h
        tm[i] -= h
        return (ld_lml(with_theta(s, tp, names), xl, yl, noise)[0]
                - ld_lml(with_theta(s, tm, names), xl, yl, noise)[0]) / (2 * h)

    # Richardson extrapolation of central differences: error O(h^4).
    h = LD(1e-5)
    ref_grad = [(4 * central(i, h / 2) - central(i, h)) / 3 for i in range(len(kernel.theta))]
    out = {
        "method": "numpy long double (80-bit x87 on x86-64): kernel from `spec`, Cholesky and "
                  "triangular solves; gradient by Richardson-extrapolated central differences of that LML "
                  "(h = 1e-5 and 5e-6 in log space)",
        "long_double_eps": float(np.finfo(LD).eps),
        "mean": rel_err(mean, ref_mean),
        "var": rel_err(var, ref_var),
        "lml": rel_err([lml], [ref_lml]),
        "lml_gradient": rel_err(grad, ref_grad),
        "min_var": float(np.min(ref_var)),
    }
    return out


# ---------------------------------------------------------------------------------------------
# Exact-GP cases

CASES = {
    # seed, n points in [lo, hi]^d, f (text and code), kernel, noise = alpha, sd of the noise
    # added to y, n_test, data_mean = fit on y - mean(y)
    "sklearn_rbf_2d_200": dict(
        seed=1, n=200, d=2, lo=0.0, hi=10.0,
        f="sin(x0) + cos(x1 / 2)", fn=lambda x: np.sin(x[:, 0]) + np.cos(x[:, 1] / 2),
        kernel=C(1.5) * RBF(1.2), noise=0.01, sd=0.1, n_test=80),
    "sklearn_ard_2d_500": dict(
        seed=2, n=500, d=2, lo=0.0, hi=10.0,
        f="sin(x0 / 1.5) + 0.5 cos(x1 / 4)",
        fn=lambda x: np.sin(x[:, 0] / 1.5) + 0.5 * np.cos(x[:, 1] / 4),
        kernel=C(2.0) * RBF([1.0, 3.0]), noise=0.0225, sd=0.15, n_test=60),
    "sklearn_matern52_1d_50": dict(
        seed=3, n=50, d=1, lo=0.0, hi=10.0,
        f="sin(x0) + 0.3 x0", fn=lambda x: np.sin(x[:, 0]) + 0.3 * x[:, 0],
        kernel=C(1.0) * Matern(0.8, nu=2.5), noise=0.04, sd=0.2, n_test=100),
    "sklearn_matern32_2d_300": dict(
        seed=4, n=300, d=2, lo=0.0, hi=10.0,
        f="sin(x0 / 2) cos(x1 / 3)", fn=lambda x: np.sin(x[:, 0] / 2) * np.cos(x[:, 1] / 3),
        kernel=C(0.7) * Matern(1.5, nu=1.5), noise=0.01, sd=0.1, n_test=60),
    "sklearn_periodic_1d_100": dict(
        seed=5, n=100, d=1, lo=0.0, hi=10.0,
        f="sin(2 pi x0 / 2.5)", fn=lambda x: np.sin(2 * np.pi * x[:, 0] / 2.5),
        kernel=C(1.0) * ExpSineSquared(length_scale=1.0, periodicity=2.5), noise=1e-3, sd=0.03,
        n_test=80),
    "sklearn_sum_2d_200": dict(
        seed=6, n=200, d=2, lo=0.0, hi=10.0,
        f="sin(x0 / 2) + 0.3 sin(3 x1)",
        fn=lambda x: np.sin(x[:, 0] / 2) + 0.3 * np.sin(3 * x[:, 1]),
        kernel=C(1.0) * RBF(2.0) + C(0.3) * Matern(0.5, nu=2.5), noise=0.01, sd=0.1, n_test=80),
    "sklearn_datamean_rbf_2d_150": dict(
        seed=7, n=150, d=2, lo=0.0, hi=10.0,
        f="5 + sin(x0) cos(x1 / 2)", fn=lambda x: 5.0 + np.sin(x[:, 0]) * np.cos(x[:, 1] / 2),
        kernel=C(1.0) * RBF(1.5), noise=0.01, sd=0.1, n_test=60, data_mean=True),
}


def draw(c):
    rng = np.random.default_rng(c["seed"])
    x = rng.uniform(c["lo"], c["hi"], size=(c["n"], c["d"]))
    y = c["fn"](x) + c["sd"] * rng.standard_normal(c["n"])
    # Test points: the training domain and a margin of 1 around it (extrapolation included).
    xt = rng.uniform(c["lo"] - 1.0, c["hi"] + 1.0, size=(c["n_test"], c["d"]))
    return x, y, xt


def exact_case(name, c):
    x, y, xt = draw(c)
    offset = float(np.mean(y)) if c.get("data_mean") else 0.0
    yc = y - offset
    gp = GaussianProcessRegressor(kernel=c["kernel"], alpha=c["noise"], optimizer=None,
                                  normalize_y=False)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # e.g. "Predicted variances smaller than 0"
        gp.fit(x, yc)
        mean, std = gp.predict(xt, return_std=True)
    mean = mean + offset
    var = std * std
    lml = float(gp.log_marginal_likelihood_value_)
    lml2, grad = gp.log_marginal_likelihood(gp.kernel_.theta, eval_gradient=True)
    assert lml2 == lml

    # The std is the latent one: k(x*, x*) - k*^T (K + alpha I)^-1 k*, no alpha added.
    k = gp.kernel_(x) + c["noise"] * np.eye(len(x))
    ks = gp.kernel_(xt, x)
    direct = gp.kernel_.diag(xt) - np.sum(ks * np.linalg.solve(k, ks.T).T, axis=1)
    assert np.max(np.abs(direct - var)) < 1e-9 * np.max(var), "std is not the latent std"
    assert np.min(np.abs(direct + c["noise"] - var)) > 0.5 * c["noise"]

    record = {
        "name": name,
        "description": f"exact GP, fixed hyperparameters: sklearn GaussianProcessRegressor("
                       f"kernel, alpha=noise, optimizer=None, normalize_y=False)"
                       + (" fitted on y - mean(y); mean(y) added back to `mean`"
                          if c.get("data_mean") else ""),
        "generator": versions(),
        "seed": c["seed"],
        "data": f"numpy default_rng({c['seed']}): x_train uniform in [{c['lo']}, {c['hi']}]^{c['d']} "
                f"(n x d draws), y = {c['f']} + {c['sd']} * standard_normal(n), then x_test "
                f"uniform in [{c['lo'] - 1}, {c['hi'] + 1}]^{c['d']}",
        "dim": c["d"],
        "n_train": c["n"],
        "n_test": c["n_test"],
        "x_train": x.tolist(),
        "y_train": y.tolist(),
        "x_test": xt.tolist(),
        "kernel": kernel_record(gp.kernel_),
        "noise": c["noise"],
        "prior_mean": ({"type": "data_mean", "value": offset} if c.get("data_mean")
                       else {"type": "zero", "value": 0.0}),
        "mean_offset": offset,
        "mean": mean.tolist(),
        "std": std.tolist(),
        "var": var.tolist(),
        "var_is_latent": True,
        "lml": lml,
        "lml_gradient": grad.tolist(),
    }
    record["accuracy"] = accuracy(gp.kernel_, x, yc, xt, c["noise"], mean - offset, var, lml, grad)
    return record


# ---------------------------------------------------------------------------------------------
# Optimisation cases

OPT_CASES = {
    "sklearn_opt_rbf_2d_300": dict(
        seed=11, n=300, d=2, lo=0.0, hi=10.0,
        f="sin(x0) cos(x1 / 2)", fn=lambda x: np.sin(x[:, 0]) * np.cos(x[:, 1] / 2), sd=0.1,
        kernel=C(0.5) * RBF(1.0) + WhiteKernel(0.1)),
    "sklearn_opt_ard_2d_200": dict(
        seed=12, n=200, d=2, lo=0.0, hi=10.0,
        f="sin(x0) + 0.5 cos(x1 / 3)",
        fn=lambda x: np.sin(x[:, 0]) + 0.5 * np.cos(x[:, 1] / 3), sd=0.1,
        kernel=C(0.5) * RBF([1.0, 1.0]) + WhiteKernel(0.1)),
}


def opt_case(name, c):
    rng = np.random.default_rng(c["seed"])
    x = rng.uniform(c["lo"], c["hi"], size=(c["n"], c["d"]))
    y = c["fn"](x) + c["sd"] * rng.standard_normal(c["n"])
    start = c["kernel"]

    runs = {}

    def recording_optimizer(obj_func, initial_theta, bounds):
        # Exactly sklearn's _constrained_optimization for "fmin_l_bfgs_b", keeping the result.
        res = scipy.optimize.minimize(obj_func, initial_theta, method="L-BFGS-B", jac=True,
                                      bounds=bounds)
        runs["res"] = res
        return res.x, res.fun

    gp = GaussianProcessRegressor(kernel=start, alpha=0.0, optimizer="fmin_l_bfgs_b",
                                  n_restarts_optimizer=0, normalize_y=False)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # ConvergenceWarning = the optimiser did not converge
        gp.fit(x, y)
    twin = GaussianProcessRegressor(kernel=start, alpha=0.0, optimizer=recording_optimizer,
                                    n_restarts_optimizer=0, normalize_y=False).fit(x, y)
    assert np.array_equal(twin.kernel_.theta, gp.kernel_.theta)
    res = runs["res"]

    lml = float(gp.log_marginal_likelihood_value_)
    lml_re, grad_opt = gp.log_marginal_likelihood(gp.kernel_.theta, eval_gradient=True)
    lml_start, grad_start = gp.log_marginal_likelihood(start.theta, eval_gradient=True)
    at_bound = [bool(np.isclose(t, lo) or np.isclose(t, hi))
                for t, (lo, hi) in zip(gp.kernel_.theta, gp.kernel_.bounds)]
    return {
        "name": name,
        "description": "exact GP, hyperparameter optimisation: sklearn GaussianProcessRegressor("
                       "kernel = start kernel, alpha=0.0, optimizer='fmin_l_bfgs_b', "
                       "n_restarts_optimizer=0, normalize_y=False). The observation noise is the "
                       "WhiteKernel's noise_level (optimised); alpha is exactly 0. scipy "
                       "L-BFGS-B with its defaults (maxcor 10, ftol 2.2e-9, gtol 1e-5, maxiter "
                       "15000) on -LML in log space within `bounds`.",
        "generator": versions(),
        "seed": c["seed"],
        "data": f"numpy default_rng({c['seed']}): x_train uniform in [{c['lo']}, {c['hi']}]^{c['d']}, "
                f"y = {c['f']} + {c['sd']} * standard_normal(n)",
        "dim": c["d"],
        "n_train": c["n"],
        "x_train": x.tolist(),
        "y_train": y.tolist(),
        "noise": 0.0,
        "prior_mean": {"type": "zero", "value": 0.0},
        "mean_offset": 0.0,
        "start_kernel": kernel_record(start),
        "theta_start": start.theta.tolist(),
        "bounds": start.bounds.tolist(),
        "lml_start": float(lml_start),
        "lml_gradient_start": grad_start.tolist(),
        "kernel": kernel_record(gp.kernel_),
        "theta_opt": gp.kernel_.theta.tolist(),
        "theta_opt_at_bound": at_bound,
        "lml": lml,
        "lml_recomputed": float(lml_re),
        "lml_gradient_opt": grad_opt.tolist(),
        "optimizer": {"method": "scipy.optimize.minimize L-BFGS-B", "nit": int(res.nit),
                      "nfev": int(res.nfev), "message": str(res.message),
                      "success": bool(res.success)},
    }


# ---------------------------------------------------------------------------------------------
# GPy sparse cases

SPARSE = dict(seed=21, n=300, d=2, lo=0.0, hi=10.0, f="sin(x0 / 2) cos(x1 / 3) + 0.02 x0",
              fn=lambda x: np.sin(x[:, 0] / 2) * np.cos(x[:, 1] / 3) + 0.02 * x[:, 0],
              sd=0.1, variance=1.2, lengthscale=1.5, noise=0.01, z_side=8, n_test=60)


def rbf(a, b, variance, lengthscale):
    d2 = np.sum((a[:, None, :] - b[None, :, :]) ** 2, axis=2)
    return variance * np.exp(-d2 / (2 * lengthscale ** 2))


def dense_sparse(kind, x, y, z, xt, variance, lengthscale, noise, jitter):
    """Textbook VFE / FITC quantities in float64 (jitter added to K(Z, Z) as GPy does)."""
    n = len(x)
    kuu = rbf(z, z, variance, lengthscale) + jitter * np.eye(len(z))
    kuf = rbf(z, x, variance, lengthscale)
    ksu = rbf(xt, z, variance, lengthscale)
    lu = cholesky(kuu, lower=True)
    vf = solve_triangular(lu, kuf, lower=True)
    qff = vf.T @ vf
    knn = np.full(n, variance)
    if kind == "vfe":
        lam = np.full(n, noise)
    else:
        lam = knn - np.diag(qff) + noise
    cov = qff + np.diag(lam)
    lc = cholesky(cov, lower=True)
    al = cho_solve((lc, True), y)
    ll = -0.5 * y @ al - np.sum(np.log(np.diag(lc))) - n / 2 * np.log(2 * np.pi)
    if kind == "vfe":
        ll -= np.sum(knn - np.diag(qff)) / (2 * noise)
    sig = kuu + (kuf / lam) @ kuf.T
    ls = cholesky(sig, lower=True)
    mean = ksu @ cho_solve((ls, True), kuf @ (y / lam))
    vs = solve_triangular(lu, ksu.T, lower=True)
    ws = solve_triangular(ls, ksu.T, lower=True)
    var = variance - np.sum(vs * vs, axis=0) + np.sum(ws * ws, axis=0)
    return ll, mean, var


def gpy_model(kind, x, y, z, p, jitter):
    """GPy sparse model with fixed parameters and `jitter` added to K(Z, Z).

    FITC adds its jitter to the *cached* K(Z, Z) in place (GPy 1.15 fitc.py:
    `diag.add(Kmm, self.const_jitter)` without a copy), so every further inference call with
    unchanged parameters adds it again: the jitter is set before the first inference and the
    model is never recomputed. VarDTC copies K(Z, Z) first and has no such problem.
    """
    kern = GPy.kern.RBF(x.shape[1], variance=p["variance"], lengthscale=p["lengthscale"])
    if kind == "vfe":
        m = GPy.models.SparseGPRegression(x, y[:, None], kernel=kern, Z=z.copy())
        m.inference_method.const_jitter = jitter  # instance attribute shadows the class default
        m.likelihood.variance = p["noise"]  # triggers the (only relevant) inference
    else:
        inference = GPy.inference.latent_function_inference.FITC()
        inference.const_jitter = jitter
        m = GPy.core.SparseGP(x, y[:, None], z.copy(), kern,
                              GPy.likelihoods.Gaussian(variance=p["noise"]),
                              inference_method=inference)
    return m


def gpy_case(kind):
    p = SPARSE
    rng = np.random.default_rng(p["seed"])
    x = rng.uniform(p["lo"], p["hi"], size=(p["n"], p["d"]))
    y = p["fn"](x) + p["sd"] * rng.standard_normal(p["n"])
    xt = rng.uniform(p["lo"] - 1.0, p["hi"] + 1.0, size=(p["n_test"], p["d"]))
    s = p["z_side"]
    centres = (np.arange(s) + 0.5) * (p["hi"] - p["lo"]) / s + p["lo"]
    z = np.array([[centres[i], centres[j]] for j in range(s) for i in range(s)])

    def run(jitter):
        m = gpy_model(kind, x, y, z, p, jitter)
        mu, var = m.predict_noiseless(xt)
        return m, float(np.squeeze(m.log_likelihood())), mu[:, 0], var[:, 0]

    default_jitter = (GPy.inference.latent_function_inference.VarDTC.const_jitter if kind == "vfe"
                      else GPy.inference.latent_function_inference.FITC.const_jitter)
    m, ll, mu, var = run(default_jitter)
    assert np.allclose(np.asarray(m.kern.variance), p["variance"], rtol=0, atol=0)
    assert np.allclose(np.asarray(m.kern.lengthscale), p["lengthscale"], rtol=0, atol=0)
    assert np.asarray(m.likelihood.variance).item() == p["noise"]
    _, ll0, mu0, var0 = run(0.0)
    # GPy's kernel is sklearn's C(variance) * RBF(lengthscale).
    sk = C(p["variance"]) * RBF(p["lengthscale"])
    # (GPy forms r^2 = |a|^2 + |b|^2 - 2 a.b, sklearn sums squared differences: they differ by
    # a few 1e-15 relative.)
    kernel_diff = float(np.max(np.abs(GPy.kern.RBF(2, p["variance"], p["lengthscale"]).K(x) - sk(x))))
    assert kernel_diff < 1e-12, kernel_diff
    exact = GaussianProcessRegressor(sk, alpha=p["noise"], optimizer=None).fit(x, y)
    exact_gpy = GPy.models.GPRegression(x, y[:, None], GPy.kern.RBF(2, p["variance"], p["lengthscale"]),
                                        noise_var=p["noise"])

    check = {"kernel_vs_sklearn_max_abs": kernel_diff}
    for label, j, got in (("default_jitter", default_jitter, (ll, mu, var)),
                          ("no_jitter", 0.0, (ll0, mu0, var0))):
        d_ll, d_mu, d_var = dense_sparse(kind, x, y, z, xt, p["variance"], p["lengthscale"],
                                         p["noise"], j)
        check[label] = {"log_likelihood_rel": abs(got[0] - d_ll) / abs(d_ll),
                        "mean_max_abs": float(np.max(np.abs(got[1] - d_mu))),
                        "var_max_abs": float(np.max(np.abs(got[2] - d_var)))}
    for c in (check["default_jitter"], check["no_jitter"]):
        assert c["log_likelihood_rel"] < 1e-9 and c["mean_max_abs"] < 1e-7 and c["var_max_abs"] < 1e-7, check

    inference = ("GPy.models.SparseGPRegression (inference VarDTC: Titsias' collapsed variational "
                 "bound, log N(y | 0, Qff + noise I) - tr(Kff - Qff) / (2 noise))" if kind == "vfe"
                 else "GPy.core.SparseGP(inference_method=GPy.inference.latent_function_inference."
                      "FITC()): log N(y | 0, Qff + diag(Kff - Qff) + noise I)")
    return {
        "name": f"gpy_{kind}_2d_300",
        "description": f"sparse GP with fixed parameters (nothing optimised): {inference}; "
                       "Qff = Kfu Kuu^-1 Kuf with Kuu = K(Z, Z) + kuu_jitter I. `mean` and `var` "
                       "from predict_noiseless (latent variance, GPy clips it below at 1e-15). "
                       "`exact_lml` is sklearn's exact LML on the same data and parameters; "
                       "`exact_lml_gpy` is GPy GPRegression's, whose exact inference always adds "
                       "1e-8 to the noise variance.",
        "generator": versions(with_gpy=True),
        "seed": p["seed"],
        "data": f"numpy default_rng({p['seed']}): x_train uniform in [{p['lo']}, {p['hi']}]^2, "
                f"y = {p['f']} + {p['sd']} * standard_normal(n), x_test uniform in "
                f"[{p['lo'] - 1}, {p['hi'] + 1}]^2; z = {s}x{s} grid of cell centres "
                f"((i + 0.5) * {(p['hi'] - p['lo']) / s}), index j*{s} + i, z = [c_i, c_j]",
        "dim": p["d"],
        "n_train": p["n"],
        "n_test": p["n_test"],
        "n_inducing": len(z),
        "x_train": x.tolist(),
        "y_train": y.tolist(),
        "x_test": xt.tolist(),
        "z": z.tolist(),
        "kernel": {
            "gpy": "GPy.kern.RBF(input_dim=2, variance, lengthscale)",
            "formula": "variance * exp(-|a - b|^2 / (2 lengthscale^2))",
            "variance": p["variance"],
            "lengthscale": p["lengthscale"],
            "sklearn_equivalent": repr(sk),
            "theta": sk.theta.tolist(),
            "theta_names": theta_names(sk),
        },
        "noise": p["noise"],
        "prior_mean": {"type": "zero", "value": 0.0},
        "inference": "vfe" if kind == "vfe" else "fitc",
        "kuu_jitter": default_jitter,
        "log_likelihood": ll,
        "mean": mu.tolist(),
        "var": var.tolist(),
        "no_jitter": {"kuu_jitter": 0.0, "log_likelihood": ll0, "mean": mu0.tolist(),
                      "var": var0.tolist()},
        "exact_lml": float(exact.log_marginal_likelihood_value_),
        "exact_lml_gpy": float(np.squeeze(exact_gpy.log_likelihood())),
        "check": check,
    }


def gpy_opt_case():
    """GPy's optimised Titsias bound on the gpy_vfe_2d_300 data with its Z held fixed.

    `SparseGPRegression` with `m.Z.fix()`: L-BFGS-B over the kernel variance, lengthscale and
    the Gaussian noise variance, from `start` and from seeded restarts (`optimize_restarts`,
    numpy seed 5); the best run is recorded. `theta_opt` is in natural-log space, in our order
    (log variance, log lengthscale, log noise). `bound_opt` is GPy's log_likelihood() at the
    optimum (with its 1e-8 jitter on K(Z, Z), checked against the textbook formula in float64);
    `no_jitter.bound_opt` is the same bound without jitter (null when K(Z, Z) is not numerically
    positive definite).
    """
    p = SPARSE
    rng = np.random.default_rng(p["seed"])
    x = rng.uniform(p["lo"], p["hi"], size=(p["n"], p["d"]))
    y = p["fn"](x) + p["sd"] * rng.standard_normal(p["n"])
    s = p["z_side"]
    centres = (np.arange(s) + 0.5) * (p["hi"] - p["lo"]) / s + p["lo"]
    z = np.array([[centres[i], centres[j]] for j in range(s) for i in range(s)])
    start = {"variance": 0.5, "lengthscale": 1.0, "noise": 0.1}
    kern = GPy.kern.RBF(2, variance=start["variance"], lengthscale=start["lengthscale"])
    m = GPy.models.SparseGPRegression(x, y[:, None], kernel=kern, Z=z.copy())
    m.Z.fix()
    m.likelihood.variance = start["noise"]
    m.optimize("lbfgsb", max_iters=5000, messages=False)
    first = float(np.squeeze(m.log_likelihood()))
    np.random.seed(5)
    m.optimize_restarts(num_restarts=5, robust=True, verbose=False, max_iters=5000)
    variance = float(np.asarray(m.kern.variance).item())
    lengthscale = float(np.asarray(m.kern.lengthscale).item())
    noise = float(np.asarray(m.likelihood.variance).item())
    assert np.array_equal(np.asarray(m.Z), z)
    bound = float(np.squeeze(m.log_likelihood()))
    dense_jit, _, _ = dense_sparse("vfe", x, y, z, x[:2], variance, lengthscale, noise,
                                   GPy.inference.latent_function_inference.VarDTC.const_jitter)
    # At the optimum K(Z, Z) is nearly singular (condition number ~1e15): without jitter the
    # float64 Cholesky may fail, and then `no_jitter.bound_opt` is null.
    try:
        dense0 = float(dense_sparse("vfe", x, y, z, x[:2], variance, lengthscale, noise, 0.0)[0])
    except np.linalg.LinAlgError:
        dense0 = None
    kuu_condition = float(np.linalg.cond(rbf(z, z, variance, lengthscale)))
    assert abs(dense_jit - bound) < 1e-8 * abs(bound), (dense_jit, bound)
    grad = m._grads(m.optimizer_array)  # of −log_likelihood, in GPy's optimiser space
    return {
        "name": "gpy_vfe_opt_2d_300",
        "description": gpy_opt_case.__doc__.strip(),
        "generator": versions(with_gpy=True),
        "seed": p["seed"],
        "data": "as gpy_vfe_2d_300.json (same x_train, y_train, z)",
        "dim": p["d"],
        "n_train": p["n"],
        "n_inducing": len(z),
        "x_train": x.tolist(),
        "y_train": y.tolist(),
        "z": z.tolist(),
        "start": start,
        "optimiser": "GPy 1.15 m.optimize('lbfgsb') then m.optimize_restarts(5, robust=True)",
        "bound_first_run": first,
        "variance": variance,
        "lengthscale": lengthscale,
        "noise": noise,
        "theta_opt": [math.log(variance), math.log(lengthscale), math.log(noise)],
        "kuu_jitter": GPy.inference.latent_function_inference.VarDTC.const_jitter,
        "bound_opt": bound,
        "gpy_gradient_norm_at_opt": float(np.linalg.norm(grad)),
        "kuu_condition_number_at_opt": kuu_condition,
        "no_jitter": {"kuu_jitter": 0.0, "bound_opt": dense0},
    }


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out-dir", default=FIXTURES_DIR, help="directory of the fixture files")
    parser.add_argument("--only", help="write only the fixture of this name (without .json)")
    args = parser.parse_args()

    jobs = [(n, lambda n=n, c=c: exact_case(n, c)) for n, c in CASES.items()]
    jobs += [(n, lambda n=n, c=c: opt_case(n, c)) for n, c in OPT_CASES.items()]
    jobs += [(f"gpy_{k}_2d_300", lambda k=k: gpy_case(k)) for k in ("vfe", "fitc")]
    jobs.append(("gpy_vfe_opt_2d_300", gpy_opt_case))
    total = 0
    for name, job in jobs:
        if args.only and name != args.only:
            continue
        if name.startswith("gpy_") and GPy is None:
            print(f"{name}: skipped, GPy is not installed", file=sys.stderr)
            continue
        record = job()
        path = Path(args.out_dir) / f"{name}.json"
        size = write_json(path, record)
        total += size
        summary = f"lml {record.get('lml', record.get('log_likelihood', record.get('bound_opt')))!r}"
        if "accuracy" in record:
            a = record["accuracy"]
            summary += (f", sklearn vs long double: mean {a['mean']['max_abs_over_max_ref']:.1e}, "
                        f"var {a['var']['max_rel']:.1e} (rel), lml {a['lml']['max_rel']:.1e}, "
                        f"grad {a['lml_gradient']['max_rel']:.1e}")
        if "check" in record:
            summary += f", check {record['check']}"
        if "optimizer" in record:
            summary += f", theta_opt {record['theta_opt']}, nit {record['optimizer']['nit']}"
        print(f"{name}: {summary}")
        print(f"wrote {path} ({size} bytes)")
    print(f"total {total} bytes")


if __name__ == "__main__":
    main()
