//! The hypertime model: a Gaussian mixture over the hypertime space built from a
//! Gustafson–Kessel clustering, and its density of people over the plane at any time.

use nalgebra::{Cholesky, DMatrix, DVector, Matrix2, Point2, Vector2};

use super::gk::{self, GkClustering, GkParams};
use super::projection::{DAY, Projected, Projection, TimedPoint};
use super::select::{Calibration, ClusterSearch, CycleValidation, PeriodSearch, Selection};
use crate::{AffordanceError, DensityMap, Result};

/// Parameters of [`HypertimeModel::fit`].
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Debug, Clone, PartialEq)]
pub struct HypertimeParams {
    /// Periods of the time dimensions, seconds (default one day; empty: the time-independent
    /// baseline). With [`period_search`](Self::period_search) these are the periods the
    /// search starts from.
    pub periods: Vec<f64>,
    /// The clustering (its `clusters` is `k`, default 30).
    pub gk: GkParams,
    /// Choose further periods from the data's spectrum (FreMEn), or `None` (default).
    pub period_search: Option<PeriodSearch>,
    /// Choose `k` by held-out likelihood, or `None` (default).
    pub cluster_search: Option<ClusterSearch>,
    /// Standard deviation of the smoothing in time, seconds (`≥ 0`, default 3600): the density
    /// is the mixture convolved with a Gaussian of this spread along each time circle (an
    /// arc of `2π·σ_t/T`), so a habit seen at 16:10 one day also predicts people at 16:40 the
    /// next. See [`HypertimeModel`].
    pub time_smoothing: f64,
    /// Standard deviation of the smoothing in the plane, metres (`≥ 0`, default 0).
    pub space_smoothing: f64,
    /// Radius of the time circles against the plane, metres (default `Some(1.0)`: seed 001
    /// clusters `(x, y)` in metres with the unit circle `(cos ωt, sin ωt)`). The plane is
    /// standardised and each circle keeps this radius relative to it, so the weight of time
    /// does not depend on how the data's times spread: data whose times hardly vary (a patrol
    /// at a fixed time each day) cluster as the time-independent model would. `None` divides
    /// each `(cos, sin)` pair by its own spread instead, as the plane is, making a few
    /// minutes count like metres when the times are close together. On the real people data
    /// (25 → 26 May 2017) the seed's reading scores −2.446 per detection against −2.591 with
    /// `None` (static baseline −2.914).
    pub time_radius: Option<f64>,
    /// Whether a clustering that reaches its iteration cap is an error
    /// ([`AffordanceError::NotConverged`]) rather than used as it stands (default `false`:
    /// used, and reported in [`FitReport::converged`]).
    pub require_convergence: bool,
    /// The spatial floor, metres (finite, `≥ 0`, default 0.1): every component's spread in the
    /// plane is widened by a Gaussian of this standard deviation, the detector's noise (the
    /// person detector of seed 001 localises people to about a decimetre), so no component is
    /// narrower than the detections it came from. Used as it stands without
    /// [`calibration`](Self::calibration); with it, the floor is chosen among
    /// [`Calibration::floors`].
    pub spatial_floor: f64,
    /// The background component of every density (default `Some`: a bivariate Student-t
    /// over the training positions, see [`Background`]); `None`: the mixture alone, as in
    /// seed 001.
    pub background: Option<Background>,
    /// Choose the spatial floor and the background's weight by held-out likelihood on blocks
    /// of the training data (default `Some`, see [`Calibration`]); `None` uses
    /// [`spatial_floor`](Self::spatial_floor) and [`Background::weight`] as they stand.
    pub calibration: Option<Calibration>,
    /// How periods (given and searched) are validated across cycles (see
    /// [`CycleValidation`]).
    pub validation: CycleValidation,
    /// Which power of the memberships weighs the components' weights and covariances alike
    /// (default [`Moments::Fuzzy`]).
    pub moments: Moments,
}

/// How the mixture's weights and covariances weigh the points, `πᵢ ∝ Σⱼ uᵢⱼᵉ` and
/// `Cᵢ = Σⱼ uᵢⱼᵉ (xⱼ − cᵢ)(xⱼ − cᵢ)ᵀ / Σⱼ uᵢⱼᵉ`, the same `e` in both so that a cluster's weight
/// counts the points its spread is measured on.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Moments {
    /// `e = m` (default), GK's own fuzzy covariance (eq. 2's `uᵐ`). With `m = 2` the
    /// memberships of a far point fall as `1/d²`, so `Σⱼ uᵢⱼ d²ᵢⱼ` gives every point of the
    /// data about the same pull on every cluster and the `e = 1` covariances spread over the
    /// whole map; `uᵐ` falls as `1/d⁴` and keeps them local. Measured on the real people
    /// data (`BENCHMARKS.md`).
    Fuzzy,
    /// `e = 1`, seed 001's eq. 7 as printed.
    Membership,
}

/// The background component: a bivariate Student-t over the training positions, mixed into
/// every density with weight `β`, `p(s | t) = (1 − β) Σᵢ wᵢ(t) N(s; mᵢ(t), Sᵢ) + β t_ν(s; μ, Σ)`.
///
/// `μ` and `Σ` are the mean and covariance of the training positions (plus the spatial
/// floor squared on the diagonal, so that data on a line still give a proper density). The
/// 2-D Student-t density is `t_ν(s) = (2π)⁻¹ det(Σ)^{−½} (1 + d²/ν)^{−(ν/2 + 1)}`, with `d²`
/// the Mahalanobis distance: heavy tails, so a detection where training saw nobody costs a
/// few nats, not tens (with `ν = 2`, five standard deviations away costs `2 ln 13.5 ≈ 5.2`
/// nats more than the centre). It integrates to 1 over the plane, so the density stays
/// exactly normalised. A model that knows nothing at a place says so by the background alone.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Background {
    /// Degrees of freedom `ν` (finite, `> 0`, default 2: the heaviest tails of the usual
    /// choices that keep a finite mean).
    pub dof: f64,
    /// Weight `β` in `[0, 1)` used without [`HypertimeParams::calibration`] (default 0.01).
    pub weight: f64,
}

impl Default for Background {
    /// `ν = 2`, `β = 0.01`.
    fn default() -> Self {
        Self {
            dof: 2.0,
            weight: 0.01,
        }
    }
}

impl Background {
    /// Sets the degrees of freedom.
    pub fn with_dof(mut self, dof: f64) -> Self {
        self.dof = dof;
        self
    }
    /// Sets the weight used without calibration.
    pub fn with_weight(mut self, weight: f64) -> Self {
        self.weight = weight;
        self
    }
    /// The rules, checked: `dof` finite and `> 0`, `weight` in `[0, 1)`.
    ///
    /// # Errors
    /// [`AffordanceError::InvalidParameter`] naming the first rule broken.
    pub fn check(self) -> Result<Self> {
        if !(self.dof.is_finite() && self.dof > 0.0) {
            return Err(AffordanceError::InvalidParameter {
                name: "dof",
                value: self.dof,
                rule: "must be finite and > 0",
            });
        }
        if !(0.0..1.0).contains(&self.weight) {
            return Err(AffordanceError::InvalidParameter {
                name: "weight",
                value: self.weight,
                rule: "must be in [0, 1)",
            });
        }
        Ok(self)
    }
}

impl Default for HypertimeParams {
    /// Seed 001's model: one period of a day, `k = 30`, `m = 2`, no search; beyond the seed,
    /// a Student-t background, the spatial floor and the background's weight chosen on
    /// held-out blocks of the training data, and periods validated across cycles (a given
    /// period the data cannot check, spanning fewer than two of its cycles, is kept).
    fn default() -> Self {
        Self {
            periods: vec![DAY],
            gk: GkParams::default(),
            period_search: None,
            cluster_search: None,
            time_smoothing: 3600.0,
            space_smoothing: 0.0,
            time_radius: Some(1.0),
            require_convergence: false,
            spatial_floor: 0.1,
            background: Some(Background::default()),
            calibration: Some(Calibration::default()),
            validation: CycleValidation::default(),
            moments: Moments::Fuzzy,
        }
    }
}

impl HypertimeParams {
    /// Sets the periods, seconds.
    pub fn with_periods(mut self, periods: Vec<f64>) -> Self {
        self.periods = periods;
        self
    }
    /// Sets [`HypertimeParams::time_radius`].
    pub fn with_time_radius(mut self, metres: Option<f64>) -> Self {
        self.time_radius = metres;
        self
    }
    /// Sets the clustering parameters.
    pub fn with_gk(mut self, gk: GkParams) -> Self {
        self.gk = gk;
        self
    }
    /// Sets the number of clusters `k`.
    pub fn with_clusters(mut self, clusters: usize) -> Self {
        self.gk.clusters = clusters;
        self
    }
    /// Sets the smoothing in time, seconds.
    pub fn with_time_smoothing(mut self, seconds: f64) -> Self {
        self.time_smoothing = seconds;
        self
    }
    /// Sets the smoothing in the plane, metres.
    pub fn with_space_smoothing(mut self, metres: f64) -> Self {
        self.space_smoothing = metres;
        self
    }
    /// Sets the spatial floor, metres.
    pub fn with_spatial_floor(mut self, metres: f64) -> Self {
        self.spatial_floor = metres;
        self
    }
    /// Sets (or clears) the background component.
    pub fn with_background(mut self, background: Option<Background>) -> Self {
        self.background = background;
        self
    }
    /// Sets (or clears) the calibration of the floor and the background's weight.
    pub fn with_calibration(mut self, calibration: Option<Calibration>) -> Self {
        self.calibration = calibration;
        self
    }
    /// Sets the validation of periods across cycles.
    pub fn with_validation(mut self, validation: CycleValidation) -> Self {
        self.validation = validation;
        self
    }
    /// Sets which power of the memberships weighs the moments.
    pub fn with_moments(mut self, moments: Moments) -> Self {
        self.moments = moments;
        self
    }
    /// Sets whether reaching the iteration cap is an error.
    pub fn with_require_convergence(mut self, require: bool) -> Self {
        self.require_convergence = require;
        self
    }
    /// Sets (or clears) the FreMEn period search.
    pub fn with_period_search(mut self, search: Option<PeriodSearch>) -> Self {
        self.period_search = search;
        self
    }
    /// Sets (or clears) the choice of `k` by held-out likelihood.
    pub fn with_cluster_search(mut self, search: Option<ClusterSearch>) -> Self {
        self.cluster_search = search;
        self
    }
    /// The time-independent baseline of these parameters: the same clustering without time
    /// dimensions (no period, no period search).
    pub fn without_time(mut self) -> Self {
        self.periods.clear();
        self.period_search = None;
        self
    }

    /// The parameters, checked: the periods (see [`Projection::new`]), finite non-negative
    /// smoothing, the clustering's rules and the searches' rules.
    ///
    /// # Errors
    /// [`AffordanceError::InvalidParameter`] naming the first rule broken.
    pub fn check(self) -> Result<Self> {
        Projection::new(self.periods.clone())?;
        if let Some(r) = self.time_radius {
            if !(r.is_finite() && r > 0.0) {
                return Err(AffordanceError::InvalidParameter {
                    name: "time_radius",
                    value: r,
                    rule: "must be finite and > 0 m",
                });
            }
        }
        for (name, value) in [
            ("time_smoothing", self.time_smoothing),
            ("space_smoothing", self.space_smoothing),
            ("spatial_floor", self.spatial_floor),
        ] {
            if !(value.is_finite() && value >= 0.0) {
                return Err(AffordanceError::InvalidParameter {
                    name,
                    value,
                    rule: "must be finite and >= 0",
                });
            }
        }
        self.gk.check()?;
        if let Some(b) = self.background {
            b.check()?;
        }
        if let Some(c) = &self.calibration {
            c.clone().check()?;
        }
        self.validation.check()?;
        if let Some(s) = &self.period_search {
            s.clone().check()?;
        }
        if let Some(s) = &self.cluster_search {
            s.clone().check()?;
        }
        Ok(self)
    }
}

/// One component of the mixture, in hypertime coordinates `(x, y, cos ω₁t, sin ω₁t, …)`.
///
/// With the `serde` feature the mean is written as an array and the covariance as an array
/// of rows.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Debug, Clone, PartialEq)]
pub struct Component {
    /// Mixing weight `πᵢ = Σⱼ uᵢⱼᵉ / Σₗⱼ uₗⱼᵉ` (see [`Moments`]).
    pub weight: f64,
    /// Mean: the cluster's prototype, hypertime coordinates.
    #[cfg_attr(feature = "serde", serde(with = "crate::serde_support::vector"))]
    pub mean: DVector<f64>,
    /// Covariance: the cluster's covariance weighted like its weight (see [`Moments`]) plus
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
    /// The spatial floor used, metres (see [`HypertimeParams::spatial_floor`]).
    #[cfg_attr(feature = "serde", serde(default))]
    pub spatial_floor: f64,
    /// The background's weight `β` used (0 without a background).
    #[cfg_attr(feature = "serde", serde(default))]
    pub background_weight: f64,
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
    pub fn log_value(&self, p: Point2<f64>) -> f64 {
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

/// A component's pieces for conditioning on the time dimensions, precomputed.
#[derive(Debug, Clone, PartialEq)]
struct Conditional {
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
/// [`HypertimeParams::time_radius`]; the GK iteration itself is nearly invariant to such
/// scalings, but its k-means++ initialisation and covariance regularisation are not, and the
/// real data show it). Seed 001 reads each cluster's prototype `cᵢ` and covariance
/// as "the parameters of the set of distributions that generate the dataset"; here they become
/// one Gaussian each, mapped back to hypertime coordinates:
///
/// * weight `πᵢ = Σⱼ uᵢⱼᵉ / Σₗⱼ uₗⱼᵉ` and
/// * covariance `Σᵢ = Cᵢ + K`, `Cᵢ = Σⱼ uᵢⱼᵉ (xⱼ − cᵢ)(xⱼ − cᵢ)ᵀ / Σⱼ uᵢⱼᵉ`, weighted like the
///   weight (`e = m` by default, see [`Moments`] for why not seed 001's eq. 7 `e = 1`), plus
///   the kernel `K = diag(σ_s² + f², σ_s² + f², a₁², a₁², …)`, `aₖ = 2πσ_t/Tₖ`, with `f` the
///   spatial floor (the detector's noise, [`HypertimeParams::spatial_floor`]) and `σ_s`, `σ_t`
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
/// are chosen on held-out blocks of the training data ([`Calibration`]). Weights are normalised in log space, so times far from
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
    projection: Projection,
    components: Vec<Component>,
    #[cfg_attr(feature = "serde", serde(skip_serializing))]
    conditionals: Vec<Conditional>,
    background: Option<BackgroundDensity>,
    report: FitReport,
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
        Ok(Self {
            projection: f.projection,
            components: f.components,
            conditionals,
            background: f.background,
            report: f.report,
        })
    }
}

/// Per-dimension centring and scaling of the hypertime coordinates.
#[derive(Debug, Clone)]
struct Standardise {
    shift: Vec<f64>,
    scale: Vec<f64>,
}

impl Standardise {
    /// Centres every dimension; scales `(x, y)` together by the root of their mean variance (1
    /// when that is 0), and each `(cos, sin)` pair the same way or, with `time_radius = r`
    /// metres, by the plane's scale over `r` (a circle of `r` metres).
    fn fit(p: &Projected, time_radius: Option<f64>) -> Self {
        let (dim, n) = (p.dim, p.len() as f64);
        let mut shift = vec![0.0; dim];
        for row in p.rows.chunks_exact(dim) {
            shift.iter_mut().zip(row).for_each(|(s, v)| *s += v);
        }
        shift.iter_mut().for_each(|s| *s /= n);
        let mut var = vec![0.0; dim];
        for row in p.rows.chunks_exact(dim) {
            for ((v, x), m) in var.iter_mut().zip(row).zip(&shift) {
                *v += (x - m) * (x - m);
            }
        }
        var.iter_mut().for_each(|v| *v /= n);
        let mut scale = vec![1.0; dim];
        for g in 0..dim / 2 {
            let s = (0.5 * (var[2 * g] + var[2 * g + 1])).sqrt();
            let size = shift[2 * g].abs().max(shift[2 * g + 1].abs()).max(1.0);
            let s = if s > 1e-9 * size { s } else { 1.0 };
            let s = match time_radius {
                Some(r) if g > 0 => scale[0] / r,
                _ => s,
            };
            scale[2 * g] = s;
            scale[2 * g + 1] = s;
        }
        Self { shift, scale }
    }

    fn apply(&self, rows: &[f64]) -> Vec<f64> {
        let dim = self.shift.len();
        let mut out = rows.to_vec();
        for row in out.chunks_exact_mut(dim) {
            for ((x, m), s) in row.iter_mut().zip(&self.shift).zip(&self.scale) {
                *x = (*x - m) / s;
            }
        }
        out
    }
}

/// What one fit produces beside the model: the clustering, the clusters' moments and the
/// positions, so that the model can be rebuilt with another floor or background weight.
pub(crate) struct Fitted {
    pub(crate) model: HypertimeModel,
    pub(crate) clustering: GkClustering,
    /// Weight, mean and membership-weighted covariance of every cluster, hypertime
    /// coordinates, before the smoothing kernel and the floor.
    moments: Vec<Component>,
    positions: Vec<Point2<f64>>,
}

/// The spatial floor (metres) and background weight a model is built with.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Tuning {
    pub(crate) floor: f64,
    pub(crate) background: f64,
}

impl Tuning {
    /// The values of `params` as they stand (no calibration).
    pub(crate) fn of(params: &HypertimeParams) -> Self {
        Self {
            floor: params.spatial_floor,
            background: params.background.map_or(0.0, |b| b.weight),
        }
    }
}

impl Fitted {
    /// The same clustering built into a model with `tuning`.
    ///
    /// # Errors
    /// [`AffordanceError::DegenerateCovariance`] if a component's covariance is not positive
    /// definite.
    pub(crate) fn retune(
        &self,
        params: &HypertimeParams,
        tuning: Tuning,
    ) -> Result<HypertimeModel> {
        assemble(
            self.model.projection.clone(),
            &self.moments,
            &self.positions,
            params,
            tuning,
            self.model.report.clone(),
        )
    }

    /// The training positions.
    pub(crate) fn positions(&self) -> &[Point2<f64>] {
        &self.positions
    }
}

impl HypertimeModel {
    /// Fits the model to detections (seed 001): projects them to hypertime (non-finite ones are
    /// skipped and counted), clusters them with [`GkParams::fit`], builds the mixture and its
    /// conditionals (see the type's docs). With a period or cluster search, those run first on
    /// a held-out split of `points` and the final model is fitted on all of them.
    ///
    /// # Errors
    /// [`AffordanceError::InvalidParameter`] for bad parameters;
    /// [`AffordanceError::TooFewPoints`] when fewer finite points than clusters remain;
    /// [`AffordanceError::EmptyHoldOut`] when a search's split leaves one side empty; the
    /// the clustering's errors ([`AffordanceError::NotConverged`] only with
    /// [`require_convergence`](HypertimeParams::require_convergence); it carries the clustering
    /// in the standardised space it ran in).
    ///
    /// # Complexity
    /// One clustering (`O(n·k·d²)` per iteration), plus one per period tried and per `k`
    /// candidate with the searches.
    ///
    /// ```
    /// use haunts_affordance::hypertime::{HypertimeModel, HypertimeParams, TimedPoint};
    /// use haunts_affordance::DensityMap;
    /// use nalgebra::Point2;
    /// // Mornings at (0, 0), afternoons at (10, 0), over three days.
    /// let mut points = Vec::new();
    /// for day in 0..3 {
    ///     for i in 0..60 {
    ///         let t = day as f64 * 86_400.0 + 9.0 * 3600.0 + i as f64 * 60.0;
    ///         let jitter = (i % 7) as f64 * 0.1;
    ///         points.push(TimedPoint::new(t, jitter, jitter));
    ///         points.push(TimedPoint::new(t + 5.0 * 3600.0, 10.0 + jitter, jitter));
    ///     }
    /// }
    /// let params = HypertimeParams::default().with_clusters(4);
    /// let model = HypertimeModel::fit(&points, &params)?;
    /// let morning = model.at(9.5 * 3600.0);
    /// let here = morning.density_at(Point2::new(0.3, 0.3)).unwrap();
    /// let there = morning.density_at(Point2::new(10.3, 0.3)).unwrap();
    /// // The background keeps a little density everywhere, so "not there" is a ratio, not 0.
    /// assert!(here > 10.0 * there);
    /// assert!(model.report().selection.period_steps[0].accepted); // three days: validated
    /// # Ok::<(), haunts_affordance::AffordanceError>(())
    /// ```
    pub fn fit(points: &[TimedPoint], params: &HypertimeParams) -> Result<Self> {
        let params = params.clone().check()?;
        let finite: Vec<TimedPoint> = points.iter().copied().filter(|p| p.is_finite()).collect();
        let skipped = points.len() - finite.len();
        let (periods, gk, tuning, selection) = super::select::choose(&finite, &params)?;
        let mut fitted = fit_once(&finite, periods, &gk, &params, tuning)?;
        fitted.model.report.skipped = skipped;
        fitted.model.report.selection = selection;
        Ok(fitted.model)
    }

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
        let background = self
            .background
            .and_then(|b| b.student().map(|t| (b.weight.ln(), t)));
        let mixture = self.background.map_or(0.0, |b| (-b.weight).ln_1p());
        HypertimeSnapshot {
            time: t,
            parts,
            mixture,
            background,
        }
    }

    /// The background component, or `None` without one (see [`Background`]).
    pub fn background(&self) -> Option<&BackgroundDensity> {
        self.background.as_ref()
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

/// `(0..n).map(f)` in order, in parallel with the `rayon` feature.
pub(crate) fn map_slice<T: Sync, U: Send>(
    items: &[T],
    f: impl Fn(&T) -> U + Sync + Send,
) -> Vec<U> {
    #[cfg(feature = "rayon")]
    {
        use rayon::prelude::*;
        items.par_iter().map(f).collect()
    }
    #[cfg(not(feature = "rayon"))]
    items.iter().map(f).collect()
}

fn log_sum_exp(values: impl Iterator<Item = f64> + Clone) -> f64 {
    let max = values.clone().fold(f64::NEG_INFINITY, f64::max);
    if max == f64::NEG_INFINITY || !max.is_finite() {
        return max;
    }
    max + values.map(|v| (v - max).exp()).sum::<f64>().ln()
}

/// Projects, standardises, clusters and builds the model for fixed periods and `k`; the
/// smoothing and convergence policy come from `params`, the floor and background weight from
/// `tuning`.
pub(crate) fn fit_once(
    points: &[TimedPoint],
    periods: Vec<f64>,
    gk: &GkParams,
    params: &HypertimeParams,
    tuning: Tuning,
) -> Result<Fitted> {
    let projection = Projection::new(periods)?;
    let projected = projection.project(points);
    if projected.len() < gk.clusters || projected.is_empty() {
        return Err(AffordanceError::TooFewPoints {
            points: projected.len(),
            clusters: gk.clusters,
        });
    }
    let dim = projected.dim;
    let standardise = Standardise::fit(&projected, params.time_radius);
    let rows = standardise.apply(&projected.rows);
    let (clustering, converged) = match gk.fit(&rows, dim) {
        Ok(c) => (c, true),
        Err(AffordanceError::NotConverged { partial, .. }) if !params.require_convergence => {
            (*partial, false)
        }
        Err(e) => return Err(e),
    };
    let exponent = match params.moments {
        Moments::Fuzzy => gk.fuzzifier,
        Moments::Membership => 1.0,
    };
    let moments = moments(&clustering, &rows, &standardise, exponent)?;
    let positions: Vec<Point2<f64>> = projected
        .rows
        .chunks_exact(dim)
        .map(|r| Point2::new(r[0], r[1]))
        .collect();
    let report = FitReport {
        points: projected.len(),
        skipped: projected.skipped,
        iterations: clustering.iterations(),
        converged,
        change: clustering.change(),
        objective: clustering.objective(),
        spatial_floor: tuning.floor,
        background_weight: 0.0,
        selection: Selection::default(),
    };
    let model = assemble(projection, &moments, &positions, params, tuning, report)?;
    Ok(Fitted {
        model,
        clustering,
        moments,
        positions,
    })
}

/// Every cluster's weight `πᵢ = Σⱼ uᵢⱼᵉ / Σₗⱼ uₗⱼᵉ`, mean (its prototype) and covariance
/// weighted like its weight, `Cᵢ = Σⱼ uᵢⱼᵉ (xⱼ − cᵢ)(xⱼ − cᵢ)ᵀ / Σⱼ uᵢⱼᵉ` (see [`Moments`]),
/// mapped back to hypertime coordinates, unregularised (the floor and the smoothing kernel
/// are added by [`assemble`]; a ridge of 10⁻⁹ of the standardised unit keeps a cluster on one
/// point proper). Summed blockwise in block order (the same on any number of threads).
fn moments(
    clustering: &GkClustering,
    rows: &[f64],
    standardise: &Standardise,
    exponent: f64,
) -> Result<Vec<Component>> {
    let (k, d) = (clustering.clusters(), clustering.dim());
    let centres = clustering.centres();
    let memberships = clustering.memberships();
    let blocks: Vec<(&[f64], &[f64])> = rows
        .chunks(gk::BLOCK * d)
        .zip(memberships.chunks(gk::BLOCK * k))
        .collect();
    let parts: Vec<Vec<f64>> = map_slice(&blocks, |(x, u)| {
        let mut acc = vec![0.0; k * (d * d + 1)];
        let mut v = vec![0.0; d];
        for (x, u) in x.chunks_exact(d).zip(u.chunks_exact(k)) {
            for (i, &w) in u.iter().enumerate() {
                let w = if exponent == 1.0 {
                    w
                } else if exponent == 2.0 {
                    w * w
                } else {
                    w.powf(exponent)
                };
                let c = &centres[i * d..(i + 1) * d];
                v.iter_mut()
                    .zip(x.iter().zip(c))
                    .for_each(|(o, (a, b))| *o = a - b);
                let a = &mut acc[i * (d * d + 1)..(i + 1) * (d * d + 1)];
                a[0] += w;
                for r in 0..d {
                    let wr = w * v[r];
                    for q in 0..d {
                        a[1 + r * d + q] += wr * v[q];
                    }
                }
            }
        }
        acc
    });
    let mut acc = vec![0.0; k * (d * d + 1)];
    for part in &parts {
        acc.iter_mut().zip(part).for_each(|(a, b)| *a += b);
    }
    let n: f64 = (0..k).map(|i| acc[i * (d * d + 1)]).sum();
    let scale = DMatrix::from_diagonal(&DVector::from_column_slice(&standardise.scale));
    let shift = DVector::from_column_slice(&standardise.shift);
    (0..k)
        .map(|i| {
            let a = &acc[i * (d * d + 1)..(i + 1) * (d * d + 1)];
            let centre = clustering
                .centre(i)
                .ok_or(AffordanceError::DegenerateCovariance { cluster: i })?;
            let total = a[0];
            let mut c = if total > 0.0 {
                DMatrix::from_row_slice(d, d, &a[1..]) / total
            } else {
                DMatrix::identity(d, d)
            };
            for r in 0..d {
                c[(r, r)] += 1e-9;
            }
            let covariance = &scale * c * &scale;
            Ok(Component {
                weight: total / n,
                mean: &shift + &scale * DVector::from_column_slice(centre),
                covariance: (&covariance + covariance.transpose()) * 0.5,
            })
        })
        .collect()
}

/// The model of `moments` with the smoothing kernel of `params`, the floor and background
/// weight of `tuning` and the background over `positions`.
fn assemble(
    projection: Projection,
    moments: &[Component],
    positions: &[Point2<f64>],
    params: &HypertimeParams,
    tuning: Tuning,
    mut report: FitReport,
) -> Result<HypertimeModel> {
    // The kernel's variance along each dimension, hypertime coordinates: the floor and the
    // smoothing in the plane, the smoothing along each time circle.
    let plane = params.space_smoothing.powi(2) + tuning.floor.powi(2);
    let mut kernel = vec![plane; 2];
    for period in projection.periods() {
        let arc = std::f64::consts::TAU * params.time_smoothing / period;
        kernel.extend([arc * arc; 2]);
    }
    let components: Vec<Component> = moments
        .iter()
        .map(|m| {
            let mut c = m.clone();
            for (i, v) in kernel.iter().enumerate() {
                c.covariance[(i, i)] += v;
            }
            c
        })
        .collect();
    let conditionals = components
        .iter()
        .enumerate()
        .map(|(i, c)| conditional(c, i))
        .collect::<Result<Vec<_>>>()?;
    let background = match params.background {
        Some(b) if tuning.background > 0.0 => {
            BackgroundDensity::over(positions, tuning.floor, b.with_weight(tuning.background))
        }
        _ => None,
    };
    report.spatial_floor = tuning.floor;
    report.background_weight = background.map_or(0.0, |b| b.weight);
    Ok(HypertimeModel {
        projection,
        components,
        conditionals,
        background,
        report,
    })
}

/// Splits component `cluster` into its time factor and its conditional Gaussian in space.
fn conditional(c: &Component, cluster: usize) -> Result<Conditional> {
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
    /// `ln(1 − β)`.
    mixture: f64,
    /// `ln β` and the background density.
    background: Option<(f64, StudentT2)>,
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
        let mixture = self.mixture + log_sum_exp(self.parts.iter().map(|g| g.log_value(p)));
        Some(match &self.background {
            Some((w, t)) => log_add_exp(mixture, w + t.log_value(p)),
            None => mixture,
        })
    }

    /// `ln` of the background's share `β t_ν(p)` and of the mixture's share
    /// `(1 − β) Σᵢ wᵢ(t) N(p; …)` at `p` (−∞ for a missing background), or `None` for a
    /// non-finite point or time.
    pub fn log_parts_at(&self, p: Point2<f64>) -> Option<(f64, f64)> {
        if !(p.x.is_finite() && p.y.is_finite()) || self.parts.is_empty() {
            return None;
        }
        let mixture = self.mixture + log_sum_exp(self.parts.iter().map(|g| g.log_value(p)));
        let background = self
            .background
            .as_ref()
            .map_or(f64::NEG_INFINITY, |(w, t)| w + t.log_value(p));
        Some((mixture, background))
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
