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
//! **Large n.** When n exceeds twice [`OptimiseOptions::warm_start_subset`], a first run
//! optimises on that many points drawn at random (seeded), and the full-data run starts from
//! its optimum, so most likelihood evaluations cost O(s³) instead of O(n³). The final model is
//! always optimised and fitted on all the data.

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
    base: &'a GpRegression,
    x: &'a [f64],
    dim: usize,
    y: &'a [f64],
    bounds: Vec<(f64, f64)>,
    optimise_noise: bool,
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

    /// A configured regression at log parameters θ.
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

    /// (−log p, −∂ log p/∂z) at z.
    fn evaluate(&self, z: &[f64]) -> Result<(f64, Vec<f64>)> {
        if let Ok(cache) = self.cache.lock()
            && let Some((cz, c, g)) = cache.as_ref()
            && cz.as_slice() == z
        {
            return Ok((*c, g.clone()));
        }
        let theta = self.theta(z);
        let fitted = self.model_at(&theta)?.fit(self.x, self.dim, self.y)?;
        if let Ok(mut e) = self.evaluations.lock() {
            *e += 1;
        }
        let lml = fitted.log_marginal_likelihood();
        let mut grad = fitted.log_marginal_likelihood_gradient();
        if !self.optimise_noise {
            grad.pop();
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
) -> Option<(Vec<f64>, f64)> {
    let z0 = objective.z_of(theta0);
    if let Ok(mut best) = objective.best.lock() {
        *best = None;
    }
    objective.evaluate(&z0).ok()?;
    let solver = LBFGS::new(MoreThuenteLineSearch::new(), options.memory)
        .with_tolerance_grad(options.grad_tolerance)
        .ok()?
        .with_tolerance_cost(1e-12)
        .ok()?;
    // Whether the run ends normally or in a line-search failure, the best point it evaluated
    // is the answer (never worse than argmin's own best).
    let _ = Executor::new(Problem(objective), solver)
        .configure(|state| state.param(z0).max_iters(options.max_iters))
        .run();
    let (z, cost) = objective.best.lock().ok()?.take()?;
    Some((objective.theta(&z), -cost))
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
        let (n, _) = self.check_data(x, dim, y)?;
        check_points(self.kernel(), x, dim)?;
        let mut bounds = self.kernel().log_bounds();
        let mut theta0 = self.kernel().log_params();
        if options.optimise_noise {
            let (lo, hi) = options.noise_bounds;
            let noise = self.noise_variance();
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

        // Warm start: each run first on a random subset.
        let subset = options.warm_start_subset;
        let mut subset_evaluations = 0;
        if subset > 0 && n > 2 * subset {
            let idx = sample_indices(n, subset, &mut rng);
            let xs: Vec<f64> = idx
                .iter()
                .flat_map(|&i| x[i * dim..(i + 1) * dim].iter().copied())
                .collect();
            let ys: Vec<f64> = idx.iter().map(|&i| y[i]).collect();
            let sub = Objective::new(self, &xs, dim, &ys, bounds.clone(), options.optimise_noise);
            for start in &mut starts {
                if let Some((theta, _)) = run(&sub, start, options) {
                    *start = theta;
                }
            }
            subset_evaluations = sub.evaluations();
        }

        let full = Objective::new(self, x, dim, y, bounds, options.optimise_noise);
        let mut best: Option<(Vec<f64>, f64)> = None;
        let mut runs = 0;
        for start in &starts {
            if let Some((theta, lml)) = run(&full, start, options) {
                runs += 1;
                if best.as_ref().is_none_or(|(_, b)| lml > *b) {
                    best = Some((theta, lml));
                }
            }
        }
        let (theta, _) = best.ok_or_else(|| GpError::OptimisationFailed {
            reason: "the likelihood could not be evaluated at any start".into(),
        })?;
        let model = full.model_at(&theta)?.fit(x, dim, y)?;
        let report = OptimisationReport {
            log_marginal_likelihood: model.log_marginal_likelihood(),
            log_params: theta,
            full_evaluations: full.evaluations() + 1,
            subset_evaluations,
            runs,
        };
        Ok((model, report))
    }
}

impl<'a> Objective<'a> {
    fn new(
        base: &'a GpRegression,
        x: &'a [f64],
        dim: usize,
        y: &'a [f64],
        bounds: Vec<(f64, f64)>,
        optimise_noise: bool,
    ) -> Self {
        Self {
            base,
            x,
            dim,
            y,
            bounds,
            optimise_noise,
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
