//! Hyperparameter optimisation: maximise the log marginal likelihood over the kernel's log
//! hyperparameters (and log σn²) with L-BFGS (and for large n, Newton iterations after warm
//! starts on subsets), within bounds, from the current values and from seeded random restarts.
//!
//! **Bounds.** argmin's L-BFGS is unconstrained, so each bounded log parameter θ ∈ (lo, hi) is
//! optimised through θ = lo + (hi − lo)·s(z) with the logistic s and z ∈ R. The map is smooth
//! and monotone: interior optima are the same, an optimum on a bound is approached as z → ±∞
//! (its likelihood to within the gradient tolerance). Bounds are each kernel's
//! [`log_bounds`](crate::Kernel::log_bounds) (scikit-learn's (1e-5, 1e5) by default) and
//! [`OptimiseOptions::noise_bounds`] for σn². Newton iterations (below) clip their steps to
//! the bounds instead.
//!
//! **Large n.** When n is at least twice [`OptimiseOptions::warm_start_subset`] = s, stages
//! on nested random subsets (seeded) of s, 2.5s, 6.25s, … points (while at most n/2 and at
//! most [`OptimiseOptions::warm_start_max`]) come first, each starting from the previous
//! stage's optimum, so that most likelihood evaluations cost O(s³) instead of O(n³):
//! - the first stage runs L-BFGS with loose tolerances;
//! - at each stage's optimum the Hessian is measured by forward differences of the gradient,
//!   on the stage's points and on the first 40% of them;
//! - each later stage, and then the full data, runs Newton iterations with the Hessian
//!   predicted from the last stage's two (extrapolated linearly in the number of points, or
//!   scaled by it when extrapolating that far is not safe: see `predict_hessian`), refined by
//!   a BFGS update after each step; L-BFGS takes over where they do not converge.
//!
//! The full-data polish stops once a step's predicted gain is below 1e-13 of |log p|; when
//! the likelihood's value costs less than its gradient (the exact GP: a Cholesky against the
//! inverse of K), a trial point's gradient is computed only once its step is accepted, and a
//! small last step whose actual gain matched the predicted one ends the polish on its value
//! alone. The final model is always optimised on all the data (with
//! [`OptimiseOptions::polish_evaluations`] set, in that many full-data evaluations at most),
//! and the exact GP returns the best full-data fit without fitting again.

use std::sync::{Arc, Mutex};

use argmin::core::{CostFunction, Executor, Gradient};
use argmin::solver::linesearch::MoreThuenteLineSearch;
use argmin::solver::quasinewton::LBFGS;
use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};

use crate::error::{GpError, Result};
use crate::exact::{ExactGp, GpRegression};
use crate::kernel::check_points;
use newton::{Ending, Point, Warm, polish, warm_stage};

mod newton;

/// Options of [`GpRegression::fit_optimised`].
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub struct OptimiseOptions {
    /// Whether σn² is optimised too (else it stays as configured).
    pub optimise_noise: bool,
    /// Bounds of σn² in natural units, used when `optimise_noise` (scikit-learn's
    /// `WhiteKernel` default (1e-5, 1e5)).
    pub noise_bounds: (f64, f64),
    /// Random restarts after the run from the current hyperparameters (scikit-learn's
    /// `n_restarts_optimizer`); starts are uniform in the log bounds.
    pub restarts: usize,
    /// Seed of the restarts and of the warm-start subsets.
    pub seed: u64,
    /// L-BFGS iterations per run.
    pub max_iters: u64,
    /// L-BFGS history length.
    pub memory: usize,
    /// Stop when the gradient norm (in the unbounded variables) falls below this.
    pub grad_tolerance: f64,
    /// Points of the first warm-start stage (default 400); 0 disables the warm starts (see the
    /// module documentation).
    pub warm_start_subset: usize,
    /// The largest warm-start subset; 0 (the default) allows up to n/2 points.
    pub warm_start_max: usize,
    /// Full-data evaluations the Newton polish after the warm starts may use; when they are
    /// spent it stops at its best point (no full-data L-BFGS after it). 0 (the default): no
    /// cap (at most 12 Newton steps), and L-BFGS on all the data finishes an unconverged
    /// polish. A cap trades a little of the optimum for time where one evaluation is
    /// expensive (the sparse GP on 10⁶ points: see
    /// [`crate::SparseGpRegression::fit_optimised`]).
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
            warm_start_subset: 400,
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
    pub fn check(self) -> Result<Self> {
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
        Ok(self)
    }
}

/// What an optimisation did.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct OptimisationReport {
    /// The best log marginal likelihood (of the returned model, on all the data).
    pub log_marginal_likelihood: f64,
    /// Its log hyperparameters: the kernel's, then log σn² if optimised.
    pub log_params: Vec<f64>,
    /// Likelihood evaluations on all the data (for the exact GP: fits, each a Cholesky of K,
    /// whether or not its gradient was needed too).
    pub full_evaluations: usize,
    /// Likelihood evaluations on the warm-start subsets.
    pub subset_evaluations: usize,
    /// Runs (the first plus the restarts) whose likelihood could be evaluated.
    pub runs: usize,
}

/// One evaluation: z, −log p and a gradient (−∂ log p/∂z in the cache, ∂ log p/∂θ as the
/// best).
type Evaluation = (Vec<f64>, f64, Vec<f64>);

/// The objective in the unbounded variables z, with a one-entry cache so that argmin's
/// separate cost and gradient calls fit the GP once.
struct Objective<'a> {
    lik: &'a dyn Likelihood,
    x: &'a [f64],
    y: &'a [f64],
    bounds: Vec<(f64, f64)>,
    cache: Mutex<Option<Evaluation>>,
    /// The lowest cost evaluated since the last run began: z, the cost and ∂ log p/∂θ.
    best: Mutex<Option<Evaluation>>,
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
            && best.as_ref().is_none_or(|(_, c, _)| -lml < *c)
        {
            *best = Some((z.to_vec(), -lml, grad));
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

/// Runs L-BFGS from `theta0`; returns the best point it evaluated.
fn run(
    objective: &Objective<'_>,
    theta0: &[f64],
    options: &OptimiseOptions,
    tolerance_cost: f64,
) -> Option<Point> {
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
    let (z, cost, grad) = objective.best.lock().ok()?.take()?;
    Some(Point {
        theta: objective.theta(&z),
        value: -cost,
        grad: Some(grad),
    })
}

/// A log likelihood (or bound) and its gradient over log parameters θ, on any subset of the
/// data: what [`maximise`] optimises.
pub(crate) trait Likelihood: Sync {
    /// `(value, ∂value/∂θ)` at θ on the points `x` and targets `y`.
    fn evaluate(&self, theta: &[f64], x: &[f64], y: &[f64]) -> Result<(f64, Vec<f64>)>;
    /// The dimension of the points.
    fn dim(&self) -> usize;
    /// The change of value below which a warm-start run on a subset of `n` points stops (it
    /// only needs to land near the optimum): L-BFGS's cost tolerance, and a floor of the
    /// predicted gain at which a Newton stage stops.
    fn warm_cost_tolerance(&self, _n: usize) -> f64 {
        1e-12
    }
    /// The value alone at θ. Provided: `evaluate`'s value.
    fn value(&self, theta: &[f64], x: &[f64], y: &[f64]) -> Result<f64> {
        Ok(self.evaluate(theta, x, y)?.0)
    }
    /// Whether [`value`](Likelihood::value) costs less than `evaluate` and an `evaluate` right
    /// after it at the same θ and data reuses its work (so that the Newton polish asks for a
    /// gradient only where it needs one). Provided: false.
    fn lazy_gradient(&self) -> bool {
        false
    }
}

/// What [`maximise`] found.
pub(crate) struct Maximum {
    pub(crate) theta: Vec<f64>,
    pub(crate) full_evaluations: usize,
    pub(crate) subset_evaluations: usize,
    pub(crate) runs: usize,
}

impl Maximum {
    /// The model at the maximum — `cached` (a full-data fit at exactly this θ, kept by the
    /// likelihood) or else `refit(θ)` — and the report, whose log likelihood is
    /// `objective(model)`.
    pub(crate) fn finish<M>(
        self,
        cached: Option<M>,
        refit: impl FnOnce(&[f64]) -> Result<M>,
        objective: impl FnOnce(&M) -> f64,
    ) -> Result<(M, OptimisationReport)> {
        let (model, refits) = match cached {
            Some(model) => (model, 0),
            None => (refit(&self.theta)?, 1),
        };
        let report = OptimisationReport {
            log_marginal_likelihood: objective(&model),
            log_params: self.theta,
            full_evaluations: self.full_evaluations + refits,
            subset_evaluations: self.subset_evaluations,
            runs: self.runs,
        };
        Ok((model, report))
    }
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
    let mut starts = vec![Warm {
        theta: theta0,
        curvatures: Vec::new(),
    }];
    for _ in 0..options.restarts {
        starts.push(Warm {
            theta: bounds
                .iter()
                .map(|&(lo, hi)| rng.random_range(lo..=hi))
                .collect(),
            curvatures: Vec::new(),
        });
    }
    // Warm start: each run first on random subsets growing by 2.5× (s, 2.5s, …, while at
    // most n/2), each stage starting from the previous stage's optimum.
    let mut sizes = Vec::new();
    let mut subset = options.warm_start_subset;
    while subset > 0
        && 2 * subset <= n
        && (options.warm_start_max == 0 || subset <= options.warm_start_max)
    {
        sizes.push(subset);
        subset = subset * 5 / 2;
    }
    // Nested subsets: each stage's points, and the smaller set its Hessian is also measured
    // on, are the first ones of one random order.
    let order = random_prefix(n, sizes.last().copied().unwrap_or(0), &mut rng);
    let points = |k: usize| {
        let mut idx = order[..k].to_vec();
        idx.sort_unstable();
        let xs: Vec<f64> = idx
            .iter()
            .flat_map(|&i| x[i * dim..(i + 1) * dim].iter().copied())
            .collect();
        let ys: Vec<f64> = idx.iter().map(|&i| y[i]).collect();
        (xs, ys)
    };
    let mut subset_evaluations = 0;
    for &size in &sizes {
        let stage = points(size);
        let smaller = points(size * 2 / 5);
        for start in &mut starts {
            subset_evaluations += warm_stage(lik, &stage, &smaller, &bounds, start, options);
        }
    }
    let full = Objective::new(lik, x, y, bounds.clone());
    let mut best: Option<(Vec<f64>, f64)> = None;
    let mut runs = 0;
    let mut polish_evaluations = 0;
    for start in &starts {
        // After warm starts, a Newton polish with the Hessian predicted from the subsets
        // usually converges in a few full-data evaluations; L-BFGS finishes whatever it leaves.
        let mut from = start.theta.clone();
        if let Some((ending, point, evals)) = polish(lik, x, y, &bounds, start, options) {
            polish_evaluations += evals;
            if ending == Ending::Converged {
                runs += 1;
                if best.as_ref().is_none_or(|(_, b)| point.value > *b) {
                    best = Some((point.theta, point.value));
                }
                continue;
            }
            from = point.theta;
        }
        if let Some(point) = run(&full, &from, options, 1e-12) {
            runs += 1;
            if best.as_ref().is_none_or(|(_, b)| point.value > *b) {
                best = Some((point.theta, point.value));
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

/// The exact GP's log marginal likelihood as a [`Likelihood`]. It keeps the model of its last
/// fit, so that a gradient asked for after [`Likelihood::value`] at the same θ costs no second
/// factorisation, and the best model fitted on all the data, which
/// [`GpRegression::fit_optimised`] returns without another fit.
struct ExactLikelihood<'a> {
    base: &'a GpRegression,
    dim: usize,
    optimise_noise: bool,
    /// The full data (the best model is kept for it alone).
    full: (&'a [f64], &'a [f64]),
    last: Mutex<Option<Fitted>>,
    best: Mutex<Option<Fitted>>,
}

/// A model fitted at θ on the targets `y` (its points are the model's).
struct Fitted {
    theta: Vec<f64>,
    y: Vec<f64>,
    gp: Arc<ExactGp>,
}

impl ExactLikelihood<'_> {
    /// The configured regression at log parameters θ.
    fn model_at(&self, theta: &[f64]) -> Result<GpRegression> {
        let mut kernel = self.base.kernel().clone_box();
        let p = kernel.n_params();
        kernel.set_log_params(&theta[..p])?;
        let mut gp = self.base.clone().with_kernel(kernel);
        if self.optimise_noise {
            gp = gp.with_noise(theta[p].exp());
        }
        Ok(gp)
    }

    /// The model at θ on `(x, y)`: the last one if it is that, else a new fit (kept as the
    /// last, and as the best if it is on the full data and better than the best so far).
    fn fitted(&self, theta: &[f64], x: &[f64], y: &[f64]) -> Result<Arc<ExactGp>> {
        // Compared by value: O(n), against the O(n³) fit it may save.
        let same = |f: &Fitted| f.theta == theta && f.y == y && f.gp.points() == x;
        let mut last = self.last.lock().map_err(|_| poisoned())?;
        if let Some(f) = last.as_ref().filter(|f| same(f)) {
            return Ok(Arc::clone(&f.gp));
        }
        // Free the last model before the next factorisation (n² numbers each).
        *last = None;
        let gp = Arc::new(self.model_at(theta)?.fit(x, self.dim, y)?);
        let fitted = || Fitted {
            theta: theta.to_vec(),
            y: y.to_vec(),
            gp: Arc::clone(&gp),
        };
        if x.as_ptr() == self.full.0.as_ptr() && y.len() == self.full.1.len() {
            let mut best = self.best.lock().map_err(|_| poisoned())?;
            if best
                .as_ref()
                .is_none_or(|b| gp.log_marginal_likelihood() > b.gp.log_marginal_likelihood())
            {
                *best = Some(fitted());
            }
        }
        *last = Some(fitted());
        Ok(gp)
    }
}

fn poisoned() -> GpError {
    GpError::OptimisationFailed {
        reason: "a lock was poisoned".into(),
    }
}

impl Likelihood for ExactLikelihood<'_> {
    fn evaluate(&self, theta: &[f64], x: &[f64], y: &[f64]) -> Result<(f64, Vec<f64>)> {
        let fitted = self.fitted(theta, x, y)?;
        let mut grad = fitted.log_marginal_likelihood_gradient();
        if !self.optimise_noise {
            grad.pop();
        }
        Ok((fitted.log_marginal_likelihood(), grad))
    }
    fn dim(&self) -> usize {
        self.dim
    }
    fn value(&self, theta: &[f64], x: &[f64], y: &[f64]) -> Result<f64> {
        Ok(self.fitted(theta, x, y)?.log_marginal_likelihood())
    }
    /// A fit (Cholesky) costs ≈ n³/3 flops, its gradient ≈ 2n³/3 more (the inverse of K).
    fn lazy_gradient(&self) -> bool {
        true
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
    /// let start = GpRegression::new(Rbf::new(1.0, 0.2)?).with_noise(0.1);
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
        options.clone().check()?;
        self.check_data(x, dim, y)?;
        check_points(self.kernel(), x, dim)?;
        let (theta0, bounds) = start_and_bounds(self.kernel(), self.noise_variance(), options)?;
        let lik = ExactLikelihood {
            base: self,
            dim,
            optimise_noise: options.optimise_noise,
            full: (x, y),
            last: Mutex::new(None),
            best: Mutex::new(None),
        };
        let found = maximise(&lik, x, y, theta0, bounds, options)?;
        // The best full-data fit is usually the answer: return its model.
        if let Ok(mut last) = lik.last.lock() {
            *last = None;
        }
        let cached = lik
            .best
            .lock()
            .ok()
            .and_then(|mut b| b.take())
            .filter(|b| b.theta == found.theta)
            .map(|b| Arc::try_unwrap(b.gp).unwrap_or_else(|gp| (*gp).clone()));
        found.finish(
            cached,
            |theta| lik.model_at(theta)?.fit(x, dim, y),
            ExactGp::log_marginal_likelihood,
        )
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
    let mut out = random_prefix(n, k, rng);
    out.sort_unstable();
    out
}

/// The first `k` indices of a random order of `0..n` (partial Fisher–Yates).
fn random_prefix(n: usize, k: usize, rng: &mut StdRng) -> Vec<usize> {
    let mut all: Vec<usize> = (0..n).collect();
    let k = k.min(n);
    for i in 0..k {
        let j = rng.random_range(i..n);
        all.swap(i, j);
    }
    all.truncate(k);
    all
}
