//! Optimisation of a sparse GP's hyperparameters: the VFE bound's value and its analytic
//! gradient over the kernel's log hyperparameters and log σn², in one streamed pass over the
//! data, maximised by the optimiser of `optimise.rs`.
//!
//! **The bound.** With `Kuu + εI = L Lᵀ` (ε the jitter of the [`JitterPolicy`]), the
//! whitened cross-covariance `A₀ = L⁻¹ Kuf` (m × n), `W = A₀ A₀ᵀ`, `B = I + W/σ² = LB LBᵀ`,
//! `c = LB⁻¹ A₀ r / σ²` for the centred targets r and `q_j = ‖A₀ e_j‖²` (the diagonal of Qff),
//!
//! `F = −½ (n ln 2π + n ln σ² + ln|B| + rᵀr/σ² − cᵀc) − (Σ k(x_j, x_j) − Σ q_j) / (2σ²)`
//!
//! (Titsias 2009, eq. 9; GPflow's `SGPR.elbo` in the same variables).
//!
//! **The gradient**, by reverse-mode differentiation of `F(Kuu, Kuf, kdiag, σ²)` and then
//! written with `L` and `LB` only (no inverse of `Kuu` or of `Kuu + σ⁻² Kuf Kfu`): with
//! `ṽ = LB⁻ᵀ c`, `P = I − B⁻¹ − ṽṽᵀ` (B⁻¹ is benign: B ⪰ I) and `w = L⁻ᵀ ṽ`,
//!
//! - `∂F/∂Kuu = ½ L⁻ᵀ (P − W/σ²) L⁻¹`,
//! - `∂F/∂Kuf = σ⁻² L⁻ᵀ (P A₀ + ṽ rᵀ)`,
//! - `∂F/∂k(x_j, x_j) = −1/(2σ²)`,
//! - `∂F/∂ln σ² = −n/2 + rᵀr/(2σ²) + (Σ k_jj − Σ q_j)/(2σ²) + (m − tr B⁻¹)/2 − (cᵀc + ṽᵀṽ)/2`.
//!
//! For a log hyperparameter θ with `Ḱuu = ∂(Kuu + εI)/∂θ` (ε is proportional to the mean of
//! `diag Kuu`, so it has a derivative too) and `Ḱuf = ∂Kuf/∂θ`, the chain rule gives
//!
//! `∂F/∂θ = ½ tr((P − W/σ²) X) + σ⁻² (tr(P V) + wᵀ Ḱuf r) − σ⁻² Σ ∂k(x_j, x_j)/∂θ / 2`
//!
//! with `X = L⁻¹ Ḱuu L⁻ᵀ` (m × m) and `V = L⁻¹ (Ḱuf A₀ᵀ)` (m × m). So one pass over the data
//! in blocks accumulates `W`, `A₀ r`, `Ḱuf A₀ᵀ` and `Ḱuf r` per hyperparameter; everything
//! else is O(m³). For a hyperparameter that scales the kernel ([`Kernel::scale_param`], e.g.
//! σ²) `Ḱuf = Kuf = L A₀`, so `V = W` and `Ḱuf r = L A₀ r` come free. Every solve is one-sided
//! with `L` or `LB`; `A₀` is computed per block as the fit does, a product with the triangular
//! `L⁻¹` (whose conditioning the pivot floor of `Kuu`'s factorisation bounds: a pivot below
//! 1e-11 of the mean variance takes the next jitter; see `sparse.rs`). Per
//! data point the pass costs (2 + 2p')·m² flops for p' kernel hyperparameters other than the
//! scale (one, the length scale, for the RBF: 4m²; the fit costs 2m²) and m kernel
//! gradients. The blocks are accumulated in order, each block's kernel columns and products
//! in parallel (rayon, faer): a fixed reduction order, so repeated runs give the same bits.

use std::sync::Mutex;

use faer::linalg::matmul::triangular::BlockStructure;
use faer::{Accum, Mat};

use crate::error::{GpError, Result};
use crate::kernel::{Kernel, check_points};
use crate::linalg::{JitterPolicy, col, for_each_column, map_range, par};
use crate::optimise::{Likelihood, OptimisationReport, OptimiseOptions, maximise};
use crate::sparse::{Inducing, SparseGp, SparseGpRegression, SparseMethod, Whitened, packed_lower};

/// ln(2π).
const LN_2PI: f64 = 1.837_877_066_409_345_5;

/// The sparse objective and its gradient at the configured hyperparameters (see
/// [`SparseGpRegression::objective_gradient`]).
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct SparseObjective {
    /// The VFE bound of log p(y) (as [`SparseGp::objective`]).
    pub value: f64,
    /// ∂ bound / ∂(log θ): the kernel's log hyperparameters in its order, then log σn².
    pub gradient: Vec<f64>,
    /// The absolute jitter added to `Kuu`'s diagonal (0 when none was needed).
    pub jitter: f64,
}

/// What [`vfe_bound`] computes besides the objective: the factors and weights of the fitted
/// model (the same as [`SparseGpRegression::fit`]'s).
struct Parts {
    luu: crate::linalg::Factor,
    lb: crate::linalg::Factor,
    w: Vec<f64>,
    /// `B = I + W/σ²`, packed as the fit's (see `Whitened` in sparse.rs).
    #[cfg(feature = "serde")]
    b_lower: Vec<f64>,
    /// `A₀ r / σ²`.
    #[cfg(feature = "serde")]
    rhs: Vec<f64>,
}

/// The VFE bound and its gradient for the inducing points `z` and centred targets `r`.
#[allow(clippy::too_many_arguments)]
fn vfe_bound(
    kernel: &dyn Kernel,
    z: &[f64],
    dim: usize,
    x: &[f64],
    r: &[f64],
    s2: f64,
    jitter: &JitterPolicy,
    chunk: usize,
) -> Result<(SparseObjective, Parts)> {
    let m = z.len() / dim;
    let n = r.len();
    let np = kernel.n_params();
    let luu = crate::sparse::factor_kuu(kernel, z, dim, jitter)?;
    let mean_diag = z.chunks_exact(dim).map(|p| kernel.value(p, p)).sum::<f64>() / m as f64;
    // The jitter is `relative · mean diag(Kuu)`: its derivative is `relative · mean diag(Ḱuu)`.
    let relative = if mean_diag.abs() > 0.0 {
        luu.jitter / mean_diag.abs() * mean_diag.signum()
    } else {
        0.0
    };
    let mut luu_inv = Mat::<f64>::zeros(m, m);
    faer::linalg::triangular_inverse::invert_lower_triangular(
        luu_inv.as_mut(),
        luu.l.as_ref(),
        par(),
    );
    let width = chunk.min(n).max(1);
    // The hyperparameters whose Ḱuf need products; a scale hyperparameter (Ḱ = K) needs none.
    let scale = kernel.scale_param().filter(|&i| i < np);
    let others: Vec<usize> = (0..np).filter(|&k| Some(k) != scale).collect();
    let no = others.len();
    let mut w = Mat::<f64>::zeros(m, m);
    let mut b0 = Mat::<f64>::zeros(m, 1);
    // Ḱuf A₀ᵀ and Ḱuf r of the other hyperparameters, stacked (rows t·m .. (t+1)·m: others[t]).
    let mut u = Mat::<f64>::zeros(no * m, m);
    let mut ur = Mat::<f64>::zeros(no * m, 1);
    let (mut sum_r2, mut sum_kd, mut sum_q) = (0.0, 0.0, 0.0);
    let mut sum_dkd = vec![0.0; np];
    // Rows 0 .. m: Kuf; rows (1 + t)·m .. (2 + t)·m: Ḱuf of others[t].
    let mut kd = Mat::<f64>::zeros((1 + no) * m, width);
    let mut a0 = Mat::<f64>::zeros(m, width);
    let mut g = vec![0.0; np];
    // Saturating: a chunk size as large as `usize` allows is one block (no overflow).
    for (bi, block) in x.chunks(chunk.saturating_mul(dim)).enumerate() {
        let c = block.len() / dim;
        let rb = &r[bi * chunk..bi * chunk + c];
        sum_r2 += rb.iter().map(|v| v * v).sum::<f64>();
        for p in block.chunks_exact(dim) {
            sum_kd += kernel.value(p, p);
            kernel.gradient(p, p, &mut g);
            for (s, v) in sum_dkd.iter_mut().zip(&g) {
                *s += v;
            }
        }
        for_each_column(kd.as_mut().subcols_mut(0, c), |j, out| {
            let b = &block[j * dim..(j + 1) * dim];
            let mut g = vec![0.0; np];
            for (i, a) in z.chunks_exact(dim).enumerate() {
                kernel.gradient(a, b, &mut g);
                out[i] = match scale {
                    Some(k) => g[k],
                    None => kernel.value(a, b),
                };
                for (t, &k) in others.iter().enumerate() {
                    out[(1 + t) * m + i] = g[k];
                }
            }
        });
        let kuf = kd.as_ref().subrows(0, m).subcols(0, c);
        // A₀ = L⁻¹ Kuf, as the fit computes it (see sparse.rs).
        faer::linalg::matmul::triangular::matmul(
            a0.as_mut().subcols_mut(0, c),
            BlockStructure::Rectangular,
            Accum::Replace,
            luu_inv.as_ref(),
            BlockStructure::TriangularLower,
            kuf,
            BlockStructure::Rectangular,
            1.0,
            par(),
        );
        let a = a0.as_ref().subcols(0, c);
        sum_q += map_range(c, |j| col(a, j).iter().map(|v| v * v).sum::<f64>())
            .iter()
            .sum::<f64>();
        faer::linalg::matmul::triangular::matmul(
            w.as_mut(),
            BlockStructure::TriangularLower,
            Accum::Add,
            a,
            BlockStructure::Rectangular,
            a.transpose(),
            BlockStructure::Rectangular,
            1.0,
            par(),
        );
        let rm = Mat::from_fn(c, 1, |j, _| rb[j]);
        faer::linalg::matmul::matmul(b0.as_mut(), Accum::Add, a, rm.as_ref(), 1.0, par());
        if no > 0 {
            let dkc = kd.as_ref().subrows(m, no * m).subcols(0, c);
            faer::linalg::matmul::matmul(u.as_mut(), Accum::Add, dkc, a.transpose(), 1.0, par());
            faer::linalg::matmul::matmul(ur.as_mut(), Accum::Add, dkc, rm.as_ref(), 1.0, par());
        }
    }
    for j in 0..m {
        for i in 0..j {
            w[(i, j)] = w[(j, i)];
        }
    }
    let b_lower = packed_lower(m, |i, j| {
        if i == j {
            w[(i, i)] / s2 + 1.0
        } else {
            w[(i, j)] / s2
        }
    });
    let rhs: Vec<f64> = (0..m).map(|i| b0[(i, 0)] / s2).collect();
    let Whitened {
        lb,
        c: cv,
        v: vt,
        w: wv,
    } = Whitened::solve(&luu, &b_lower, &rhs)?;
    let c2: f64 = cv.iter().map(|v| v * v).sum();
    let nf = n as f64;
    let trace_term = (sum_kd - sum_q) / s2;
    let value =
        -0.5 * (nf * LN_2PI + nf * s2.ln() + lb.log_det() + sum_r2 / s2 - c2) - 0.5 * trace_term;
    let v2: f64 = vt.iter().map(|v| v * v).sum();
    let binv = lb.inverse_lower();
    let tr_binv: f64 = (0..m).map(|i| binv[(i, i)]).sum();
    // P = I − B⁻¹ − ṽṽᵀ (B⁻¹ is stored in its lower triangle).
    let pm = Mat::from_fn(m, m, |i, j| {
        let bi = if i >= j { binv[(i, j)] } else { binv[(j, i)] };
        f64::from(u8::from(i == j)) - bi - vt[i] * vt[j]
    });
    // Ḱuu of every hyperparameter, as for Ḱuf.
    let mut dkuu = Mat::<f64>::zeros(np * m, m);
    for_each_column(dkuu.as_mut(), |j, out| {
        let b = &z[j * dim..(j + 1) * dim];
        let mut g = vec![0.0; np];
        for (i, a) in z.chunks_exact(dim).enumerate() {
            kernel.gradient(a, b, &mut g);
            for (k, v) in g.iter().enumerate() {
                out[k * m + i] = *v;
            }
        }
    });
    let mut gradient = Vec::with_capacity(np + 1);
    for (k, dkd) in sum_dkd.iter().enumerate() {
        let mut xk = dkuu.as_ref().subrows(k * m, m).to_owned();
        let djit = relative * (0..m).map(|i| xk[(i, i)]).sum::<f64>() / m as f64;
        for i in 0..m {
            xk[(i, i)] += djit;
        }
        // X = L⁻¹ Ḱuu L⁻ᵀ = L⁻¹ (L⁻¹ Ḱuu)ᵀ for a symmetric Ḱuu.
        luu.solve_lower(xk.as_mut());
        let mut xk = xk.transpose().to_owned();
        luu.solve_lower(xk.as_mut());
        // V = L⁻¹ Ḱuf A₀ᵀ and wᵀ Ḱuf r; for the scale hyperparameter Ḱuf = Kuf = L A₀, so
        // V = W and wᵀ Kuf r = ṽᵀ A₀ r.
        let (vk, wu) = match others.iter().position(|&o| o == k) {
            Some(t) => {
                let mut vk = u.as_ref().subrows(t * m, m).to_owned();
                luu.solve_lower(vk.as_mut());
                let wu: f64 = (0..m).map(|i| wv[i] * ur[(t * m + i, 0)]).sum();
                (vk, wu)
            }
            None => (w.clone(), (0..m).map(|i| vt[i] * b0[(i, 0)]).sum()),
        };
        let (mut px, mut wx, mut pv) = (0.0, 0.0, 0.0);
        for j in 0..m {
            for i in 0..m {
                px += pm[(i, j)] * xk[(i, j)];
                wx += w[(i, j)] * xk[(i, j)];
                pv += pm[(i, j)] * vk[(j, i)];
            }
        }
        gradient.push(0.5 * px + (pv + wu - 0.5 * wx - 0.5 * dkd) / s2);
    }
    gradient.push(
        -0.5 * nf + 0.5 * sum_r2 / s2 + 0.5 * trace_term + 0.5 * (m as f64 - tr_binv)
            - 0.5 * (c2 + v2),
    );
    let objective = SparseObjective {
        value,
        gradient,
        jitter: luu.jitter,
    };
    Ok((
        objective,
        Parts {
            luu,
            lb,
            w: wv,
            #[cfg(feature = "serde")]
            b_lower,
            #[cfg(feature = "serde")]
            rhs,
        },
    ))
}

impl SparseGpRegression {
    /// The VFE bound (as [`SparseGp::objective`] of [`fit`](SparseGpRegression::fit)) and its
    /// gradient with respect to the kernel's log hyperparameters and log σn², computed
    /// analytically in one pass over the data (the module documentation of `sparse_optimise.rs`
    /// gives the formulas: triangular solves with the Cholesky factors only).
    ///
    /// # Errors
    /// As [`fit`](SparseGpRegression::fit); [`GpError::Unsupported`] for FITC.
    ///
    /// # Complexity
    /// (2 + 2p')·m² flops and m kernel gradients per data point for p' kernel hyperparameters
    /// besides a [scale](Kernel::scale_param), plus O(p·m³); memory O(p·m² + p·m·block).
    ///
    /// # Example
    /// ```
    /// use haunts_gp::{Inducing, Rbf, SparseGpRegression};
    /// let x: Vec<f64> = (0..200).map(|i| i as f64 * 0.05).collect();
    /// let y: Vec<f64> = x.iter().map(|v| v.sin()).collect();
    /// let gp = SparseGpRegression::new(Rbf::new(1.0, 1.0)?, Inducing::Grid(vec![15])).with_noise(0.01);
    /// let at = gp.objective_gradient(&x, 1, &y)?;
    /// approx::assert_relative_eq!(at.value, gp.fit(&x, 1, &y)?.objective(), max_relative = 1e-10);
    /// assert_eq!(at.gradient.len(), 3); // log σ², log ℓ, log σn²
    /// # Ok::<(), haunts_gp::GpError>(())
    /// ```
    pub fn objective_gradient(&self, x: &[f64], dim: usize, y: &[f64]) -> Result<SparseObjective> {
        Ok(self.fit_with_gradient(x, dim, y)?.1)
    }

    /// The fitted model and [`objective_gradient`](SparseGpRegression::objective_gradient)'s
    /// result, from one pass over the data.
    pub(crate) fn fit_with_gradient(
        &self,
        x: &[f64],
        dim: usize,
        y: &[f64],
    ) -> Result<(SparseGp, SparseObjective)> {
        let (z, r, offset) = self.check_vfe(x, dim, y)?;
        let (objective, parts) = vfe_bound(
            self.kernel.as_ref(),
            &z,
            dim,
            x,
            &r,
            self.noise,
            &self.jitter,
            self.block_size(z.len() / dim),
        )?;
        let gp = SparseGp {
            kernel: self.kernel.clone(),
            z,
            dim,
            offset,
            noise: self.noise,
            method: SparseMethod::Vfe,
            policy: self.jitter,
            luu: parts.luu,
            lb: parts.lb,
            w: parts.w,
            #[cfg(feature = "serde")]
            b_lower: parts.b_lower,
            #[cfg(feature = "serde")]
            rhs: parts.rhs,
            objective: objective.value,
            n: r.len(),
        };
        Ok((gp, objective))
    }

    /// Checks the configuration and data for the VFE bound's gradient; returns the inducing
    /// points, the centred targets and the prior mean's value.
    fn check_vfe(&self, x: &[f64], dim: usize, y: &[f64]) -> Result<(Vec<f64>, Vec<f64>, f64)> {
        if self.method != SparseMethod::Vfe {
            return Err(GpError::Unsupported {
                what: "the gradient of FITC's objective (only VFE's bound is differentiated)",
            });
        }
        if !(self.noise.is_finite() && self.noise > 0.0) {
            return Err(GpError::invalid("noise", self.noise, "finite and > 0"));
        }
        let exact = crate::GpRegression::from_box(self.kernel.clone())
            .with_mean(self.mean)
            .with_noise(self.noise)
            .with_jitter(self.jitter);
        let (_, offset) = exact.check_data(x, dim, y)?;
        let z = self.inducing.points(x, dim)?;
        check_points(self.kernel.as_ref(), &z, dim)?;
        Ok((z, y.iter().map(|v| v - offset).collect(), offset))
    }

    /// Fits the sparse GP after maximising the VFE bound over the kernel's hyperparameters
    /// (and σn² if [`OptimiseOptions::optimise_noise`]) with the inducing points held fixed
    /// (computed once from all the data by the [`Inducing`] rule); the same optimiser,
    /// options and report as [`crate::GpRegression::fit_optimised`], the report's
    /// `log_marginal_likelihood` being the bound.
    ///
    /// **Large n.** The optimiser's staged warm starts run on random subsets of
    /// [`OptimiseOptions::warm_start_subset`] points growing by 2.5× up to
    /// [`OptimiseOptions::warm_start_max`] (all with the same inducing points), then a Newton
    /// polish with the last subset's Hessian runs on all the data, at most
    /// [`OptimiseOptions::polish_evaluations`] full passes when set; the model of the best
    /// full pass is returned without another fit. For n = 10⁶ and m = 500 one full pass costs
    /// ≈ 10 s on two cores; `warm_start_max: 40_000, polish_evaluations: 3` is the setting of
    /// the `gp_sparse/n1M_m500_optimise` bench (`BENCHMARKS.md` gives its time and the bound it
    /// gives up against longer runs). The bound on a subset with the same inducing points is
    /// not the full bound scaled (its log-determinant grows like m ln n, not n), so the
    /// subsets only bring the start near the optimum; the full passes finish the job.
    ///
    /// # Errors
    /// As [`fit`](SparseGpRegression::fit); [`GpError::Unsupported`] for FITC;
    /// [`GpError::TooFewPoints`] for fewer than 2 points; [`GpError::IdenticalInputs`] when
    /// all points coincide; [`GpError::InvalidParameter`] for bad options or a noise outside
    /// `noise_bounds`; [`GpError::OptimisationFailed`] if the bound cannot be evaluated at any
    /// start.
    ///
    /// # Complexity
    /// Per evaluation as [`objective_gradient`](SparseGpRegression::objective_gradient).
    ///
    /// # Example
    /// ```
    /// use haunts_gp::{Inducing, OptimiseOptions, Rbf, SparseGpRegression};
    /// let x: Vec<f64> = (0..400).map(|i| i as f64 * 0.025).collect();
    /// let y: Vec<f64> = x.iter().map(|v| (2.0 * v).sin()).collect();
    /// let start = SparseGpRegression::new(Rbf::new(0.5, 3.0)?, Inducing::Grid(vec![20])).with_noise(0.1);
    /// let before = start.fit(&x, 1, &y)?.objective();
    /// let (gp, report) = start.fit_optimised(&x, 1, &y, &OptimiseOptions::default())?;
    /// assert!(report.log_marginal_likelihood > before);
    /// assert_eq!(gp.objective(), report.log_marginal_likelihood);
    /// assert!(gp.noise() < 0.1);
    /// # Ok::<(), haunts_gp::GpError>(())
    /// ```
    pub fn fit_optimised(
        &self,
        x: &[f64],
        dim: usize,
        y: &[f64],
        options: &OptimiseOptions,
    ) -> Result<(SparseGp, OptimisationReport)> {
        options.clone().check()?;
        let (z, _, _) = self.check_vfe(x, dim, y)?;
        let n = y.len();
        if n < 2 {
            return Err(GpError::TooFewPoints {
                found: n,
                required: 2,
            });
        }
        if x.chunks_exact(dim).all(|p| p == &x[..dim]) {
            return Err(GpError::IdenticalInputs { n });
        }
        let (theta0, bounds) =
            crate::optimise::start_and_bounds(self.kernel.as_ref(), self.noise, options)?;
        let lik = VfeLikelihood {
            base: self,
            z: &z,
            dim,
            optimise_noise: options.optimise_noise,
            n,
            best: Mutex::new(None),
        };
        let found = maximise(&lik, x, y, theta0, bounds, options)?;
        // The best full-data evaluation is usually the answer: reuse its model.
        let cached = lik
            .best
            .lock()
            .ok()
            .and_then(|mut b| b.take())
            .filter(|(theta, _)| *theta == found.theta)
            .map(|(_, model)| model);
        found.finish(
            cached,
            |theta| lik.model_at(theta)?.fit(x, dim, y),
            SparseGp::objective,
        )
    }
}

/// The VFE bound with fixed inducing points as a [`Likelihood`].
struct VfeLikelihood<'a> {
    base: &'a SparseGpRegression,
    z: &'a [f64],
    dim: usize,
    optimise_noise: bool,
    /// Points of the full data set.
    n: usize,
    /// The best full-data evaluation so far: θ and its fitted model.
    best: Mutex<Option<(Vec<f64>, SparseGp)>>,
}

impl VfeLikelihood<'_> {
    /// The configured regression at log parameters θ, with the inducing points given.
    fn model_at(&self, theta: &[f64]) -> Result<SparseGpRegression> {
        let mut kernel = self.base.kernel.clone();
        let p = kernel.n_params();
        kernel.set_log_params(&theta[..p])?;
        let mut gp = self.base.clone();
        gp.kernel = kernel;
        gp.inducing = Inducing::Given(self.z.to_vec());
        if self.optimise_noise {
            gp.noise = theta[p].exp();
        }
        Ok(gp)
    }
}

impl Likelihood for VfeLikelihood<'_> {
    fn evaluate(&self, theta: &[f64], x: &[f64], y: &[f64]) -> Result<(f64, Vec<f64>)> {
        let (gp, mut at) = self.model_at(theta)?.fit_with_gradient(x, self.dim, y)?;
        if y.len() == self.n
            && let Ok(mut best) = self.best.lock()
            && best.as_ref().is_none_or(|(_, b)| at.value > b.objective)
        {
            *best = Some((theta.to_vec(), gp));
        }
        if !self.optimise_noise {
            at.gradient.pop();
        }
        Ok((at.value, at.gradient))
    }
    fn dim(&self) -> usize {
        self.dim
    }
    /// The bound is a sum of O(n) terms of order 1: a warm start stops once an L-BFGS
    /// iteration gains less than 1e-8 per point (else its line search can spend a hundred
    /// evaluations on rounding-level steps).
    fn warm_cost_tolerance(&self, n: usize) -> f64 {
        1e-8 * n as f64
    }
}
