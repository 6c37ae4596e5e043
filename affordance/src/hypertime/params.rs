//! The parameters of a hypertime fit and of its searches, and the reports of what the
//! searches chose: below the model, the fit and the searches, which all read them.

use super::gk::GkParams;
use super::projection::{DAY, Projection, TimedPoint};
use crate::{AffordanceError, Result};

/// Parameters of [`HypertimeModel::fit`](super::HypertimeModel::fit).
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
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
    /// next. See [`HypertimeModel`](super::HypertimeModel).
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
    /// used, and reported in [`FitReport::converged`](super::FitReport::converged)).
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
    /// The uniform component of every density (default `Some`, see [`Uniform`]): what the
    /// model owes a place its training data never showed, over the training area.
    /// `None`: no uniform component.
    #[cfg_attr(feature = "serde", serde(default))]
    pub uniform: Option<Uniform>,
    /// Choose the spatial floor and the background's and the uniform component's weights by
    /// held-out likelihood on a later part of the training data (default `Some`, see
    /// [`Calibration`]); `None` uses [`spatial_floor`](Self::spatial_floor),
    /// [`Background::weight`] and [`Uniform::weight`] as they stand.
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
        haunts_core::positive("dof", self.dof)?;
        if !(0.0..1.0).contains(&self.weight) {
            return Err(AffordanceError::InvalidParameter(
                haunts_core::InvalidParameter {
                    name: "weight",
                    value: self.weight,
                    rule: "must be in [0, 1)",
                },
            ));
        }
        Ok(self)
    }
}

/// The uniform component: every density is `(1 − u)·p(s | t) + u / A` inside the box of the
/// training positions grown by `margin` on every side (area `A`), and `(1 − u)·p(s | t)`
/// outside it, where `p` is the mixture with its Student-t [`Background`].
///
/// Why both: the Student-t is spread over the *training positions*, so where the next day's
/// people walk elsewhere within the site it still gives them the tail of a distribution
/// centred on yesterday's crowd, and a model trained on a crowd in one room is over-confident
/// in the next. The uniform component is what a model that knows nothing would say, over the
/// area the uniform reference of [`evaluate`](super::evaluate) uses (its grid bounds the
/// training detections with 1 m to spare: `margin`'s default); with weight `u` a detection
/// anywhere in that area costs at most `ln(1/u)` nats more than the uniform reference. `u`
/// is fitted with the floor and the background's weight ([`Calibration`]); by maximum
/// likelihood on held-out training data, so it is large only where the training data's own
/// later part went where its earlier part had not.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Uniform {
    /// Growth of the training positions' box on every side, metres (finite, `≥ 0`,
    /// default 1).
    pub margin: f64,
    /// Weight `u` in `[0, 1)` used without [`HypertimeParams::calibration`] (default 0).
    pub weight: f64,
}

impl Default for Uniform {
    /// A 1 m margin, `u = 0`.
    fn default() -> Self {
        Self {
            margin: 1.0,
            weight: 0.0,
        }
    }
}

impl Uniform {
    /// Sets the weight used without calibration.
    pub fn with_weight(mut self, weight: f64) -> Self {
        self.weight = weight;
        self
    }
    /// Sets the margin, metres.
    pub fn with_margin(mut self, margin: f64) -> Self {
        self.margin = margin;
        self
    }
    /// The rules, checked: `margin` finite and `≥ 0`, `weight` in `[0, 1)`.
    ///
    /// # Errors
    /// [`AffordanceError::InvalidParameter`] naming the first rule broken.
    pub fn check(self) -> Result<Self> {
        haunts_core::non_negative("margin", self.margin)?;
        if !(0.0..1.0).contains(&self.weight) {
            return Err(AffordanceError::InvalidParameter(
                haunts_core::InvalidParameter {
                    name: "uniform.weight",
                    value: self.weight,
                    rule: "must be in [0, 1)",
                },
            ));
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
            uniform: Some(Uniform::default()),
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
    /// Sets (or clears) the uniform component.
    pub fn with_uniform(mut self, uniform: Option<Uniform>) -> Self {
        self.uniform = uniform;
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
                return Err(AffordanceError::InvalidParameter(
                    haunts_core::InvalidParameter {
                        name: "time_radius",
                        value: r,
                        rule: "must be finite and > 0 m",
                    },
                ));
            }
        }
        for (name, value) in [
            ("time_smoothing", self.time_smoothing),
            ("space_smoothing", self.space_smoothing),
            ("spatial_floor", self.spatial_floor),
        ] {
            haunts_core::non_negative(name, value)?;
        }
        self.gk.check()?;
        if let Some(b) = self.background {
            b.check()?;
        }
        if let Some(u) = self.uniform {
            u.check()?;
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

/// How a search holds data out: time is cut into blocks of `block` seconds and every
/// `every`-th block (the last of each run of `every`) is held out. Whole blocks, not single
/// detections, are held out because detections a second apart are near copies of each other.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HoldOut {
    /// Block length, seconds (> 0).
    pub block: f64,
    /// One block in `every` is held out (≥ 2).
    pub every: usize,
}

impl Default for HoldOut {
    /// Blocks of 10 minutes, one in five held out.
    fn default() -> Self {
        Self {
            block: 600.0,
            every: 5,
        }
    }
}

impl HoldOut {
    /// The rules, checked: `block` finite and > 0, `every ≥ 2`.
    ///
    /// # Errors
    /// [`AffordanceError::InvalidParameter`] naming the first rule broken.
    pub fn check(self) -> Result<Self> {
        if !(self.block.is_finite() && self.block > 0.0) {
            return Err(AffordanceError::InvalidParameter(
                haunts_core::InvalidParameter {
                    name: "block",
                    value: self.block,
                    rule: "must be finite and > 0 s",
                },
            ));
        }
        if self.every < 2 {
            return Err(AffordanceError::InvalidParameter(
                haunts_core::InvalidParameter {
                    name: "every",
                    value: self.every as f64,
                    rule: "must be >= 2",
                },
            ));
        }
        Ok(self)
    }

    /// `(kept, held out)`, each in input order.
    ///
    /// # Errors
    /// [`AffordanceError::EmptyHoldOut`] if either side is empty.
    pub fn split(&self, points: &[TimedPoint]) -> Result<(Vec<TimedPoint>, Vec<TimedPoint>)> {
        let every = self.every as f64;
        let (held, kept): (Vec<TimedPoint>, Vec<TimedPoint>) = points
            .iter()
            .partition(|p| (p.time / self.block).floor().rem_euclid(every) == every - 1.0);
        if held.is_empty() || kept.is_empty() {
            return Err(AffordanceError::EmptyHoldOut {
                points: points.len(),
            });
        }
        Ok((kept, held))
    }
}

/// FreMEn period selection (Krajník et al., "FreMEn", IEEE T-RO 2017, applied as seed 001's
/// outlook proposes): starting from the validated periods, repeatedly take the candidate
/// period at which the spectrum of the current model's residual has the largest amplitude,
/// and keep it while it passes the [`CycleValidation`] (the training data span at least
/// `min_cycles` of its cycles over at least two held-out blocks, and leaving whole blocks
/// out, the likelihood rises by more than the margin). Candidates the data cannot validate
/// (fewer cycles or blocks: one day of training data) are not tried.
///
/// **The residual.** Detections are events, not a sampled state, so the signal is *where*
/// people are: each detection `j` is labelled with the cluster `c(j)` of its largest
/// membership in the starting model (spatial cells when it starts without periods). The
/// current model predicts, at `tⱼ`, the distribution of labels `qⱼ = Σₗ wₗ(tⱼ) aₗ`, with
/// `wₗ(t)` its component weights at `t` and `aₗ` the share of cluster `l`'s membership
/// falling on each label. The residual is `rⱼ = e_{c(j)} − qⱼ` (for the model without periods,
/// the label indicators minus their mean, FreMEn's first step) and the amplitude at period
/// `T` is `|(1/n) Σⱼ rⱼ e^{−2πi tⱼ/T}|` (Euclidean norm over labels).
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Debug, Clone, PartialEq)]
pub struct PeriodSearch {
    /// Candidate periods, seconds (each finite, > 0).
    pub candidates: Vec<f64>,
    /// At most this many periods are added.
    pub max_periods: usize,
}

impl Default for PeriodSearch {
    /// FreMEn's usual candidates `T = 1 day / k`, `k = 1…24` (a day down to an hour); up to 3
    /// periods.
    fn default() -> Self {
        Self {
            candidates: (1..=24).map(|k| DAY / k as f64).collect(),
            max_periods: 3,
        }
    }
}

impl PeriodSearch {
    /// The rules, checked: finite positive candidates.
    ///
    /// # Errors
    /// [`AffordanceError::InvalidParameter`] naming the first rule broken.
    pub fn check(self) -> Result<Self> {
        if let Some(&bad) = self
            .candidates
            .iter()
            .find(|p| !(p.is_finite() && **p > 0.0))
        {
            return Err(AffordanceError::InvalidParameter(
                haunts_core::InvalidParameter {
                    name: "candidates",
                    value: bad,
                    rule: "every candidate period must be finite and > 0 s",
                },
            ));
        }
        Ok(self)
    }
}

/// What to do with a given period ([`HypertimeParams::periods`]) that the validation rejects
/// or cannot check.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum GivenPeriods {
    /// Keep every given period unchecked (seed 001: the daily period is chosen a priori).
    Trust,
    /// Validate those the data can check (dropping the rejected ones) and keep those spanning
    /// fewer than `min_cycles` cycles or fewer than two blocks as given (default: one day of training data cannot check
    /// a daily period, and on the real people data the daily period trained on one day still
    /// predicts the next better than the static model, `BENCHMARKS.md`).
    KeepUnverifiable,
    /// Keep a given period only if it is validated.
    Validate,
}

/// Validation of periods across cycles, on held-out *blocks* of time: a period `T` is
/// accepted only when the training data fall in at least `min_cycles` of its cycles
/// (distinct `⌊t / T⌋`), spread over at least two blocks, and the likelihood of whole
/// held-out blocks rises by more than `margin` nats per detection when `T` is added.
///
/// **The blocks.** Time is cut into blocks of `B = max(block, T)` seconds (default `block`:
/// one day), starting at the quietest time of the period `B` (the middle of the longest run of
/// empty 1/96ths of `B` in the data folded onto `B`, or the emptiest one): with the default,
/// a block is one working day of the robot whatever its time zone. The blocks holding data,
/// in order, are dealt round robin into `F = min(max_folds, blocks)` folds; each fold is
/// scored by the models, with and without `T`, fitted on the others, and the gain is the
/// difference of the mean log-likelihoods over all held-out detections.
///
/// Why blocks of a day and not cycles of `T`: a day of training data holds fifteen cycles of
/// a 1.6 h period, and leaving one out asks only whether the rest of *that day* predicts it,
/// so a pattern of one afternoon passes (on the real people data it did, and lost to the
/// static model on the next day, `BENCHMARKS.md`). Holding out whole days asks whether a
/// period predicts time ranges of days it did not see, which is what a model used on the next
/// day must do; a period longer than the block holds out whole cycles of its own. A single
/// block (one day of training data) cannot validate any period: every candidate of the
/// search is then left untried, and a given period follows [`GivenPeriods`].
/// The margin, block and folds are chosen a priori (never on test data).
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CycleValidation {
    /// Minimum gain of held-out mean log-likelihood, nats per detection (finite, `≥ 0`,
    /// default 0.02).
    pub margin: f64,
    /// Cycles the data must span (`≥ 2`, default 2).
    pub min_cycles: usize,
    /// The shortest held-out block, seconds (finite, `> 0`, default one day). Also the blocks
    /// the [`ClusterSearch`] holds out when the data span two of them.
    #[cfg_attr(feature = "serde", serde(default = "default_block"))]
    pub block: f64,
    /// At most this many folds (`≥ 2`, default 3: each fold costs two fits).
    pub max_folds: usize,
    /// What happens to the given periods (default [`GivenPeriods::KeepUnverifiable`]).
    pub given: GivenPeriods,
}

#[cfg(feature = "serde")]
fn default_block() -> f64 {
    DAY
}

impl Default for CycleValidation {
    /// A margin of 0.02 nats, two cycles, blocks of a day, three folds, given periods kept
    /// when unverifiable.
    fn default() -> Self {
        Self {
            margin: 0.02,
            min_cycles: 2,
            block: DAY,
            max_folds: 3,
            given: GivenPeriods::KeepUnverifiable,
        }
    }
}

impl CycleValidation {
    /// Sets the margin, nats per detection.
    pub fn with_margin(mut self, margin: f64) -> Self {
        self.margin = margin;
        self
    }
    /// Sets the shortest held-out block, seconds.
    pub fn with_block(mut self, seconds: f64) -> Self {
        self.block = seconds;
        self
    }
    /// Sets the policy for given periods.
    pub fn with_given(mut self, given: GivenPeriods) -> Self {
        self.given = given;
        self
    }
    /// The rules, checked: `margin` finite and `≥ 0`, `block` finite and `> 0`,
    /// `min_cycles ≥ 2`, `max_folds ≥ 2`.
    ///
    /// # Errors
    /// [`AffordanceError::InvalidParameter`] naming the first rule broken.
    pub fn check(self) -> Result<Self> {
        haunts_core::non_negative("margin", self.margin)?;
        if !(self.block.is_finite() && self.block > 0.0) {
            return Err(AffordanceError::InvalidParameter(
                haunts_core::InvalidParameter {
                    name: "block",
                    value: self.block,
                    rule: "must be finite and > 0 s",
                },
            ));
        }
        for (name, value) in [
            ("min_cycles", self.min_cycles),
            ("max_folds", self.max_folds),
        ] {
            if value < 2 {
                return Err(AffordanceError::InvalidParameter(
                    haunts_core::InvalidParameter {
                        name,
                        value: value as f64,
                        rule: "must be >= 2",
                    },
                ));
            }
        }
        Ok(self)
    }
}

/// The choice of the spatial floor, the background's weight `β` and the uniform
/// component's weight `u`, by held-out mean log-likelihood (maximum likelihood over the
/// candidates; the first in the lists' order on ties), in two stages on two splits of the
/// training data:
///
/// 1. **The floor and `β`** on interleaved blocks ([`holdout`](Self::holdout)): the model is
///    fitted on the kept blocks and scored on the held-out ones for every floor and `β`. The
///    blocks see the day's places on both sides, so this measures how sharp the density may
///    be (the floor is the detector's noise) and how heavy its tails.
/// 2. **`u`** on the later part ([`later`](Self::later)): the part a model must predict as it
///    will predict the next day. When the training data span several UTC days, the last day
///    is held out; within one day, the last `later` share of its time span (a quarter by
///    default). The model with the floor and `β` of stage 1 is fitted on the earlier part and
///    scored on the later for every `u`. A later part that goes where the earlier did not
///    (people drifting from room to room over the day, a site that changes) asks for a large
///    `u`; a later part like the earlier asks for none. Within one day the later hours are
///    also hours the earlier part never saw, so a periodic model's `u` errs large (the next
///    day's hours were seen the day before): the safe side on a new site.
///
/// Why two splits, not one: the floor chosen on the later part (measured on the shared
/// people data, train on one day, test on the next) is the coarsest candidate, 0.5 m, and
/// costs hypertime 0.7 nats per test detection and its lead over the static model; the
/// later part is evidence of novelty, not of the detector's noise. With `later = None`, `u`
/// is chosen with the floor and `β` on the blocks. The Student-t, the uniform component,
/// both or neither come out of the choice: a weight of 0 is a candidate of each.
///
/// Only the training data are used. When a split leaves too little to fit, the values of
/// [`HypertimeParams::spatial_floor`], [`Background::weight`](super::Background::weight) and
/// [`Uniform::weight`] are used and the report says so.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Debug, Clone, PartialEq)]
pub struct Calibration {
    /// Candidate floors, metres (finite, `≥ 0`; default 0.05, 0.1, 0.2, 0.3, 0.5: from
    /// below to well above the decimetre of a laser person detector).
    pub floors: Vec<f64>,
    /// Candidate background weights in `[0, 1)` (default 0, 0.001, 0.003, 0.01, 0.03, 0.1,
    /// 0.3).
    pub weights: Vec<f64>,
    /// Candidate uniform weights in `[0, 1)` (default 0, 0.001, 0.01, 0.03, 0.1, 0.2, 0.3,
    /// 0.5, 0.7, 0.9, 0.97, 0.99: up to a model that is nearly the uniform reference, for
    /// training data whose later part it cannot predict at all). Saved parameters without the
    /// field read as `[0]`, as they were fitted.
    #[cfg_attr(feature = "serde", serde(default = "no_uniform"))]
    pub uniform_weights: Vec<f64>,
    /// The share of a single day's time span held out at its end to choose `u` (in `(0, 1)`,
    /// default `Some(0.25)`; the last day when there are several); `None`: `u` is chosen
    /// with the floor on the blocks of [`holdout`](Self::holdout). Saved parameters without
    /// the field read as `None`.
    #[cfg_attr(feature = "serde", serde(default))]
    pub later: Option<f64>,
    /// The interleaved split of the floor and `β` (one-hour blocks, one in three held out:
    /// longer than the search's ten minutes, so that held-out blocks can show places the kept
    /// ones did not).
    pub holdout: HoldOut,
}

#[cfg(feature = "serde")]
fn no_uniform() -> Vec<f64> {
    vec![0.0]
}

impl Default for Calibration {
    /// See the fields.
    fn default() -> Self {
        Self {
            floors: vec![0.05, 0.1, 0.2, 0.3, 0.5],
            weights: vec![0.0, 0.001, 0.003, 0.01, 0.03, 0.1, 0.3],
            uniform_weights: vec![
                0.0, 0.001, 0.01, 0.03, 0.1, 0.2, 0.3, 0.5, 0.7, 0.9, 0.97, 0.99,
            ],
            later: Some(0.25),
            holdout: HoldOut {
                block: 3600.0,
                every: 3,
            },
        }
    }
}

impl Calibration {
    /// `(kept, held out)` of `points` by the split `u` is chosen on (see the type's docs):
    /// the later part, or the blocks without [`later`](Self::later); each in input order.
    ///
    /// # Errors
    /// [`AffordanceError::EmptyHoldOut`] if either side is empty.
    pub fn split(&self, points: &[TimedPoint]) -> Result<(Vec<TimedPoint>, Vec<TimedPoint>)> {
        let Some(share) = self.later else {
            return self.holdout.split(points);
        };
        let day = |t: f64| (t / DAY).floor();
        let times = points.iter().map(|p| p.time).filter(|t| t.is_finite());
        let (first, last) = times.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), t| {
            (a.min(t), b.max(t))
        });
        let held_out = |t: f64| {
            if day(first) < day(last) {
                day(t) == day(last)
            } else {
                t >= last - share * (last - first)
            }
        };
        let (held, kept): (Vec<TimedPoint>, Vec<TimedPoint>) =
            points.iter().partition(|p| held_out(p.time));
        if held.is_empty() || kept.is_empty() {
            return Err(AffordanceError::EmptyHoldOut {
                points: points.len(),
            });
        }
        Ok((kept, held))
    }

    /// The rules, checked: at least one floor and one weight, floors finite and `≥ 0`,
    /// weights in `[0, 1)`, the split's rules.
    ///
    /// # Errors
    /// [`AffordanceError::InvalidParameter`] naming the first rule broken.
    pub fn check(self) -> Result<Self> {
        if self.floors.is_empty() || self.weights.is_empty() {
            return Err(AffordanceError::InvalidParameter(
                haunts_core::InvalidParameter {
                    name: "calibration",
                    value: 0.0,
                    rule: "needs at least one floor and one weight",
                },
            ));
        }
        if let Some(&bad) = self.floors.iter().find(|f| !(f.is_finite() && **f >= 0.0)) {
            return Err(AffordanceError::InvalidParameter(
                haunts_core::InvalidParameter {
                    name: "floors",
                    value: bad,
                    rule: "every floor must be finite and >= 0 m",
                },
            ));
        }
        for (name, list) in [
            ("weights", &self.weights),
            ("uniform_weights", &self.uniform_weights),
        ] {
            if let Some(&bad) = list.iter().find(|w| !(0.0..1.0).contains(*w)) {
                return Err(AffordanceError::InvalidParameter(
                    haunts_core::InvalidParameter {
                        name,
                        value: bad,
                        rule: "every weight must be in [0, 1)",
                    },
                ));
            }
        }
        if self.uniform_weights.is_empty() {
            return Err(AffordanceError::InvalidParameter(
                haunts_core::InvalidParameter {
                    name: "uniform_weights",
                    value: 0.0,
                    rule: "needs at least one weight (0: no uniform component)",
                },
            ));
        }
        if let Some(share) = self.later
            && !(share > 0.0 && share < 1.0)
        {
            return Err(AffordanceError::InvalidParameter(
                haunts_core::InvalidParameter {
                    name: "later",
                    value: share,
                    rule: "must be in (0, 1)",
                },
            ));
        }
        self.holdout.check()?;
        Ok(self)
    }
}

/// The choice of `k` by held-out likelihood: each candidate is fitted on the kept part and
/// scored on the held-out part; the best score wins (the smaller `k` on ties). The held-out
/// parts are the folds of whole blocks of the [`CycleValidation`] (blocks of
/// `max(block, longest validated period)`) when the data span two of them, as periods are
/// validated; only data within one block (one day) fall back to [`ClusterSearch::holdout`].
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Debug, Clone, PartialEq)]
pub struct ClusterSearch {
    /// Candidate numbers of clusters (those above the number of kept points are skipped).
    pub candidates: Vec<usize>,
    /// The held-out split when the data span a single block of the [`CycleValidation`].
    pub holdout: HoldOut,
}

impl Default for ClusterSearch {
    /// `k ∈ {5, 10, 20, 30, 40, 60}` and the default [`HoldOut`].
    fn default() -> Self {
        Self {
            candidates: vec![5, 10, 20, 30, 40, 60],
            holdout: HoldOut::default(),
        }
    }
}

impl ClusterSearch {
    /// The rules, checked: at least one candidate, all ≥ 1, the split's rules.
    ///
    /// # Errors
    /// [`AffordanceError::InvalidParameter`] naming the first rule broken.
    pub fn check(self) -> Result<Self> {
        if self.candidates.is_empty() || self.candidates.contains(&0) {
            return Err(AffordanceError::InvalidParameter(
                haunts_core::InvalidParameter {
                    name: "candidates",
                    value: 0.0,
                    rule: "needs at least one candidate, each >= 1",
                },
            ));
        }
        self.holdout.check()?;
        Ok(self)
    }
}

/// One period checked by the [`CycleValidation`]: a given period, or one the
/// [`PeriodSearch`] proposed.
///
/// With the `serde` feature, a non-finite amplitude or score is written as `"inf"`, `"-inf"`
/// or `"NaN"` in human-readable formats, a missing one as `null`.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PeriodStep {
    /// The period, seconds.
    pub period: f64,
    /// Its amplitude in the residual spectrum (`None` for a given period).
    #[cfg_attr(
        feature = "serde",
        serde(with = "haunts_occupancy::serde_float::option")
    )]
    pub amplitude: Option<f64>,
    /// Cycles of it that hold training data (distinct `⌊t / T⌋`: for a day, UTC days).
    pub cycles: usize,
    /// Held-out blocks of [`CycleValidation`] that hold training data (fewer than two: it
    /// could not be checked).
    #[cfg_attr(feature = "serde", serde(default))]
    pub blocks: usize,
    /// Held-out (left-out blocks) mean log-likelihood without it (`None` when not checked).
    #[cfg_attr(
        feature = "serde",
        serde(with = "haunts_occupancy::serde_float::option")
    )]
    pub without_loglik: Option<f64>,
    /// Held-out mean log-likelihood with it (`None` when not checked).
    #[cfg_attr(
        feature = "serde",
        serde(with = "haunts_occupancy::serde_float::option")
    )]
    pub heldout_loglik: Option<f64>,
    /// Whether it passed the validation.
    pub accepted: bool,
    /// Whether the model kept it (accepted, or given and kept by [`GivenPeriods`]).
    pub kept: bool,
}

/// What the calibration chose (see [`Calibration`]).
///
/// With the `serde` feature, a non-finite score is written as a string.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Debug, Clone, PartialEq)]
pub struct CalibrationReport {
    /// The floor chosen, metres.
    pub floor: f64,
    /// The background weight chosen.
    pub weight: f64,
    /// The uniform component's weight chosen (0 without one).
    #[cfg_attr(feature = "serde", serde(default))]
    pub uniform_weight: f64,
    /// Its held-out mean log-likelihood (`None` when the split left too little to fit and
    /// the parameters' values were used).
    #[cfg_attr(
        feature = "serde",
        serde(with = "haunts_occupancy::serde_float::option")
    )]
    pub heldout_loglik: Option<f64>,
    /// Held-out detections it was scored on.
    pub heldout: usize,
    /// The held-out mean log-likelihood of the uniform weight chosen on the later part
    /// ([`Calibration::later`]; `None` when it was chosen with the floor, or not at all).
    #[cfg_attr(
        feature = "serde",
        serde(default, with = "haunts_occupancy::serde_float::option")
    )]
    pub uniform_heldout_loglik: Option<f64>,
    /// Held-out detections of the later part (0 when not used).
    #[cfg_attr(feature = "serde", serde(default))]
    pub uniform_heldout: usize,
}

/// What the searches did.
///
/// With the `serde` feature, a non-finite score is written as `"inf"`, `"-inf"` or `"NaN"`
/// in human-readable formats.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Selection {
    /// The calibration of the floor and the background's weight (`None` without it).
    #[cfg_attr(feature = "serde", serde(default))]
    pub calibration: Option<CalibrationReport>,
    /// Every period checked, given ones first, then the search's, in order.
    pub period_steps: Vec<PeriodStep>,
    /// `(k, held-out mean log-likelihood)` of each candidate tried.
    #[cfg_attr(feature = "serde", serde(with = "crate::serde_support::lenient_pairs"))]
    pub cluster_scores: Vec<(usize, f64)>,
}

impl Selection {
    /// Whether no period passed the validation (the model then has only the given periods
    /// kept unverified, or none: the static model).
    pub fn no_period_validated(&self) -> bool {
        !self.period_steps.iter().any(|s| s.accepted)
    }
}
