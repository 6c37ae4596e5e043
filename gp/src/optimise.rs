//! Hyperparameter optimisation: maximise the log marginal likelihood over the kernel's log
//! hyperparameters (and log σn²) with L-BFGS, within bounds, from the current values and from
//! seeded random restarts.
//!
//! **Bounds.** argmin's L-BFGS is unconstrained, so each bounded log parameter θ ∈ (lo, hi) is
//! optimised through θ = lo + (hi − lo)·s(z) with the logistic s and z ∈ R. The map is smooth
//! and monotone: interior optima are the same, an optimum on a bound is approached as z → ±∞
//! (its likelihood to within the gradient tolerance). Bounds are each kernel's
//! [`log_bounds`](crate::Kernel::log_bounds) (scikit-learn's (1e-5, 1e5) by default) and
//! [`OptimiseOptions::noise_bounds`] for σn².
//!
//! **Large n.** When n is at least twice [`OptimiseOptions::warm_start_subset`] = s, runs on
//! random subsets (seeded) of s, 2.5s, 6.25s, … points (while at most n/2 and at most
//! [`OptimiseOptions::warm_start_max`]) come first, each starting from the previous optimum,
//! and the full-data run starts from the last one, so most likelihood evaluations cost O(s³)
//! instead of O(n³). The final model is always optimised and fitted on all the data (with
//! [`OptimiseOptions::polish_evaluations`] set, in that many full-data evaluations at most).

use std::sync::Mutex;

use argmin::core::{CostFunction, Executor, Gradient};
use argmin::solver::linesearch::MoreThuenteLineSearch;
use argmin::solver::quasinewton::LBFGS;
use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};

use crate::error::{GpError, Result};
use crate::exact::{ExactGp, GpRegression};
use crate::kernel::check_points;

/// Options of [`GpRegression::fit_optimised`].
#[derive(Debug, Clone, PartialEq)]
pub struct OptimiseOptions {
    /// Whether σn² is optimised too (else it stays as configured).
    pub optimise_noise: bool,
    /// Bounds of σn² in natural units, used when `optimise_noise` (scikit-learn's
    /// `WhiteKernel` default (1e-5, 1e5)).
    pub noise_bounds: (f64, f64),
    /// Random restarts after the run from the current hyperparameters (scikit-learn's
    /// `n_restarts_optimizer`); starts are uniform in the log bounds.
    pub restarts: usize,
    /// Seed of the restarts and of the warm-start subset.
    pub seed: u64,
    /// L-BFGS iterations per run.
    pub max_iters: u64,
    /// L-BFGS history length.
    pub memory: usize,
    /// Stop when the gradient norm (in the unbounded variables) falls below this.
    pub grad_tolerance: f64,
    /// Points of the warm-start run; 0 disables it (see the module documentation).
    pub warm_start_subset: usize,
    /// The largest warm-start subset; 0 (the default) allows up to n/2 points.
    pub warm_start_max: usize,
    /// Full-data evaluations the Newton polish after the warm starts may use; when they are
    /// spent it stops at its best point (no full-data L-BFGS after it). 0 (the default): up
    /// to 13, and L-BFGS on all the data finishes an unconverged polish. A cap trades a
    /// little of the optimum for time where one evaluation is expensive (the sparse GP on
    /// 10⁶ points: see [`crate::SparseGpRegression::fit_optimised`]).
    pub polish_evaluations: usize,
}

impl Default for OptimiseOptions {
    fn default() -> Self {
        Self {
            optimise_noise: true,
            noise_bounds: (1e-5, 1e5),
            restarts: 0,
            seed: 0,
            max_iters: 200,
            memory: 10,
            grad_tolerance: 1e-6,
            warm_start_subset: 1000,
            warm_start_max: 0,
            polish_evaluations: 0,
        }
    }
}

impl OptimiseOptions {
    /// Checks each field's rule.
    ///
    /// # Errors
    /// [`GpError::InvalidParameter`] naming the field.
    pub fn check(&self) -> Result<()> {
        let (lo, hi) = self.noise_bounds;
        if !(lo.is_finite() && hi.is_finite() && lo > 0.0 && hi > lo) {
            return Err(GpError::invalid(
                "noise_bounds",
                lo,
                "0 < low < high, finite",
            ));
        }
        if self.max_iters == 0 {
            return Err(GpError::invalid("max_iters", 0.0, ">= 1"));
        }
        if self.memory == 0 {
            return Err(GpError::invalid("memory", 0.0, ">= 1"));
        }
        if !(self.grad_tolerance.is_finite() && self.grad_tolerance > 0.0) {
            return Err(GpError::invalid(
                "grad_tolerance",
                self.grad_tolerance,
                "finite and > 0",
            ));
        }
        Ok(())
    }
}

/// What an optimisation did.
#[derive(Debug, Clone, PartialEq)]
pub struct OptimisationReport {
    /// The best log marginal likelihood (of the returned model, on all the data).
    pub log_marginal_likelihood: f64,
    /// Its log hyperparameters: the kernel's, then log σn² if optimised.
    pub log_params: Vec<f64>,
    /// Likelihood evaluations on all the data.
    pub full_evaluations: usize,
    /// Likelihood evaluations on the warm-start subset.
    pub subset_evaluations: usize,
    /// Runs (the first plus the restarts) whose likelihood could be evaluated.
    pub runs: usize,
}

/// One evaluation: z, −log p and −∂ log p/∂z.
type Evaluation = (Vec<f64>, f64, Vec<f64>);

/// The objective in the unbounded variables z, with a one-entry cache so that argmin's
/// separate cost and gradient calls fit the GP once.
struct Objective<'a> {
    lik: &'a dyn Likelihood,
    x: &'a [f64],
    y: &'a [f64],
    bounds: Vec<(f64, f64)>,
    cache: Mutex<Option<Evaluation>>,
    /// The lowest cost evaluated since the last `take_best`, and where.
    best: Mutex<Option<(Vec<f64>, f64)>>,
    evaluations: Mutex<usize>,
}

fn logistic(z: f64) -> f64 {
    1.0 / (1.0 + (-z).exp())
}

impl Objective<'_> {
    fn theta(&self, z: &[f64]) -> Vec<f64> {
        z.iter()
            .zip(&self.bounds)
            .map(|(&z, &(lo, hi))| lo + (hi - lo) * logistic(z))
            .collect()
    }

    fn z_of(&self, theta: &[f64]) -> Vec<f64> {
        theta
            .iter()
            .zip(&self.bounds)
            .map(|(&t, &(lo, hi))| {
                // Keep strictly inside so that z is finite.
                let s = ((t - lo) / (hi - lo)).clamp(1e-12, 1.0 - 1e-12);
                (s / (1.0 - s)).ln()
            })
            .collect()
    }

    /// (−log p, −∂ log p/∂z) at z.
    fn evaluate(&self, z: &[f64]) -> Result<(f64, Vec<f64>)> {
        if let Ok(cache) = self.cache.lock()
            && let Some((cz, c, g)) = cache.as_ref()
            && cz.as_slice() == z
        {
            return Ok((*c, g.clone()));
        }
        let theta = self.theta(z);
        let (lml, grad) = self.lik.evaluate(&theta, self.x, self.y)?;
        if let Ok(mut e) = self.evaluations.lock() {
            *e += 1;
        }
        let g: Vec<f64> = grad
            .iter()
            .zip(z.iter().zip(&self.bounds))
            .map(|(g, (&z, &(lo, hi)))| {
                let s = logistic(z);
                -g * (hi - lo) * s * (1.0 - s)
            })
            .collect();
        if !lml.is_finite() || g.iter().any(|v| !v.is_finite()) {
            return Err(GpError::OptimisationFailed {
                reason: "non-finite likelihood or gradient".into(),
            });
        }
        if let Ok(mut cache) = self.cache.lock() {
            *cache = Some((z.to_vec(), -lml, g.clone()));
        }
        if let Ok(mut best) = self.best.lock()
            && best.as_ref().is_none_or(|(_, c)| -lml < *c)
        {
            *best = Some((z.to_vec(), -lml));
        }
        Ok((-lml, g))
    }

    fn evaluations(&self) -> usize {
        self.evaluations.lock().map_or(0, |e| *e)
    }
}

/// argmin takes its problem by value: a borrowed objective.
struct Problem<'o, 'a>(&'o Objective<'a>);

impl CostFunction for Problem<'_, '_> {
    type Param = Vec<f64>;
    type Output = f64;
    fn cost(&self, z: &Self::Param) -> std::result::Result<f64, argmin::core::Error> {
        // A failed fit (e.g. a kernel overflow far out in the bounds) is a very bad point for
        // the line search, not the end of the run.
        Ok(self.0.evaluate(z).map_or(f64::MAX / 4.0, |(c, _)| c))
    }
}

impl Gradient for Problem<'_, '_> {
    type Param = Vec<f64>;
    type Gradient = Vec<f64>;
    fn gradient(&self, z: &Self::Param) -> std::result::Result<Vec<f64>, argmin::core::Error> {
        Ok(self.0.evaluate(z).map_or(vec![0.0; z.len()], |(_, g)| g))
    }
}

/// Runs L-BFGS from `theta0`; returns the best θ and its log likelihood.
fn run(
    objective: &Objective<'_>,
    theta0: &[f64],
    options: &OptimiseOptions,
    tolerance_cost: f64,
) -> Option<(Vec<f64>, f64)> {
    let z0 = objective.z_of(theta0);
    if let Ok(mut best) = objective.best.lock() {
        *best = None;
    }
    objective.evaluate(&z0).ok()?;
    let solver = LBFGS::new(MoreThuenteLineSearch::new(), options.memory)
        .with_tolerance_grad(options.grad_tolerance)
        .ok()?
        .with_tolerance_cost(tolerance_cost)
        .ok()?;
    // Whether the run ends normally or in a line-search failure, the best point it evaluated
    // is the answer (never worse than argmin's own best).
    let _ = Executor::new(Problem(objective), solver)
        .configure(|state| state.param(z0).max_iters(options.max_iters))
        .run();
    let (z, cost) = objective.best.lock().ok()?.take()?;
    Some((objective.theta(&z), -cost))
}

/// A log likelihood (or bound) and its gradient over log parameters θ, on any subset of the
/// data: what [`maximise`] optimises.
pub(crate) trait Likelihood: Sync {
    /// `(value, ∂value/∂θ)` at θ on the points `x` and targets `y`.
    fn evaluate(&self, theta: &[f64], x: &[f64], y: &[f64]) -> Result<(f64, Vec<f64>)>;
    /// The dimension of the points.
    fn dim(&self) -> usize;
    /// The change of value below which an L-BFGS run on a warm-start subset of `n` points
    /// stops (it only needs to land near the optimum).
    fn warm_cost_tolerance(&self, _n: usize) -> f64 {
        1e-12
    }
}

/// What [`maximise`] found.
pub(crate) struct Maximum {
    pub(crate) theta: Vec<f64>,
    pub(crate) full_evaluations: usize,
    pub(crate) subset_evaluations: usize,
    pub(crate) runs: usize,
}

/// Maximises `lik` from `theta0` and seeded restarts within `bounds`, with staged warm starts
/// on subsets (see the module documentation).
pub(crate) fn maximise(
    lik: &dyn Likelihood,
    x: &[f64],
    y: &[f64],
    theta0: Vec<f64>,
    bounds: Vec<(f64, f64)>,
    options: &OptimiseOptions,
) -> Result<Maximum> {
    let dim = lik.dim();
    let n = y.len();
    let mut rng = StdRng::seed_from_u64(options.seed);
    let mut starts = vec![theta0];
    for _ in 0..options.restarts {
        starts.push(
            bounds
                .iter()
                .map(|&(lo, hi)| rng.random_range(lo..=hi))
                .collect(),
        );
    }
    // Warm start: each run first on random subsets growing by 2.5× (s, 2.5s, …, while at
    // most n/2), each stage starting from the previous stage's optimum.
    let mut subset = options.warm_start_subset;
    let mut subset_evaluations = 0;
    let mut last_subset: Option<(Vec<f64>, Vec<f64>)> = None;
    while subset > 0
        && 2 * subset <= n
        && (options.warm_start_max == 0 || subset <= options.warm_start_max)
    {
        let idx = sample_indices(n, subset, &mut rng);
        let xs: Vec<f64> = idx
            .iter()
            .flat_map(|&i| x[i * dim..(i + 1) * dim].iter().copied())
            .collect();
        let ys: Vec<f64> = idx.iter().map(|&i| y[i]).collect();
        let sub = Objective::new(lik, &xs, &ys, bounds.clone());
        // A warm start only needs to land near the optimum: looser tolerances.
        let loose = OptimiseOptions {
            grad_tolerance: options.grad_tolerance.max(1e-3),
            max_iters: options.max_iters.min(50),
            ..options.clone()
        };
        for start in &mut starts {
            if let Some((theta, _)) = run(&sub, start, &loose, lik.warm_cost_tolerance(ys.len())) {
                *start = theta;
            }
        }
        subset_evaluations += sub.evaluations();
        last_subset = Some((xs, ys));
        subset = subset * 5 / 2;
    }
    let full = Objective::new(lik, x, y, bounds.clone());
    let mut best: Option<(Vec<f64>, f64)> = None;
    let mut runs = 0;
    let mut polish_evaluations = 0;
    for start in &starts {
        // After warm starts, a Newton polish with the subset's Hessian (scaled to n) usually
        // converges in a few full-data evaluations; L-BFGS finishes whatever it leaves.
        let mut from = start.clone();
        if let Some((xs, ys)) = &last_subset {
            let (outcome, evals) = polish(lik, x, y, xs, ys, start, &bounds, options);
            polish_evaluations += evals;
            subset_evaluations += 2 * start.len();
            match outcome {
                Polish::Converged(theta, value) => {
                    runs += 1;
                    if best.as_ref().is_none_or(|(_, b)| value > *b) {
                        best = Some((theta, value));
                    }
                    continue;
                }
                Polish::Unfinished(theta) => from = theta,
            }
        }
        if let Some((theta, value)) = run(&full, &from, options, 1e-12) {
            runs += 1;
            if best.as_ref().is_none_or(|(_, b)| value > *b) {
                best = Some((theta, value));
            }
        }
    }
    let (theta, _) = best.ok_or_else(|| GpError::OptimisationFailed {
        reason: "the likelihood could not be evaluated at any start".into(),
    })?;
    Ok(Maximum {
        theta,
        full_evaluations: full.evaluations() + polish_evaluations,
        subset_evaluations,
        runs,
    })
}

/// How a [`polish`] ended.
enum Polish {
    /// At a maximum: θ and its value.
    Converged(Vec<f64>, f64),
    /// Not converged: the best θ reached.
    Unfinished(Vec<f64>),
}

/// Newton iterations on all the data from `theta`, with the Hessian estimated by central
/// differences of the gradient on the last warm-start subset `(xs, ys)` and scaled by
/// n / subset size (the log likelihood is a sum over points), then refined by BFGS updates.
/// Converged when a step's predicted gain falls below `1e-10 · max(1, |value|)`. Returns the
/// outcome and the number of full-data evaluations.
#[allow(clippy::too_many_arguments)]
fn polish(
    lik: &dyn Likelihood,
    x: &[f64],
    y: &[f64],
    xs: &[f64],
    ys: &[f64],
    theta: &[f64],
    bounds: &[(f64, f64)],
    options: &OptimiseOptions,
) -> (Polish, usize) {
    let p = theta.len();
    let clamp = |t: &mut Vec<f64>| {
        for (v, &(lo, hi)) in t.iter_mut().zip(bounds) {
            *v = v.clamp(lo, hi);
        }
    };
    // Hessian on the subset.
    let h = 1e-4;
    let mut hess = vec![vec![0.0; p]; p];
    for j in 0..p {
        let (mut up, mut down) = (theta.to_vec(), theta.to_vec());
        up[j] += h;
        down[j] -= h;
        let (Ok((_, gu)), Ok((_, gd))) = (lik.evaluate(&up, xs, ys), lik.evaluate(&down, xs, ys))
        else {
            return (Polish::Unfinished(theta.to_vec()), 0);
        };
        for i in 0..p {
            hess[i][j] = (gu[i] - gd[i]) / (2.0 * h) * (y.len() as f64 / ys.len() as f64);
        }
    }
    let symmetric: Vec<Vec<f64>> = (0..p)
        .map(|i| (0..p).map(|j| 0.5 * (hess[i][j] + hess[j][i])).collect())
        .collect();
    let mut hess = symmetric;
    let mut evals = 0;
    let mut current = theta.to_vec();
    let Ok((mut value, mut grad)) = lik.evaluate(&current, x, y) else {
        return (Polish::Unfinished(current), evals);
    };
    evals += 1;
    let cap = options.polish_evaluations;
    for _ in 0..options.max_iters.min(12) {
        if cap > 0 && evals >= cap {
            return (Polish::Converged(current, value), evals);
        }
        // Newton step δ = −H⁻¹ g for the maximum (−H positive definite).
        let Some(delta) = solve_negative_definite(&hess, &grad) else {
            return (Polish::Unfinished(current), evals);
        };
        let gain: f64 = 0.5 * delta.iter().zip(&grad).map(|(d, g)| d * g).sum::<f64>();
        if gain.abs() <= 1e-10 * value.abs().max(1.0) {
            return (Polish::Converged(current, value), evals);
        }
        let mut step = 1.0;
        let mut accepted = false;
        for _ in 0..4 {
            if cap > 0 && evals >= cap {
                return (Polish::Converged(current, value), evals);
            }
            let mut next: Vec<f64> = current
                .iter()
                .zip(&delta)
                .map(|(c, d)| c + step * d)
                .collect();
            clamp(&mut next);
            let Ok((v, g)) = lik.evaluate(&next, x, y) else {
                step *= 0.5;
                continue;
            };
            evals += 1;
            if v >= value {
                // BFGS update of the Hessian (of −f: s = next − current, yv = −(g − grad)).
                let sv: Vec<f64> = next.iter().zip(&current).map(|(a, b)| a - b).collect();
                let yv: Vec<f64> = g.iter().zip(&grad).map(|(a, b)| -(a - b)).collect();
                bfgs_update(&mut hess, &sv, &yv);
                current = next;
                value = v;
                grad = g;
                accepted = true;
                break;
            }
            step *= 0.5;
        }
        if !accepted {
            return (Polish::Unfinished(current), evals);
        }
    }
    (Polish::Unfinished(current), evals)
}

/// δ = −H⁻¹ g for a negative definite H (Cholesky of −H), or `None` if −H is not positive
/// definite.
fn solve_negative_definite(hess: &[Vec<f64>], grad: &[f64]) -> Option<Vec<f64>> {
    let p = grad.len();
    let neg = faer::Mat::from_fn(p, p, |i, j| -hess[i][j]);
    let llt = neg.llt(faer::Side::Lower).ok()?;
    let rhs = faer::Mat::from_fn(p, 1, |i, _| grad[i]);
    let sol = faer::linalg::solvers::Solve::solve(&llt, rhs);
    let out: Vec<f64> = (0..p).map(|i| sol[(i, 0)]).collect();
    out.iter().all(|v| v.is_finite()).then_some(out)
}

/// BFGS update of the Hessian of −f stored negated in `hess` (so `hess` stays the Hessian of
/// f), skipped when the curvature condition fails.
fn bfgs_update(hess: &mut [Vec<f64>], s: &[f64], y: &[f64]) {
    let p = s.len();
    // B = −hess is the Hessian of −f.
    let b: Vec<Vec<f64>> = hess
        .iter()
        .map(|r| r.iter().map(|v| -v).collect())
        .collect();
    let ys: f64 = y.iter().zip(s).map(|(a, b)| a * b).sum();
    let bs: Vec<f64> = (0..p)
        .map(|i| (0..p).map(|j| b[i][j] * s[j]).sum())
        .collect();
    let sbs: f64 = s.iter().zip(&bs).map(|(a, b)| a * b).sum();
    if ys <= 1e-12 || sbs <= 1e-300 {
        return;
    }
    for i in 0..p {
        for j in 0..p {
            hess[i][j] = -(b[i][j] - bs[i] * bs[j] / sbs + y[i] * y[j] / ys);
        }
    }
}

/// The exact GP's log marginal likelihood as a [`Likelihood`].
struct ExactLikelihood<'a> {
    base: &'a GpRegression,
    dim: usize,
    optimise_noise: bool,
}

impl ExactLikelihood<'_> {
    /// The configured regression at log parameters θ.
    fn model_at(&self, theta: &[f64]) -> Result<GpRegression> {
        let mut kernel = self.base.kernel().clone_box();
        let p = kernel.n_params();
        kernel.set_log_params(&theta[..p])?;
        let mut gp = self.base.clone().with_kernel(kernel);
        if self.optimise_noise {
            gp = gp.noise(theta[p].exp());
        }
        Ok(gp)
    }
}

impl Likelihood for ExactLikelihood<'_> {
    fn evaluate(&self, theta: &[f64], x: &[f64], y: &[f64]) -> Result<(f64, Vec<f64>)> {
        let fitted = self.model_at(theta)?.fit(x, self.dim, y)?;
        let mut grad = fitted.log_marginal_likelihood_gradient();
        if !self.optimise_noise {
            grad.pop();
        }
        Ok((fitted.log_marginal_likelihood(), grad))
    }
    fn dim(&self) -> usize {
        self.dim
    }
}

/// `(low, high)` per log parameter.
type Bounds = Vec<(f64, f64)>;

/// The kernel's log bounds and log parameters, with log σn² appended when optimised.
pub(crate) fn start_and_bounds(
    kernel: &dyn crate::Kernel,
    noise: f64,
    options: &OptimiseOptions,
) -> Result<(Vec<f64>, Bounds)> {
    let mut bounds = kernel.log_bounds();
    let mut theta0 = kernel.log_params();
    if options.optimise_noise {
        let (lo, hi) = options.noise_bounds;
        if !(noise >= lo && noise <= hi) {
            return Err(GpError::invalid(
                "noise",
                noise,
                "within noise_bounds when optimised",
            ));
        }
        bounds.push((lo.ln(), hi.ln()));
        theta0.push(noise.ln());
    }
    Ok((theta0, bounds))
}

impl GpRegression {
    /// Fits the GP after maximising the log marginal likelihood over the kernel's
    /// hyperparameters (and σn² if [`OptimiseOptions::optimise_noise`]), as scikit-learn's
    /// `GaussianProcessRegressor` with `fmin_l_bfgs_b` does; deterministic for a seed.
    ///
    /// # Errors
    /// As [`fit`](GpRegression::fit) for the data and the configuration (the noise must
    /// lie within `noise_bounds` when optimised); [`GpError::InvalidParameter`] for bad
    /// options; [`GpError::OptimisationFailed`] if no run could evaluate its start.
    ///
    /// # Example
    /// ```
    /// use haunts_gp::{GpRegression, OptimiseOptions, Rbf};
    /// let x: Vec<f64> = (0..30).map(|i| i as f64 * 0.3).collect();
    /// let y: Vec<f64> = x.iter().map(|v| v.sin()).collect();
    /// let start = GpRegression::new(Rbf::new(1.0, 0.2)?).noise(0.1);
    /// let before = start.fit(&x, 1, &y)?.log_marginal_likelihood();
    /// let (gp, report) = start.fit_optimised(&x, 1, &y, &OptimiseOptions::default())?;
    /// assert!(report.log_marginal_likelihood > before);
    /// assert_eq!(gp.log_marginal_likelihood(), report.log_marginal_likelihood);
    /// # Ok::<(), haunts_gp::GpError>(())
    /// ```
    pub fn fit_optimised(
        &self,
        x: &[f64],
        dim: usize,
        y: &[f64],
        options: &OptimiseOptions,
    ) -> Result<(ExactGp, OptimisationReport)> {
        options.check()?;
        self.check_data(x, dim, y)?;
        check_points(self.kernel(), x, dim)?;
        let (theta0, bounds) = start_and_bounds(self.kernel(), self.noise_variance(), options)?;
        let lik = ExactLikelihood {
            base: self,
            dim,
            optimise_noise: options.optimise_noise,
        };
        let found = maximise(&lik, x, y, theta0, bounds, options)?;
        let model = lik.model_at(&found.theta)?.fit(x, dim, y)?;
        let report = OptimisationReport {
            log_marginal_likelihood: model.log_marginal_likelihood(),
            log_params: found.theta,
            full_evaluations: found.full_evaluations + 1,
            subset_evaluations: found.subset_evaluations,
            runs: found.runs,
        };
        Ok((model, report))
    }
}

impl<'a> Objective<'a> {
    fn new(lik: &'a dyn Likelihood, x: &'a [f64], y: &'a [f64], bounds: Vec<(f64, f64)>) -> Self {
        Self {
            lik,
            x,
            y,
            bounds,
            cache: Mutex::new(None),
            best: Mutex::new(None),
            evaluations: Mutex::new(0),
        }
    }
}

/// `k` distinct indices of `0..n` in increasing order (partial Fisher–Yates).
pub(crate) fn sample_indices(n: usize, k: usize, rng: &mut StdRng) -> Vec<usize> {
    let mut all: Vec<usize> = (0..n).collect();
    let k = k.min(n);
    for i in 0..k {
        let j = rng.random_range(i..n);
        all.swap(i, j);
    }
    let mut out = all[..k].to_vec();
    out.sort_unstable();
    out
}
