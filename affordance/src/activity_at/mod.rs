//! Activity at any time of day (beyond the seeds): a time-independent activity map (seed
//! 002's TA map, seed 000's per-layout affordance, a static presence model) modulated by the
//! daily rhythm that seed 001's hypertime model and the rate of detections learn.
//!
//! # The model
//! Let `A(s)` be the time-independent activity at a place `s` (any [`DensityMap`], in its own
//! units), `p(s | t)` the hypertime model's density of people over the plane at time `t`
//! ([`HypertimeModel::at`]) and `n(t)` the rate of detections per second of observation at
//! the time of day of `t` ([`DailyRate`]). The expected presence at `s` and `t` is the
//! intensity
//!
//! `λ(s, t) = n(t) · p(s | t)`  (detections per second per m²),
//!
//! and what a time-independent map estimates at `s` is its average over the times the robot
//! observed, weighted by how long it observed them (`X(t)`, seconds of observation near `t`):
//!
//! `λ̄(s) = ∫ X(t) λ(s, t) dt / ∫ X(t) dt = ∫ C(t) p(s | t) dt / ∫ X(t) dt`,
//!
//! since `X(t) n(t) = C(t)`, the detections near `t`. The rhythm at `s` is the ratio
//! `r(s, t) = λ(s, t) / λ̄(s)`: how much busier `s` is at `t` than on average. The activity
//! at `t` is
//!
//! `A(s, t) = A(s) · (1 − c(t) + c(t) · r(s, t))`,
//!
//! with `c(t) ∈ [0, 1]` the confidence in the rhythm at `t`:
//! `c(t) = min(1, X(t) / X_min)` when the hypertime model kept a period or the rate's rhythm
//! passed its check across days (below), `0` otherwise.
//!
//! Why this reading: the time-independent map is the better *where* (a TA map counts
//! distinct trajectories per cell; a layout's affordance divides hits by laser visits, so it
//! is corrected for where the robot looked; both pool many days), and hypertime is the only
//! model of *when*. Its conditional `p(s | t)` alone says where people are given that someone
//! is there, not how many come: a lunch peak that brings three times the people at the
//! same tables leaves `p(s | t)` unchanged, so the rate `n(t)` multiplies it. Dividing by
//! `λ̄(s)`, the same model averaged as the map averages, makes `r` a pure modulation that
//! is 1 on average at every place: with `c ≡ 1`, `Σₖ X(tₖ) A(s, tₖ) / Σₖ X(tₖ) = A(s)` exactly
//! on the quadrature nodes `tₖ` (every [`ActivityAtParams::node_step`] over the day), so the
//! time-dependent map is the time-independent one, redistributed over the day. The ratio
//! cancels the hypertime model's own spatial errors to first order (a component a little off
//! in space is off in `λ` and `λ̄` alike), which is why its *where* is not used directly.
//!
//! It degrades gracefully: at a time of day the robot never observed (`X(t) = 0`, the kernel
//! cut at `4σ`) or without a period in the hypertime model (no period validated on held-out
//! days, [`CycleValidation`](crate::hypertime::CycleValidation)) and no rate rhythm that
//! recurs across days ([`DailyRate::check_across_days`]), `c = 0` and
//! `A(s, t) = A(s)` exactly; between the two, the rhythm fades in with the observation behind
//! it. Where `λ̄(s)` is 0 (no detection near `s` at any time) `r = 1`. The hypertime model's
//! periods must divide the rhythm's period (a day), so that the day's nodes average over
//! whole cycles.
//!
//! The rhythm here is validated as the hypertime model's periods are: a period kept is one
//! validated on held-out days, or seed 001's a-priori daily period kept when the data span
//! a single day (`GivenPeriods::KeepUnverifiable`, the default; `GivenPeriods::Validate`
//! drops it). When the model kept no period, the rate's rhythm alone (`r = n(t)/n̄`) is used
//! only if it predicts the hourly counts of held-out whole days better than a flat rate, by
//! [`ActivityAtParams::rate_margin`] ([`DailyRate::check_across_days`]); otherwise the
//! activity is time-independent.

mod eval;
mod rate;

pub use eval::{HourScore, HourlyEvaluation, HourlyParams, evaluate_hours};
pub use rate::{DailyRate, RateCheck, observation_windows};

use haunts_occupancy::{Grid, GridGeometry};
use nalgebra::Point2;

use crate::hypertime::{DAY, HypertimeModel, HypertimeSnapshot, TimedPoint};
use crate::{AffordanceError, DensityMap, Result};

/// Parameters of [`ActivityAt`].
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub struct ActivityAtParams {
    /// The rhythm's period, seconds (default one day).
    pub period: f64,
    /// Standard deviation `σ` of the smoothing of the rate over the time of day, seconds
    /// (default 3600, hypertime's own time smoothing).
    pub smoothing: f64,
    /// Detections further apart than this end an observation window, seconds (default 900;
    /// see [`observation_windows`]).
    pub max_gap: f64,
    /// `X_min`: the seconds of observation near `t` (in the kernel's weighting) at which the
    /// rhythm is fully trusted (default 600: ten minutes within about `σ` of `t`).
    pub min_exposure: f64,
    /// Step of the quadrature nodes of `λ̄`, seconds (default 3600; the period is divided
    /// into a whole number of steps). `λ̄` costs one hypertime evaluation per node with
    /// detections near it, per place.
    pub node_step: f64,
    /// Whether the rate's rhythm `n(t)/n̄` is used when the hypertime model kept no period
    /// and the rhythm recurs across days (default `true`). Without a period `p(s | t)` is the
    /// same at every `t`, so `r(s, t) = n(t)/n̄` (up to the quadrature): how many come, not
    /// where. For data whose *where* does not recur from day to day while *how many* does
    /// (the simulated office: the daily period loses on left-out days, `BENCHMARKS.md`). The
    /// rhythm is used only when [`DailyRate::check_across_days`] accepts it (hourly counts of
    /// held-out whole days predicted better than by the flat rate; one day of data is never
    /// accepted); [`ActivityAt::rate_check`] says what it found. `false`: the activity is
    /// time-independent whenever the model kept no period.
    pub rate_without_period: bool,
    /// The share by which the rate's rhythm must cut the count error of the flat rate on
    /// held-out days to be used (in `[0, 1)`, default 0.1; see
    /// [`DailyRate::check_across_days`]).
    #[cfg_attr(feature = "serde", serde(default = "default_rate_margin"))]
    pub rate_margin: f64,
}

#[cfg(feature = "serde")]
fn default_rate_margin() -> f64 {
    0.1
}

impl Default for ActivityAtParams {
    fn default() -> Self {
        Self {
            period: DAY,
            smoothing: 3600.0,
            max_gap: 900.0,
            min_exposure: 600.0,
            node_step: 3600.0,
            rate_without_period: true,
            rate_margin: 0.1,
        }
    }
}

impl ActivityAtParams {
    /// Sets the smoothing `σ`, seconds.
    pub fn with_smoothing(mut self, seconds: f64) -> Self {
        self.smoothing = seconds;
        self
    }
    /// Sets the gap that ends an observation window, seconds.
    pub fn with_max_gap(mut self, seconds: f64) -> Self {
        self.max_gap = seconds;
        self
    }
    /// Sets `X_min`, seconds.
    pub fn with_min_exposure(mut self, seconds: f64) -> Self {
        self.min_exposure = seconds;
        self
    }
    /// Sets the step of the quadrature nodes, seconds.
    pub fn with_node_step(mut self, seconds: f64) -> Self {
        self.node_step = seconds;
        self
    }

    /// Sets whether the rate's rhythm is used without a period in the model.
    pub fn with_rate_without_period(mut self, rate: bool) -> Self {
        self.rate_without_period = rate;
        self
    }
    /// Sets the margin of the rate's check across days.
    pub fn with_rate_margin(mut self, margin: f64) -> Self {
        self.rate_margin = margin;
        self
    }

    /// The rules, checked: `period` finite and ≥ 120 s; `smoothing` finite and `≥ 0`;
    /// `max_gap`, `min_exposure` finite and `> 0`; `node_step` finite, `> 0` and at most the
    /// period; `rate_margin` in `[0, 1)`.
    ///
    /// # Errors
    /// [`AffordanceError::InvalidParameter`] naming the first rule broken.
    pub fn check(self) -> Result<Self> {
        let bad = |name, value, rule| {
            Err(AffordanceError::InvalidParameter(
                haunts_core::InvalidParameter { name, value, rule },
            ))
        };
        if !(self.period.is_finite() && self.period >= 120.0) {
            return bad("period", self.period, "must be finite and >= 120 s");
        }
        if !(self.smoothing.is_finite() && self.smoothing >= 0.0) {
            return bad("smoothing", self.smoothing, "must be finite and >= 0");
        }
        if !(self.max_gap.is_finite() && self.max_gap > 0.0) {
            return bad("max_gap", self.max_gap, "must be finite and > 0");
        }
        if !(self.min_exposure.is_finite() && self.min_exposure > 0.0) {
            return bad("min_exposure", self.min_exposure, "must be finite and > 0");
        }
        if !(0.0..1.0).contains(&self.rate_margin) {
            return bad("rate_margin", self.rate_margin, "must be in [0, 1)");
        }
        if !(self.node_step.is_finite() && self.node_step > 0.0 && self.node_step <= self.period) {
            return bad(
                "node_step",
                self.node_step,
                "must be finite, > 0 and <= period",
            );
        }
        Ok(self)
    }
}

/// Activity at any time of day: a time-independent [`DensityMap`] `A(s)` modulated by the
/// daily rhythm of a [`HypertimeModel`] and of the rate of detections (see the
/// [module docs](self) for the model, `A(s, t) = A(s)·(1 − c(t) + c(t)·r(s, t))`).
/// [`ActivityAt::at`] is a [`DensityMap`] in `A`'s units; [`ActivityAt::on_grid`] precomputes
/// what does not depend on `t` for a grid.
///
/// ```
/// use haunts_affordance::activity_at::{ActivityAt, ActivityAtParams};
/// use haunts_affordance::UniformDensity;
/// use haunts_affordance::hypertime::{DAY, HypertimeModel, HypertimeParams, TimedPoint};
/// use haunts_affordance::DensityMap;
/// use nalgebra::Point2;
///
/// // Three days observed 8:00–14:00: a few people at the desk (0, 0) all day, a crowd at
/// // the table (6, 0) from 12:00 to 13:00.
/// let mut points = Vec::new();
/// for day in 0..3 {
///     let t0 = day as f64 * DAY;
///     for i in 0..360 {
///         let t = t0 + 8.0 * 3600.0 + i as f64 * 60.0;
///         let wobble = 0.1 * (i % 5) as f64;
///         points.push(TimedPoint::new(t, wobble, -wobble));
///         if (240..300).contains(&i) {
///             for k in 0..4 {
///                 points.push(TimedPoint::new(t + k as f64, 6.0 + wobble, 0.1 * k as f64));
///             }
///         }
///     }
/// }
/// let model = HypertimeModel::fit(&points, &HypertimeParams::default().with_clusters(4))?;
/// // The time-independent map here says "1 everywhere"; the rhythm redistributes it.
/// let base = UniformDensity(Some(1.0));
/// let activity = ActivityAt::new(base, model, &points, &ActivityAtParams::default())?;
/// let (table, h) = (Point2::new(6.2, 0.1), 3600.0);
/// let lunch = activity.at(12.5 * h).density_at(table).unwrap();
/// let morning = activity.at(9.0 * h).density_at(table).unwrap();
/// assert!(lunch > 2.0 && morning < 0.1); // the peak, smoothed by σ = 1 h
/// // At 3:00 the robot never observed: the time-independent map, exactly.
/// assert_eq!(activity.at(3.0 * h).density_at(table), Some(1.0));
/// # Ok::<(), haunts_affordance::AffordanceError>(())
/// ```
#[derive(Debug, Clone)]
pub struct ActivityAt<M> {
    base: M,
    model: HypertimeModel,
    rate: DailyRate,
    params: ActivityAtParams,
    /// `(C(tₖ), p(· | tₖ))` at the nodes with detections near them.
    nodes: Vec<(f64, HypertimeSnapshot)>,
    /// `Σₖ X(tₖ)` over all nodes.
    node_exposure: f64,
    /// The rate's check across days, when the model kept no period.
    rate_check: Option<RateCheck>,
}

impl<M: DensityMap> ActivityAt<M> {
    /// The activity of `base` modulated by the rhythm of `model` and of `points`, the
    /// detections the rate is counted on (normally those `model` was fitted on), observed in
    /// the windows [`observation_windows`] finds in them.
    ///
    /// # Errors
    /// [`AffordanceError::InvalidParameter`] for bad parameters, or (`name: "periods"`) for a
    /// model period that does not divide [`ActivityAtParams::period`] (within 10⁻⁶).
    ///
    /// # Complexity
    /// `O(n log n)` for the windows and the rate, and one hypertime snapshot per node.
    pub fn new(
        base: M,
        model: HypertimeModel,
        points: &[TimedPoint],
        params: &ActivityAtParams,
    ) -> Result<Self> {
        let params = params.check()?;
        let windows = observation_windows(points, params.max_gap);
        Self::with_windows(base, model, points, &windows, &params)
    }

    /// As [`ActivityAt::new`] with the observation windows given (UNIX seconds, `[start,
    /// end]`), e.g. a robot's patrol sessions.
    ///
    /// # Errors
    /// As [`ActivityAt::new`]; a window with a non-finite or reversed end.
    pub fn with_windows(
        base: M,
        model: HypertimeModel,
        points: &[TimedPoint],
        windows: &[(f64, f64)],
        params: &ActivityAtParams,
    ) -> Result<Self> {
        let params = params.check()?;
        for &p in model.periods() {
            let cycles = params.period / p;
            if (cycles - cycles.round()).abs() > 1e-6 * cycles.max(1.0) || cycles.round() < 1.0 {
                return Err(AffordanceError::InvalidParameter(
                    haunts_core::InvalidParameter {
                        name: "periods",
                        value: p,
                        rule: "a hypertime period must divide the rhythm's period",
                    },
                ));
            }
        }
        let rate = DailyRate::fit(points, windows, params.period, params.smoothing)?;
        let steps = (params.period / params.node_step).round().max(1.0) as usize;
        let step = params.period / steps as f64;
        let mut nodes = Vec::new();
        let mut node_exposure = 0.0;
        let rate_check = if model.periods().is_empty() && params.rate_without_period {
            Some(DailyRate::check_across_days(
                points,
                windows,
                params.period,
                params.smoothing,
                params.node_step,
                params.rate_margin,
            )?)
        } else {
            None
        };
        if !model.periods().is_empty() || rate_check.is_some_and(|c| c.accepted) {
            for k in 0..steps {
                let t = k as f64 * step;
                node_exposure += rate.exposure_near(t);
                let c = rate.detections_near(t);
                if c > 0.0 {
                    nodes.push((c, model.at(t)));
                }
            }
        }
        Ok(Self {
            base,
            model,
            rate,
            params,
            nodes,
            node_exposure,
            rate_check,
        })
    }

    /// The check of the rate's rhythm across held-out days ([`DailyRate::check_across_days`],
    /// intervals of [`ActivityAtParams::node_step`]), made when the model kept no period and
    /// [`ActivityAtParams::rate_without_period`] asks for the rhythm; `None` otherwise.
    pub fn rate_check(&self) -> Option<&RateCheck> {
        self.rate_check.as_ref()
    }

    /// The time-independent map `A`.
    pub fn base(&self) -> &M {
        &self.base
    }
    /// The hypertime model.
    pub fn model(&self) -> &HypertimeModel {
        &self.model
    }
    /// The rate of detections `n(t)`.
    pub fn rate(&self) -> &DailyRate {
        &self.rate
    }
    /// The parameters.
    pub fn params(&self) -> &ActivityAtParams {
        &self.params
    }

    /// Whether there is a rhythm at all: the model kept a period (or the rate's rhythm passed
    /// its [`rate_check`](Self::rate_check)) and some node has detections near it. Without
    /// one the activity is `A` at every time.
    pub fn has_rhythm(&self) -> bool {
        !self.nodes.is_empty() && self.node_exposure > 0.0
    }

    /// `c(t)`: the confidence in the rhythm at `t`, in `[0, 1]`.
    pub fn confidence(&self, t: f64) -> f64 {
        if !self.has_rhythm() {
            return 0.0;
        }
        (self.rate.exposure_near(t) / self.params.min_exposure).clamp(0.0, 1.0)
    }

    /// `λ̄(s)`: the presence at `p` averaged over the observed times, detections per second
    /// per m², or `None` without a rhythm or at a non-finite point.
    pub(crate) fn mean_presence(&self, p: Point2<f64>) -> Option<f64> {
        if !self.has_rhythm() {
            return None;
        }
        let mut sum = 0.0;
        for (c, snapshot) in &self.nodes {
            sum += c * snapshot.density_at(p)?;
        }
        Some(sum / self.node_exposure)
    }

    /// The activity at time `t` (UNIX seconds): a [`DensityMap`] in `A`'s units.
    pub fn at(&self, t: f64) -> ActivityAtTime<'_, M> {
        let confidence = self.confidence(t);
        let (rate, snapshot) = if confidence > 0.0 {
            (self.rate.rate(t).unwrap_or(0.0), Some(self.model.at(t)))
        } else {
            (0.0, None)
        };
        ActivityAtTime {
            activity: self,
            confidence,
            rate,
            snapshot,
        }
    }

    /// What does not depend on `t`, on the cells of `geometry`: `A` and `λ̄` rasterised once
    /// (in parallel with the `rayon` feature), so that [`ActivityRaster::at`] costs one
    /// hypertime snapshot per cell.
    pub fn on_grid(&self, geometry: &GridGeometry) -> ActivityRaster<'_, M> {
        let values = par_map(geometry.len(), |i| {
            let p = geometry
                .cell_at(i)
                .map(|c| geometry.cell_center(c))
                .unwrap_or_else(Point2::origin);
            (
                self.base.density_at(p).unwrap_or(f64::NAN),
                self.mean_presence(p).unwrap_or(f64::NAN),
            )
        });
        let (base, mean): (Vec<f64>, Vec<f64>) = values.into_iter().unzip();
        ActivityRaster {
            activity: self,
            geometry: *geometry,
            base,
            mean,
        }
    }
}

/// `(0..n).map(f)` in order, in parallel with the `rayon` feature.
fn par_map<U: Send>(n: usize, f: impl Fn(usize) -> U + Sync + Send) -> Vec<U> {
    #[cfg(feature = "rayon")]
    {
        use rayon::prelude::*;
        (0..n).into_par_iter().map(f).collect()
    }
    #[cfg(not(feature = "rayon"))]
    (0..n).map(f).collect()
}

/// `A(s)·(1 − c + c·r)` from its parts; `A` where `r` is undefined.
fn modulate(base: f64, confidence: f64, lambda: Option<f64>, mean: f64) -> f64 {
    match lambda {
        Some(l) if confidence > 0.0 && mean > 0.0 && mean.is_finite() => {
            base * (1.0 - confidence + confidence * l / mean)
        }
        _ => base,
    }
}

/// The activity at one time ([`ActivityAt::at`]).
#[derive(Debug, Clone)]
pub struct ActivityAtTime<'a, M> {
    activity: &'a ActivityAt<M>,
    confidence: f64,
    rate: f64,
    snapshot: Option<HypertimeSnapshot>,
}

impl<M: DensityMap> ActivityAtTime<'_, M> {
    /// `r(s, t)` at `p` with the confidence applied, `1 − c + c·r` (1 without a rhythm), or
    /// `None` at a non-finite point.
    fn factor_at(&self, p: Point2<f64>) -> Option<f64> {
        if !(p.x.is_finite() && p.y.is_finite()) {
            return None;
        }
        let Some(snapshot) = &self.snapshot else {
            return Some(1.0);
        };
        let mean = self.activity.mean_presence(p).unwrap_or(0.0);
        let lambda = snapshot.density_at(p).map(|d| self.rate * d);
        Some(modulate(1.0, self.confidence, lambda, mean))
    }
}

impl<M: DensityMap> DensityMap for ActivityAtTime<'_, M> {
    /// `A(s, t)`, in `A`'s units; `None` where `A` knows nothing.
    fn density_at(&self, p: Point2<f64>) -> Option<f64> {
        let base = self.activity.base.density_at(p)?;
        Some(base * self.factor_at(p)?)
    }
}

/// `A` and `λ̄` on the cells of a grid ([`ActivityAt::on_grid`]).
#[derive(Debug, Clone)]
pub struct ActivityRaster<'a, M> {
    activity: &'a ActivityAt<M>,
    geometry: GridGeometry,
    base: Vec<f64>,
    mean: Vec<f64>,
}

impl<M: DensityMap> ActivityRaster<'_, M> {
    /// The grid.
    pub fn geometry(&self) -> &GridGeometry {
        &self.geometry
    }

    /// The time-independent map `A` on the grid (NaN where unknown).
    pub fn base(&self) -> Grid<f64> {
        Grid::from_fn(self.geometry, |c| {
            self.geometry.index(c).map_or(f64::NAN, |i| self.base[i])
        })
    }

    /// `A(s, t)` at every cell centre, NaN where `A` is unknown: equal to
    /// `activity.at(t).rasterise(geometry)` (in parallel with the `rayon` feature).
    pub fn at(&self, t: f64) -> Grid<f64> {
        let at = self.activity.at(t);
        let g = &self.geometry;
        let values = par_map(g.len(), |i| {
            let base = self.base[i];
            let Some(snapshot) = &at.snapshot else {
                return base;
            };
            if base.is_nan() {
                return base;
            }
            let p = g
                .cell_at(i)
                .map(|c| g.cell_center(c))
                .unwrap_or_else(Point2::origin);
            let lambda = snapshot.density_at(p).map(|d| at.rate * d);
            let mean = if self.mean[i].is_finite() {
                self.mean[i]
            } else {
                0.0
            };
            modulate(base, at.confidence, lambda, mean)
        });
        Grid::from_fn(*g, |c| g.index(c).map_or(f64::NAN, |i| values[i]))
    }
}
