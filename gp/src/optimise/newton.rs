//! The Newton side of the optimiser: the warm-start stages after the first, the Hessians
//! measured at each stage and predicted for the next, and the Newton iterations (with BFGS
//! updates) that converge each stage and then polish on all the data (see the parent
//! module's documentation).

use super::{Likelihood, Objective, OptimiseOptions, run};

/// A Hessian of the log likelihood over θ, row by row.
type Hessian = Vec<Vec<f64>>;

/// A Hessian measured at a warm-start stage's optimum, on that stage's `points` points.
pub(super) struct Curvature {
    points: usize,
    hess: Hessian,
}

/// One start's progress through the warm-start stages.
pub(super) struct Warm {
    pub(super) theta: Vec<f64>,
    pub(super) curvatures: Vec<Curvature>,
}

/// A point of a run: θ, the value there and its gradient (`None` where it was not needed).
pub(super) struct Point {
    pub(super) theta: Vec<f64>,
    pub(super) value: f64,
    pub(super) grad: Option<Vec<f64>>,
}

/// The relative predicted gain below which the full-data polish has converged (the value
/// is then within about this fraction of its maximum).
const POLISH_TOLERANCE: f64 = 1e-13;

/// The relative predicted gain below which a warm-start stage's Newton run has converged (or
/// the likelihood's [`Likelihood::warm_cost_tolerance`] if larger).
const STAGE_TOLERANCE: f64 = 1e-5;

/// The largest predicted relative gain of a step that may end the polish on its value alone
/// (see [`NewtonRules::settle`]).
const SETTLE_GAIN: f64 = 1e-8;

/// The farthest a Hessian is extrapolated linearly in the number of points, in units of the
/// gap between the two stages it is extrapolated from (see [`predict_hessian`]).
const MAX_EXTRAPOLATION: f64 = 4.0;

/// The full-data Newton polish of one start after its warm-start stages, from the last
/// stage's optimum with the Hessian predicted from its measurements and with
/// [`OptimiseOptions::polish_evaluations`] as the cap: the ending, the best point and the
/// evaluations; `None` without a Hessian or if the start cannot be evaluated.
pub(super) fn polish(
    lik: &dyn Likelihood,
    x: &[f64],
    y: &[f64],
    bounds: &[(f64, f64)],
    warm: &Warm,
    options: &OptimiseOptions,
) -> Option<(Ending, Point, usize)> {
    let mut hess = predict_hessian(&warm.curvatures, y.len())?;
    let (value, grad) = lik.evaluate(&warm.theta, x, y).ok()?;
    let rules = NewtonRules {
        absolute: 0.0,
        relative: POLISH_TOLERANCE,
        settle: lik.lazy_gradient(),
        iterations: options.max_iters.min(12),
        cap: (options.polish_evaluations > 0).then(|| options.polish_evaluations - 1),
    };
    let point = Point {
        theta: warm.theta.clone(),
        value,
        grad: Some(grad),
    };
    let (ending, point, evals) = newton(lik, x, y, bounds, point, &mut hess, &rules);
    Some((ending, point, evals + 1))
}

/// One warm-start stage of one start on the subset `(xs, ys)`: a Newton run with the Hessian
/// predicted from the earlier stages (L-BFGS on the first stage, or if Newton does not
/// converge), then the Hessian measured at the stage's optimum on `(xm, ym)` (the stage's
/// first 40% points) and on `(xs, ys)`, which the next stage predicts its own from. Returns
/// the evaluations.
pub(super) fn warm_stage(
    lik: &dyn Likelihood,
    (xs, ys): &(Vec<f64>, Vec<f64>),
    (xm, ym): &(Vec<f64>, Vec<f64>),
    bounds: &[(f64, f64)],
    warm: &mut Warm,
    options: &OptimiseOptions,
) -> usize {
    let s = ys.len();
    let mut evals = 0;
    let mut reached = None;
    let mut from = warm.theta.clone();
    if let Some(mut hess) = predict_hessian(&warm.curvatures, s)
        && let Ok((value, grad)) = lik.evaluate(&from, xs, ys)
    {
        evals += 1;
        let rules = NewtonRules {
            absolute: lik.warm_cost_tolerance(s),
            relative: STAGE_TOLERANCE,
            settle: false,
            iterations: options.max_iters.min(12),
            cap: None,
        };
        let point = Point {
            theta: from.clone(),
            value,
            grad: Some(grad),
        };
        let (ending, point, e) = newton(lik, xs, ys, bounds, point, &mut hess, &rules);
        evals += e;
        match ending {
            Ending::Converged => reached = Some(point),
            Ending::Unfinished => from = point.theta,
        }
    }
    let point = match reached {
        Some(point) => point,
        None => {
            // A warm start only needs to land near the optimum: looser tolerances.
            let loose = OptimiseOptions {
                grad_tolerance: options.grad_tolerance.max(1e-3),
                max_iters: options.max_iters.min(50),
                ..options.clone()
            };
            let sub = Objective::new(lik, xs, ys, bounds.to_vec());
            let found = run(&sub, &from, &loose, lik.warm_cost_tolerance(s));
            evals += sub.evaluations();
            match found {
                Some(point) => point,
                None => return evals,
            }
        }
    };
    // The Hessian at the optimum, on the smaller set (first) and on the stage's.
    let mut measured = Vec::with_capacity(2);
    if !ym.is_empty()
        && let Ok((_, grad)) = lik.evaluate(&point.theta, xm, ym)
    {
        evals += 1;
        let (hess, e) = measure_hessian(lik, xm, ym, &point.theta, &grad, bounds);
        evals += e;
        measured.extend(hess.map(|hess| Curvature {
            points: ym.len(),
            hess,
        }));
    }
    if let Some(grad) = &point.grad {
        let (hess, e) = measure_hessian(lik, xs, ys, &point.theta, grad, bounds);
        evals += e;
        if let Some(hess) = hess {
            measured.push(Curvature { points: s, hess });
            warm.curvatures = measured;
        }
    }
    warm.theta = point.theta;
    evals
}

/// The Hessian at θ on `(xs, ys)` by forward differences of the gradient (`grad` is the
/// gradient at θ), symmetrised; and the evaluations it took. `None` if an evaluation failed.
fn measure_hessian(
    lik: &dyn Likelihood,
    xs: &[f64],
    ys: &[f64],
    theta: &[f64],
    grad: &[f64],
    bounds: &[(f64, f64)],
) -> (Option<Hessian>, usize) {
    let p = theta.len();
    let h = 1e-4;
    let mut hess = vec![vec![0.0; p]; p];
    for j in 0..p {
        // Step inwards at an upper bound.
        let step = if theta[j] + h <= bounds[j].1 { h } else { -h };
        let mut probe = theta.to_vec();
        probe[j] += step;
        let Ok((_, g)) = lik.evaluate(&probe, xs, ys) else {
            return (None, j + 1);
        };
        for i in 0..p {
            hess[i][j] = (g[i] - grad[i]) / step;
        }
    }
    let symmetric = (0..p)
        .map(|i| (0..p).map(|j| 0.5 * (hess[i][j] + hess[j][i])).collect())
        .collect();
    (Some(symmetric), p)
}

/// The Hessian on `n` points predicted from the last stage's two (at the same θ, on nested
/// sets): extrapolated linearly in the number of points when n is at most
/// [`MAX_EXTRAPOLATION`] gaps between the two sets beyond the larger and the result is
/// negative definite, else the larger set's scaled by n / its points (as if the log
/// likelihood were a sum over points). The linear model is the better one for a GP: the
/// curvature of the signal variance and of the length scales grows more slowly than n (on
/// the bench data the Hessian on 2500 of the 5000 points, scaled by 2, is 1.7–2 times the
/// full one in those directions, the one extrapolated from 1000 and 2500 points within
/// 2–8%), while the noise's grows like n.
fn predict_hessian(measured: &[Curvature], n: usize) -> Option<Hessian> {
    let last = measured.last()?;
    if let [.., a, b] = measured
        && b.points > a.points
    {
        let f = (n as f64 - b.points as f64) / (b.points - a.points) as f64;
        if f <= MAX_EXTRAPOLATION {
            let h: Hessian = a
                .hess
                .iter()
                .zip(&b.hess)
                .map(|(ra, rb)| {
                    ra.iter()
                        .zip(rb)
                        .map(|(va, vb)| vb + f * (vb - va))
                        .collect()
                })
                .collect();
            if solve_negative_definite(&h, &vec![0.0; h.len()]).is_some() {
                return Some(h);
            }
        }
    }
    let scale = n as f64 / last.points as f64;
    Some(
        last.hess
            .iter()
            .map(|r| r.iter().map(|v| v * scale).collect())
            .collect(),
    )
}

/// How a [`newton`] run ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Ending {
    /// At a maximum (or at the evaluation cap).
    Converged,
    /// Not converged: the point returned is the best reached.
    Unfinished,
}

/// The stopping rules of a [`newton`] run.
struct NewtonRules {
    /// Converged once a step's predicted gain is at most `max(absolute, relative ·
    /// max(1, |value|))`.
    absolute: f64,
    /// See `absolute`.
    relative: f64,
    /// Whether a full step whose predicted gain g is at most [`SETTLE_GAIN`] (relative) ends
    /// the run on the value at its end, without a gradient, when its actual gain a says the
    /// quadratic model was good enough: the gap left after a quasi-Newton step is about
    /// (a − g)²/g (with a Hessian error ε, a − g ≈ ε·g and the gap ≈ ε²·g), so the run ends
    /// when that is within the tolerance. Like the predicted gain itself, the estimate misses
    /// what a curvature overestimated along a flat ridge hides.
    settle: bool,
    /// Newton steps at most.
    iterations: u64,
    /// Evaluations allowed (`None`: no cap); at the cap the run stops at its best point.
    cap: Option<usize>,
}

impl NewtonRules {
    fn tolerance(&self, value: f64) -> f64 {
        self.absolute.max(self.relative * value.abs().max(1.0))
    }
}

/// Newton iterations on `(x, y)` from `current` (whose gradient is known) with the Hessian
/// `hess` of the log likelihood, refined by a BFGS update after each step; steps are clipped
/// to the bounds and halved (at most 3 times) until the value does not decrease; converged
/// when a step's predicted gain is within the tolerance (the step is not taken). With
/// [`Likelihood::lazy_gradient`] a trial point's value comes first and its gradient only once
/// the step is accepted. Returns the ending, the best point and the evaluations.
fn newton(
    lik: &dyn Likelihood,
    x: &[f64],
    y: &[f64],
    bounds: &[(f64, f64)],
    mut current: Point,
    hess: &mut Hessian,
    rules: &NewtonRules,
) -> (Ending, Point, usize) {
    let lazy = lik.lazy_gradient();
    let mut evals = 0;
    for _ in 0..rules.iterations {
        let Some(grad) = current.grad.clone() else {
            return (Ending::Unfinished, current, evals);
        };
        // Newton step δ = −H⁻¹ g for the maximum (−H positive definite).
        let Some(delta) = solve_negative_definite(hess, &grad) else {
            return (Ending::Unfinished, current, evals);
        };
        let gain: f64 = 0.5 * delta.iter().zip(&grad).map(|(d, g)| d * g).sum::<f64>();
        if gain <= rules.tolerance(current.value) {
            return (Ending::Converged, current, evals);
        }
        let mut step = 1.0;
        let mut clipped = false;
        let mut accepted = None;
        for _ in 0..4 {
            if rules.cap.is_some_and(|cap| evals >= cap) {
                return (Ending::Converged, current, evals);
            }
            let free: Vec<f64> = current
                .theta
                .iter()
                .zip(&delta)
                .map(|(c, d)| c + step * d)
                .collect();
            let next: Vec<f64> = free
                .iter()
                .zip(bounds)
                .map(|(v, &(lo, hi))| v.clamp(lo, hi))
                .collect();
            clipped = next != free;
            let trial = if lazy {
                lik.value(&next, x, y).map(|v| (v, None))
            } else {
                lik.evaluate(&next, x, y).map(|(v, g)| (v, Some(g)))
            };
            let Ok((value, g)) = trial else {
                step *= 0.5;
                continue;
            };
            evals += 1;
            if value >= current.value {
                accepted = Some((next, value, g));
                break;
            }
            step *= 0.5;
        }
        let Some((next, value, g)) = accepted else {
            return (Ending::Unfinished, current, evals);
        };
        let scale = value.abs().max(1.0);
        let miss = value - current.value - gain;
        if rules.settle
            && step == 1.0
            && !clipped
            && gain <= SETTLE_GAIN * scale
            && miss * miss / gain <= rules.tolerance(value)
        {
            let point = Point {
                theta: next,
                value,
                grad: None,
            };
            return (Ending::Converged, point, evals);
        }
        let g = match g {
            Some(g) => g,
            None => match lik.evaluate(&next, x, y) {
                Ok((_, g)) => g,
                Err(_) => return (Ending::Unfinished, current, evals),
            },
        };
        // BFGS update of the Hessian (of −f: s = next − current, yv = −(g − grad)).
        let sv: Vec<f64> = next
            .iter()
            .zip(&current.theta)
            .map(|(a, b)| a - b)
            .collect();
        let yv: Vec<f64> = g.iter().zip(&grad).map(|(a, b)| -(a - b)).collect();
        bfgs_update(hess, &sv, &yv);
        current = Point {
            theta: next,
            value,
            grad: Some(g),
        };
    }
    (Ending::Unfinished, current, evals)
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
