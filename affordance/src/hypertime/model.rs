//! The hypertime model: a Gaussian mixture over the hypertime space built from a
//! Gustafson–Kessel clustering, and its density of people over the plane at any time.

use nalgebra::{Cholesky, DMatrix, DVector, Matrix2, Point2, Vector2};

use super::params::{Background, Selection};
use super::projection::{Projection, TimedPoint};
use crate::parallel::map_slice;
use crate::{AffordanceError, DensityMap, Result};

/// One component of the mixture, in hypertime coordinates `(x, y, cos ω₁t, sin ω₁t, …)`.
///
/// With the `serde` feature the mean is written as an array and the covariance as an array
/// of rows.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Debug, Clone, PartialEq)]
pub struct Component {
    /// Mixing weight `πᵢ = Σⱼ uᵢⱼᵉ / Σₗⱼ uₗⱼᵉ` (see [`Moments`](super::Moments)).
    pub weight: f64,
    /// Mean: the cluster's prototype, hypertime coordinates.
    #[cfg_attr(feature = "serde", serde(with = "crate::serde_support::vector"))]
    pub mean: DVector<f64>,
    /// Covariance: the cluster's covariance weighted like its weight (see [`Moments`](super::Moments)) plus
    /// the smoothing kernel and the spatial floor, hypertime coordinates.
    #[cfg_attr(feature = "serde", serde(with = "crate::serde_support::square_matrix"))]
    pub covariance: DMatrix<f64>,
}

/// What a fit saw and did.
///
/// With the `serde` feature, a change or objective that is not finite (the change is `∞`
/// after a single iteration) is written as `"inf"`, `"-inf"` or `"NaN"` in human-readable
/// formats.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Debug, Clone, PartialEq)]
pub struct FitReport {
    /// Points clustered.
    pub points: usize,
    /// Points skipped because their time or a coordinate was not finite.
    pub skipped: usize,
    /// Iterations of the final clustering.
    pub iterations: usize,
    /// Whether it converged (no membership changed by more than the tolerance) before the
    /// iteration cap.
    pub converged: bool,
    /// The largest membership change of its last iteration.
    #[cfg_attr(
        feature = "serde",
        serde(with = "haunts_occupancy::serde_float::value")
    )]
    pub change: f64,
    /// Its objective `J` (in the standardised space it ran in).
    #[cfg_attr(
        feature = "serde",
        serde(with = "haunts_occupancy::serde_float::value")
    )]
    pub objective: f64,
    /// The spatial floor used, metres (see [`HypertimeParams::spatial_floor`](super::HypertimeParams::spatial_floor)).
    #[cfg_attr(feature = "serde", serde(default))]
    pub spatial_floor: f64,
    /// The background's weight `β` used (0 without a background).
    #[cfg_attr(feature = "serde", serde(default))]
    pub background_weight: f64,
    /// The uniform component's weight `u` used (0 without one).
    #[cfg_attr(feature = "serde", serde(default))]
    pub uniform_weight: f64,
    /// The calibration, the validation of periods and the period and `k` searches.
    pub selection: Selection,
}

/// The background component of a fitted model (see [`Background`]): `β t_ν(s; μ, Σ)`.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BackgroundDensity {
    /// Its weight `β` in `[0, 1)`.
    pub weight: f64,
    /// Degrees of freedom `ν`.
    pub dof: f64,
    /// Location `μ`, metres.
    pub mean: [f64; 2],
    /// Scale matrix `Σ`, m² (rows).
    pub scale: [[f64; 2]; 2],
}

impl BackgroundDensity {
    /// The Student-t over `positions` (their mean, their covariance plus `floor²` on the
    /// diagonal), or `None` when there is no position or the scale is not positive definite.
    pub(crate) fn over(
        positions: &[Point2<f64>],
        floor: f64,
        background: Background,
    ) -> Option<Self> {
        let n = positions.len() as f64;
        if positions.is_empty() {
            return None;
        }
        let mean = positions.iter().fold(Vector2::zeros(), |a, p| a + p.coords) / n;
        let mut c = Matrix2::zeros();
        for p in positions {
            let v = p.coords - mean;
            c += v * v.transpose();
        }
        c /= n;
        c[(0, 0)] += floor * floor;
        c[(1, 1)] += floor * floor;
        let b = Self {
            weight: background.weight,
            dof: background.dof,
            mean: [mean.x, mean.y],
            scale: [[c[(0, 0)], c[(0, 1)]], [c[(1, 0)], c[(1, 1)]]],
        };
        b.student().map(|_| b)
    }

    /// `ln t_ν(p; μ, Σ)` (without the weight), −∞ for an improper background.
    pub(crate) fn log_value(&self, p: Point2<f64>) -> f64 {
        self.student().map_or(f64::NEG_INFINITY, |t| t.log_value(p))
    }

    /// The precomputed density, or `None` when the scale is not positive definite or a value
    /// is not finite.
    fn student(&self) -> Option<StudentT2> {
        let s = Matrix2::new(
            self.scale[0][0],
            self.scale[0][1],
            self.scale[1][0],
            self.scale[1][1],
        );
        let det = s.determinant();
        let finite = s.iter().chain(&self.mean).all(|v| v.is_finite());
        let symmetric =
            (s[(0, 1)] - s[(1, 0)]).abs() <= 1e-9 * (s[(0, 0)] * s[(1, 1)]).abs().sqrt();
        if !(finite && symmetric && det > 0.0 && s[(0, 0)] > 0.0 && det.is_finite()) {
            return None;
        }
        if !(self.dof.is_finite() && self.dof > 0.0 && (0.0..1.0).contains(&self.weight)) {
            return None;
        }
        Some(StudentT2 {
            mean: Point2::new(self.mean[0], self.mean[1]),
            inverse: s.try_inverse()?,
            log_norm: -(std::f64::consts::TAU.ln()) - 0.5 * det.ln(),
            dof: self.dof,
        })
    }
}

/// A bivariate Student-t, precomputed.
#[derive(Debug, Clone, Copy, PartialEq)]
struct StudentT2 {
    mean: Point2<f64>,
    inverse: Matrix2<f64>,
    log_norm: f64,
    dof: f64,
}

impl StudentT2 {
    fn log_value(&self, p: Point2<f64>) -> f64 {
        let v = p - self.mean;
        let d2 = v.dot(&(self.inverse * v));
        self.log_norm - (0.5 * self.dof + 1.0) * (d2 / self.dof).ln_1p()
    }
}

/// The uniform component of a fitted model (see [`Uniform`](super::Uniform)): `u / A` inside
/// the box from `lower` to `upper` (area `A`), 0 outside.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UniformDensity {
    /// Its weight `u` in `[0, 1)`.
    pub weight: f64,
    /// Lower-left corner of the box, metres.
    pub lower: [f64; 2],
    /// Upper-right corner of the box, metres.
    pub upper: [f64; 2],
}

impl UniformDensity {
    /// The uniform density over the box of `positions` grown by `uniform.margin`, or `None`
    /// when there is no finite position or the box has no area.
    pub(crate) fn over(positions: &[Point2<f64>], uniform: super::Uniform) -> Option<Self> {
        let finite = positions
            .iter()
            .filter(|p| p.x.is_finite() && p.y.is_finite());
        let (lo, hi) = finite.fold(
            (
                Point2::new(f64::INFINITY, f64::INFINITY),
                Point2::new(f64::NEG_INFINITY, f64::NEG_INFINITY),
            ),
            |(lo, hi), p| (lo.inf(p), hi.sup(p)),
        );
        let m = uniform.margin;
        let u = Self {
            weight: uniform.weight,
            lower: [lo.x - m, lo.y - m],
            upper: [hi.x + m, hi.y + m],
        };
        u.log_area().map(|_| u)
    }

    /// `ln A`, or `None` when the box is not finite, has no area, or the weight is outside
    /// `[0, 1)`.
    fn log_area(&self) -> Option<f64> {
        let area = (self.upper[0] - self.lower[0]) * (self.upper[1] - self.lower[1]);
        let ok = area.is_finite()
            && area > 0.0
            && self.upper[0] > self.lower[0]
            && (0.0..1.0).contains(&self.weight);
        ok.then(|| area.ln())
    }

    /// `ln(1 / A)` inside the box, −∞ outside (without the weight).
    pub(crate) fn log_value(&self, p: Point2<f64>) -> f64 {
        let inside = (self.lower[0]..=self.upper[0]).contains(&p.x)
            && (self.lower[1]..=self.upper[1]).contains(&p.y);
        match self.log_area() {
            Some(log_area) if inside => -log_area,
            _ => f64::NEG_INFINITY,
        }
    }
}

/// A component's pieces for conditioning on the time dimensions, precomputed.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Conditional {
    /// `ln πᵢ` (−∞ for an empty cluster).
    log_weight: f64,
    /// `μ_τ`.
    tau_mean: Vec<f64>,
    /// `Σ_ττ⁻¹`, row-major.
    tau_precision: Vec<f64>,
    /// `−½ ln det(2π Σ_ττ)`.
    tau_log_norm: f64,
    /// `μ_s`.
    space_mean: Vector2<f64>,
    /// `G = Σ_sτ Σ_ττ⁻¹`, 2 rows, row-major.
    gain: Vec<f64>,
    /// `S⁻¹`, `S = Σ_ss − G Σ_τs`.
    inverse: Matrix2<f64>,
    /// `−½ ln det(2π S)`.
    log_norm: f64,
}

/// People's whereabouts over space and time (seed 001): a Gaussian mixture over the hypertime
/// space fitted with Gustafson–Kessel clustering, giving a density over the plane for any
/// time, [`HypertimeModel::at`].
///
/// # The density
/// The clustering runs on standardised hypertime coordinates (centred; `(x, y)` divided by
/// one common scale and each `(cos, sin)` pair by one scale, so circles stay circles: by
/// default the circle keeps seed 001's radius of 1 m against the plane, see
/// [`HypertimeParams::time_radius`](super::HypertimeParams::time_radius); the GK iteration itself is nearly invariant to such
/// scalings, but its k-means++ initialisation and covariance regularisation are not, and the
/// real data show it). Seed 001 reads each cluster's prototype `cᵢ` and covariance
/// as "the parameters of the set of distributions that generate the dataset"; here they become
/// one Gaussian each, mapped back to hypertime coordinates:
///
/// * weight `πᵢ = Σⱼ uᵢⱼᵉ / Σₗⱼ uₗⱼᵉ` and
/// * covariance `Σᵢ = Cᵢ + K`, `Cᵢ = Σⱼ uᵢⱼᵉ (xⱼ − cᵢ)(xⱼ − cᵢ)ᵀ / Σⱼ uᵢⱼᵉ`, weighted like the
///   weight (`e = m` by default, see [`Moments`](super::Moments) for why not seed 001's eq. 7 `e = 1`), plus
///   the kernel `K = diag(σ_s² + f², σ_s² + f², a₁², a₁², …)`, `aₖ = 2πσ_t/Tₖ`, with `f` the
///   spatial floor (the detector's noise, [`HypertimeParams::spatial_floor`](super::HypertimeParams::spatial_floor)) and `σ_s`, `σ_t`
///   the smoothing (adding a covariance is convolving with a Gaussian: the mixture is
///   blurred by `√(σ_s² + f²)` in the plane and by about `σ_t` along each time circle);
/// * mean `μᵢ = cᵢ`.
///
/// This is a density `p(s, τ) = Σᵢ πᵢ N((s, τ); μᵢ, Σᵢ)` over `s = (x, y)` and the time
/// dimensions `τ`. At time `t` the time dimensions are known, `τ(t) = (cos ω₁t, sin ω₁t, …)`,
/// and `p(s | t) = p(s, τ(t)) / ∫ p(s', τ(t)) ds'`. Conditioning each Gaussian on `τ` splits it
/// (with `Σᵢ = [[Σ_ss, Σ_sτ], [Σ_τs, Σ_ττ]]`) into a factor of `τ` alone and a Gaussian in `s`:
///
/// `N((s, τ); μ, Σ) = N(τ; μ_τ, Σ_ττ) · N(s; μ_s + G(τ − μ_τ), Σ_ss − G Σ_τs)`,
/// `G = Σ_sτ Σ_ττ⁻¹`,
///
/// so `p(s | t) = Σᵢ wᵢ(t) N(s; mᵢ(t), Sᵢ)` with
/// `wᵢ(t) = πᵢ N(τ(t); μ_τ,ᵢ, Σ_ττ,ᵢ) / Σₖ πₖ N(τ(t); μ_τ,ₖ, Σ_ττ,ₖ)`: a mixture of 2-D
/// Gaussians whose weights and means move with the time of day. Each Gaussian integrates to 1
/// over the plane and the weights sum to 1, so the normalisation over `(x, y)` is exact, not
/// numerical; the density is per m². A [`Background`] Student-t over the training positions
/// is mixed in with weight `β`, `(1 − β) p(s | t) + β t_ν(s)` (still exactly normalised), so
/// that a detection where training saw nobody costs a few nats, not tens; the floor and `β`
/// are chosen on held-out blocks of the training data ([`Calibration`](super::Calibration)). Weights are normalised in log space, so times far from
/// every cluster (e.g. at night, when the robot saw nobody) still give a proper density,
/// dominated by the clusters nearest in time. Without periods the weights are the `πᵢ` and the
/// model is the time-independent baseline.
///
/// # Saving and loading
/// With the `serde` feature the model is saved as its projection (the periods), its
/// components (weights, means, covariances in hypertime coordinates) and its [`FitReport`];
/// the conditionals are recomputed on loading, so a loaded model gives the same densities.
/// Loading checks that there is at least one component, that each has a mean of the
/// projection's dimension, a square covariance of that size, finite values and a weight in
/// `[0, 1]`, that the weights sum to 1 (within 10⁻⁶), that the covariances are symmetric and
/// positive definite ([`AffordanceError::DegenerateCovariance`] otherwise), and that the
/// report counts at least one point per component.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(try_from = "HypertimeModelFields"))]
pub struct HypertimeModel {
    pub(super) projection: Projection,
    pub(super) components: Vec<Component>,
    #[cfg_attr(feature = "serde", serde(skip_serializing))]
    pub(super) conditionals: Vec<Conditional>,
    pub(super) background: Option<BackgroundDensity>,
    pub(super) uniform: Option<UniformDensity>,
    pub(super) report: FitReport,
}

/// The fields of a [`HypertimeModel`] as deserialised, before they are checked and the
/// conditionals computed.
#[cfg(feature = "serde")]
#[derive(serde::Deserialize)]
struct HypertimeModelFields {
    projection: Projection,
    components: Vec<Component>,
    #[serde(default)]
    background: Option<BackgroundDensity>,
    #[serde(default)]
    uniform: Option<UniformDensity>,
    report: FitReport,
}

#[cfg(feature = "serde")]
impl TryFrom<HypertimeModelFields> for HypertimeModel {
    type Error = AffordanceError;
    fn try_from(f: HypertimeModelFields) -> Result<Self> {
        let bad = |problem: String| AffordanceError::InvalidModel {
            model: "hypertime model",
            problem,
        };
        if f.components.is_empty() {
            return Err(bad("no component (a model has at least one cluster)".into()));
        }
        let dim = f.projection.dim();
        let mut total = 0.0;
        for (i, c) in f.components.iter().enumerate() {
            if c.mean.len() != dim {
                return Err(bad(format!(
                    "component {i}: mean of {} values, the projection has {dim} dimensions",
                    c.mean.len()
                )));
            }
            if c.covariance.nrows() != dim || c.covariance.ncols() != dim {
                return Err(bad(format!(
                    "component {i}: covariance of {} × {}, expected {dim} × {dim}",
                    c.covariance.nrows(),
                    c.covariance.ncols()
                )));
            }
            if !(0.0..=1.0).contains(&c.weight) {
                return Err(bad(format!(
                    "component {i}: weight {} (must be in [0, 1])",
                    c.weight
                )));
            }
            if c.mean
                .iter()
                .chain(c.covariance.iter())
                .any(|v| !v.is_finite())
            {
                return Err(bad(format!("component {i}: a value is not finite")));
            }
            let s = &c.covariance;
            for r in 0..dim {
                for q in 0..r {
                    let scale = (s[(r, r)] * s[(q, q)]).abs().sqrt();
                    if (s[(r, q)] - s[(q, r)]).abs() > 1e-9 * scale {
                        return Err(bad(format!(
                            "component {i}: covariance is not symmetric at ({r}, {q})"
                        )));
                    }
                }
            }
            total += c.weight;
        }
        if (total - 1.0).abs() > 1e-6 {
            return Err(bad(format!("the weights sum to {total}, not 1")));
        }
        if f.report.points < f.components.len() {
            return Err(bad(format!(
                "{} components for {} points",
                f.components.len(),
                f.report.points
            )));
        }
        let conditionals = f
            .components
            .iter()
            .enumerate()
            .map(|(i, c)| conditional(c, i))
            .collect::<Result<Vec<_>>>()?;
        if let Some(b) = &f.background {
            if b.student().is_none() {
                return Err(bad(
                    "background: weight outside [0, 1), dof not finite and > 0, or a scale \
                     that is not finite, symmetric and positive definite"
                        .into(),
                ));
            }
        }
        if let Some(u) = &f.uniform
            && u.log_area().is_none()
        {
            return Err(bad(
                "uniform: weight outside [0, 1), or a box that is not finite with an area".into(),
            ));
        }
        Ok(Self {
            projection: f.projection,
            components: f.components,
            conditionals,
            background: f.background,
            uniform: f.uniform,
            report: f.report,
        })
    }
}

impl HypertimeModel {
    /// The density of people over the plane at time `t` (UNIX seconds): a [`DensityMap`] in
    /// people-density per m² (integrating to 1 over the plane). At a non-finite `t` the
    /// snapshot knows nothing (`density_at` is `None`).
    pub fn at(&self, t: f64) -> HypertimeSnapshot {
        if !t.is_finite() {
            return HypertimeSnapshot {
                time: t,
                parts: Vec::new(),
                mixture: 0.0,
                background: None,
                uniform: None,
            };
        }
        let p = self.projection.periods().len() * 2;
        let mut tau = vec![0.0; p];
        self.projection.time_features(t, &mut tau);
        let mut v = vec![0.0; p];
        let mut parts: Vec<Gaussian2> = self
            .conditionals
            .iter()
            .map(|c| {
                for ((o, a), b) in v.iter_mut().zip(&tau).zip(&c.tau_mean) {
                    *o = a - b;
                }
                let mut q = 0.0;
                for (r, vr) in v.iter().enumerate() {
                    let row = &c.tau_precision[r * p..(r + 1) * p];
                    q += vr * row.iter().zip(&v).map(|(a, b)| a * b).sum::<f64>();
                }
                let shift = Vector2::new(
                    c.gain[..p].iter().zip(&v).map(|(a, b)| a * b).sum(),
                    c.gain[p..].iter().zip(&v).map(|(a, b)| a * b).sum(),
                );
                Gaussian2 {
                    log_weight: c.log_weight + c.tau_log_norm - 0.5 * q,
                    mean: Point2::from(c.space_mean + shift),
                    inverse: c.inverse,
                    log_norm: c.log_norm,
                }
            })
            .collect();
        let total = log_sum_exp(parts.iter().map(|g| g.log_weight));
        for g in &mut parts {
            g.log_weight -= total;
        }
        // ln(1 − u): the share of the mixture and the Student-t beside the uniform component.
        let rest = self.uniform.map_or(0.0, |u| (-u.weight).ln_1p());
        let background = self
            .background
            .and_then(|b| b.student().map(|t| (rest + b.weight.ln(), t)));
        let mixture = rest + self.background.map_or(0.0, |b| (-b.weight).ln_1p());
        let uniform = self
            .uniform
            .filter(|u| u.weight > 0.0)
            .map(|u| (u.weight.ln(), u));
        HypertimeSnapshot {
            time: t,
            parts,
            mixture,
            background,
            uniform,
        }
    }

    /// The background component, or `None` without one (see [`Background`]).
    pub fn background(&self) -> Option<&BackgroundDensity> {
        self.background.as_ref()
    }

    /// The uniform component, or `None` without one (see [`Uniform`](super::Uniform)).
    pub fn uniform(&self) -> Option<&UniformDensity> {
        self.uniform.as_ref()
    }

    /// `ln p(x, y | t)` of one detection (per m²), or `None` if it is not finite.
    pub fn log_density(&self, point: &TimedPoint) -> Option<f64> {
        if !point.is_finite() {
            return None;
        }
        self.at(point.time).log_density_at(point.position)
    }

    /// The mean of `ln p(x, y | t)` over the finite points, with their number (`None` if
    /// there is none); parallel with the `rayon` feature, summed in input order.
    pub fn mean_log_likelihood(&self, points: &[TimedPoint]) -> Option<(f64, usize)> {
        let values: Vec<Option<f64>> = map_slice(points, |p| self.log_density(p));
        let (sum, n) = values
            .iter()
            .flatten()
            .fold((0.0, 0usize), |(s, n), v| (s + v, n + 1));
        (n > 0).then(|| (sum / n as f64, n))
    }

    /// The projection (and so the periods) of the model.
    pub fn projection(&self) -> &Projection {
        &self.projection
    }
    /// The periods of the time dimensions, seconds (empty for the baseline).
    pub fn periods(&self) -> &[f64] {
        self.projection.periods()
    }
    /// Number of clusters (mixture components).
    pub fn clusters(&self) -> usize {
        self.components.len()
    }
    /// The mixture components, hypertime coordinates.
    pub fn components(&self) -> &[Component] {
        &self.components
    }
    /// What the fit saw and did.
    pub fn report(&self) -> &FitReport {
        &self.report
    }
}

fn log_sum_exp(values: impl Iterator<Item = f64> + Clone) -> f64 {
    let max = values.clone().fold(f64::NEG_INFINITY, f64::max);
    if max == f64::NEG_INFINITY || !max.is_finite() {
        return max;
    }
    max + values.map(|v| (v - max).exp()).sum::<f64>().ln()
}

/// Splits component `cluster` into its time factor and its conditional Gaussian in space.
pub(super) fn conditional(c: &Component, cluster: usize) -> Result<Conditional> {
    let d = c.mean.len();
    let p = d - 2;
    let bad = || AffordanceError::DegenerateCovariance { cluster };
    let sigma = &c.covariance;
    let ss = sigma.view((0, 0), (2, 2)).into_owned();
    let (tau_precision, tau_log_norm, gain, s) = if p == 0 {
        (Vec::new(), 0.0, Vec::new(), ss)
    } else {
        let tt = sigma.view((2, 2), (p, p)).into_owned();
        let st = sigma.view((0, 2), (2, p)).into_owned();
        let chol = Cholesky::new(tt).ok_or_else(bad)?;
        let log_det: f64 = 2.0
            * chol
                .l_dirty()
                .diagonal()
                .iter()
                .map(|v| v.ln())
                .sum::<f64>();
        let precision = chol.inverse();
        let gain = &st * &precision;
        let s = &ss - &gain * st.transpose();
        let tau_log_norm = -0.5 * (p as f64 * std::f64::consts::TAU.ln() + log_det);
        (
            precision.transpose().as_slice().to_vec(),
            tau_log_norm,
            gain.transpose().as_slice().to_vec(),
            s,
        )
    };
    let s = Matrix2::new(
        s[(0, 0)],
        0.5 * (s[(0, 1)] + s[(1, 0)]),
        0.5 * (s[(0, 1)] + s[(1, 0)]),
        s[(1, 1)],
    );
    let det = s.determinant();
    if !(det > 0.0 && s[(0, 0)] > 0.0 && det.is_finite()) {
        return Err(bad());
    }
    let inverse = s.try_inverse().ok_or_else(bad)?;
    Ok(Conditional {
        log_weight: c.weight.ln(),
        tau_mean: c.mean.as_slice()[2..].to_vec(),
        tau_precision,
        tau_log_norm,
        space_mean: Vector2::new(c.mean[0], c.mean[1]),
        gain,
        inverse,
        log_norm: -(std::f64::consts::TAU.ln()) - 0.5 * det.ln(),
    })
}

/// One weighted 2-D Gaussian of a snapshot.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Gaussian2 {
    log_weight: f64,
    mean: Point2<f64>,
    inverse: Matrix2<f64>,
    log_norm: f64,
}

impl Gaussian2 {
    fn log_value(&self, p: Point2<f64>) -> f64 {
        let v = p - self.mean;
        self.log_weight + self.log_norm - 0.5 * v.dot(&(self.inverse * v))
    }
}

/// The hypertime model at one time: `p(x, y | t)` as a mixture of 2-D Gaussians, per m²
/// (see [`HypertimeModel`] for the derivation).
#[derive(Debug, Clone, PartialEq)]
pub struct HypertimeSnapshot {
    time: f64,
    parts: Vec<Gaussian2>,
    /// `ln((1 − u)(1 − β))`.
    mixture: f64,
    /// `ln((1 − u) β)` and the background density.
    background: Option<(f64, StudentT2)>,
    /// `ln u` and the uniform density (`None` without one, or with `u = 0`).
    uniform: Option<(f64, UniformDensity)>,
}

impl HypertimeSnapshot {
    /// The time, UNIX seconds.
    pub fn time(&self) -> f64 {
        self.time
    }

    /// The weight `wᵢ(t)` of each component, in the model's order (they sum to 1; an empty
    /// cluster has weight 0; the mixture as a whole has weight `1 − β` beside the
    /// background), with the component's mean in the plane at this time. Empty at a
    /// non-finite time.
    pub fn weights(&self) -> Vec<(f64, Point2<f64>)> {
        self.parts
            .iter()
            .map(|g| (g.log_weight.exp(), g.mean))
            .collect()
    }

    /// `ln p(x, y | t)` per m², or `None` for a non-finite point or time.
    pub fn log_density_at(&self, p: Point2<f64>) -> Option<f64> {
        if !(p.x.is_finite() && p.y.is_finite()) || self.parts.is_empty() {
            return None;
        }
        let (mixture, background) = self.log_parts_at(p)?;
        Some(log_add_exp(mixture, background))
    }

    /// `(ln mixture, ln background)` at `p`: the mixture's share `(1 − u)(1 − β) Σᵢ wᵢ(t)
    /// N(p; …)` and the background's share `(1 − u) β t_ν(p) + u / A` (the Student-t and the
    /// uniform component; −∞ without either), whose log-sum is
    /// [`HypertimeSnapshot::log_density_at`]. Where the background's share is the larger,
    /// the model knows nothing of `p` from its training data. `None` for a non-finite point
    /// or time.
    pub fn log_parts_at(&self, p: Point2<f64>) -> Option<(f64, f64)> {
        if !(p.x.is_finite() && p.y.is_finite()) || self.parts.is_empty() {
            return None;
        }
        let mixture = self.mixture + log_sum_exp(self.parts.iter().map(|g| g.log_value(p)));
        let student = self
            .background
            .as_ref()
            .map_or(f64::NEG_INFINITY, |(w, t)| w + t.log_value(p));
        let uniform = self
            .uniform
            .as_ref()
            .map_or(f64::NEG_INFINITY, |(w, u)| w + u.log_value(p));
        Some((mixture, log_add_exp(student, uniform)))
    }
}

/// `ln(eᵃ + eᵇ)`.
pub(crate) fn log_add_exp(a: f64, b: f64) -> f64 {
    let max = a.max(b);
    if max == f64::NEG_INFINITY {
        return max;
    }
    max + ((a - max).exp() + (b - max).exp()).ln()
}

impl DensityMap for HypertimeSnapshot {
    /// `p(x, y | t)` per m²; `None` for a non-finite point or time.
    fn density_at(&self, p: Point2<f64>) -> Option<f64> {
        if !(p.x.is_finite() && p.y.is_finite()) || self.parts.is_empty() {
            return None;
        }
        self.log_density_at(p).map(f64::exp)
    }
}
