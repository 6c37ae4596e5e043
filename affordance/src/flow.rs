//! Which way people walk: a flow map per cell (the maps of dynamics beside seed 002's TA map).
//!
//! Seed 002's TA map holds *where* people are; a planner in a corridor also needs *which way*
//! they walk. [`FlowMap`] holds, for every cell of a grid, the distribution of the direction
//! of the people that passed through it, in two forms:
//!
//! * **the histogram** of STeF-map (Molina et al., 2018; its published form): `B` bins (8 by
//!   default, centred on east, north-east, north, …: bin `b` holds the headings within half a
//!   bin of `b · 2π/B`), the density in a bin `B/2π` times its share of the cell's
//!   observations;
//! * **a semi-wrapped Gaussian mixture** in the manner of CLiFF-map (Kucner et al., 2017): per
//!   cell, a mixture of Gaussians over (heading, speed), wrapped on the heading (the wrapped
//!   copies `θ + 2πk`, `|k| ≤ 2`, so each component's heading marginal is a wrapped normal),
//!   fitted by expectation–maximisation with 1 to [`FlowParams::max_components`] components,
//!   the number chosen by BIC. Its heading marginal scores directions.
//!
//! **Few observations.** A cell with fewer than [`FlowParams::min_observations`] pools the
//! observations of the cells around it, ring by ring up to [`FlowParams::rings`] cells away,
//! until the pool has enough; a cell whose pool never has enough (or has none) scores the
//! uniform direction `1/2π`. Both forms are shrunk towards uniform by a pseudo-count
//! [`FlowParams::prior`] per bin (`A = B·prior` in all): `p = (N·p̂ + A/2π) / (N + A)` over the
//! `N` pooled observations (the histogram's additively smoothed bins are exactly this form), so
//! a direction nobody walked costs a bounded number of nats, never `−∞`.
//!
//! **Which is the default** ([`FlowForm::Histogram`]): the histogram is a count, so its fit is
//! bounded, deterministic and exact (no iteration to converge, nothing to initialise), its
//! shrinkage is plain additive smoothing of the counts, and it is the form STeF-map publishes and
//! extends over time. The mixture resolves a lane's direction finer than a 45° bin, and also
//! models speed, at the price of an EM per cell. Which scores better is for the data to say,
//! on data the map is not scored on: the `flow_map` example fits both on the first part of the
//! training observations and takes the better on their last part (on ETH's two sequences it
//! takes the mixture, which then scores about 0.3 nat per held-out observation above the
//! histogram; `BENCHMARKS.md`).
//!
//! Observations come from trajectories ([`observations`]: finite differences of consecutive
//! samples, the dummy-target filter being the caller's, as `ta_map` applies it) or directly
//! as [`FlowObservation`]s (detections with a heading).
//!
//! ```
//! use haunts_affordance::flow::{FlowForm, FlowMap, FlowObservation, FlowParams};
//! use haunts_affordance::nalgebra::Point2;
//! use haunts_occupancy::GridGeometry;
//!
//! // Everybody walks east along y = 1, north along x = 5.
//! let mut seen = Vec::new();
//! for i in 0..200 {
//!     let s = 0.05 * i as f64;
//!     seen.push(FlowObservation::new(s, Point2::new(s, 1.0), 0.0, 1.2));
//!     seen.push(FlowObservation::new(s, Point2::new(5.0, s), std::f64::consts::FRAC_PI_2, 1.2));
//! }
//! let grid = GridGeometry::new(1.0, Point2::new(0.0, 0.0), 10, 10)?;
//! let map = FlowMap::fit(&seen, grid, &FlowParams::default())?;
//! let east = map.log_density(FlowForm::Histogram, Point2::new(2.5, 1.2), 0.0);
//! let west = map.log_density(FlowForm::Histogram, Point2::new(2.5, 1.2), std::f64::consts::PI);
//! assert!(east > west + 3.0);
//! assert_eq!(map.dominant(Point2::new(5.2, 7.5)), Some(std::f64::consts::FRAC_PI_2));
//! # Ok::<(), haunts_affordance::AffordanceError>(())
//! ```

use std::f64::consts::{PI, TAU};

pub mod timed;
pub use timed::{TimedFlowMap, TimedFlowParams, choose_order};

use haunts_occupancy::GridGeometry;
use haunts_tracking::Trajectory;
use nalgebra::Point2;

#[cfg(doc)]
use crate::AffordanceError;
use crate::Result;

/// One person passing a point: where, when, which way and how fast.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FlowObservation {
    /// Time, seconds.
    pub time: f64,
    /// Position, metres.
    pub position: Point2<f64>,
    /// Heading, radians (any real; read modulo 2π).
    pub heading: f64,
    /// Speed, metres per second.
    pub speed: f64,
}

impl FlowObservation {
    /// An observation at `time` and `position`, heading `heading` (radians) at `speed` (m/s).
    pub fn new(time: f64, position: Point2<f64>, heading: f64, speed: f64) -> Self {
        Self {
            time,
            position,
            heading,
            speed,
        }
    }

    fn is_finite(&self) -> bool {
        [
            self.time,
            self.position.x,
            self.position.y,
            self.heading,
            self.speed,
        ]
        .iter()
        .all(|v| v.is_finite())
    }
}

/// The observations of trajectories by finite differences: for each pair of consecutive
/// samples `(t₀, p₀)`, `(t₁, p₁)` of a trajectory, one observation at the midpoint in time
/// and space, heading `atan2(Δy, Δx)`, speed `|Δp| / Δt`. Pairs with `Δt ≤ 0`, a non-finite
/// number, or a speed below `min_speed` (a person standing has no direction; 0.1 m/s is a
/// sensible floor for annotated pedestrians) give none. Returns the observations and the
/// number of pairs that gave none.
pub fn observations(trajectories: &[Trajectory], min_speed: f64) -> (Vec<FlowObservation>, usize) {
    let mut out = Vec::new();
    let mut dropped = 0;
    for t in trajectories {
        for w in t.samples.windows(2) {
            let ((t0, p0), (t1, p1)) = (w[0], w[1]);
            let dt = t1 - t0;
            let d = p1 - p0;
            let speed = d.norm() / dt;
            let o = FlowObservation::new(
                0.5 * (t0 + t1),
                Point2::from((p0.coords + p1.coords) * 0.5),
                d.y.atan2(d.x),
                speed,
            );
            // `!(a >= b)` so that NaN speeds are dropped too.
            if !(dt > 0.0 && o.is_finite() && speed >= min_speed) {
                dropped += 1;
                continue;
            }
            out.push(o);
        }
    }
    (out, dropped)
}

/// `observations` split in time: those before the time below which `1 − share` of them lie,
/// and the rest (the last `share` in time, held out), each in its given order. Non-finite
/// times go to neither. `share` is clamped to `[0, 1]`.
pub fn hold_out_last(
    observations: &[FlowObservation],
    share: f64,
) -> (Vec<FlowObservation>, Vec<FlowObservation>) {
    let mut times: Vec<f64> = observations
        .iter()
        .map(|o| o.time)
        .filter(|t| t.is_finite())
        .collect();
    times.sort_by(f64::total_cmp);
    let share = if share.is_nan() {
        0.0
    } else {
        share.clamp(0.0, 1.0)
    };
    let keep = ((1.0 - share) * times.len() as f64).round() as usize;
    let cut = times.get(keep).copied().unwrap_or(f64::INFINITY);
    let finite = observations.iter().filter(|o| o.time.is_finite());
    (
        finite.clone().filter(|o| o.time < cut).copied().collect(),
        finite.filter(|o| o.time >= cut).copied().collect(),
    )
}

/// Which of a [`FlowMap`]'s two forms scores a direction.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum FlowForm {
    /// STeF-map's direction histogram (the default; see the [module](self) for why).
    #[default]
    Histogram,
    /// The CLiFF-style semi-wrapped Gaussian mixture's heading marginal.
    Mixture,
}

/// Parameters of [`FlowMap::fit`].
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub struct FlowParams {
    /// Direction bins of the histogram (8, STeF-map's).
    pub bins: usize,
    /// Observations a cell needs to stand on its own; fewer pool the rings around it (5).
    pub min_observations: usize,
    /// Rings of neighbours a cell may pool, cells (2); beyond, the direction is uniform.
    pub rings: usize,
    /// Pseudo-count per bin shrinking both forms towards uniform (0.5, Jeffreys' prior on
    /// the bins' shares).
    pub prior: f64,
    /// Most components of a cell's mixture (3: CLiFF-map's cells seldom hold more lanes).
    pub max_components: usize,
    /// Smallest standard deviation of a component's heading, radians (0.05, about 3°: below,
    /// one straight walker's samples make a spike).
    pub min_heading_sd: f64,
    /// Smallest standard deviation of a component's speed, m/s (0.05).
    pub min_speed_sd: f64,
    /// EM iterations per mixture at most (100); it stops earlier when the log-likelihood
    /// rises by less than 1e-6 per observation.
    pub max_iterations: usize,
    /// Fit the mixture too (true); off, only the histogram (the mixture's EM per cell is
    /// most of the fit's time).
    pub mixture: bool,
}

impl Default for FlowParams {
    /// See the fields.
    fn default() -> Self {
        Self {
            bins: 8,
            min_observations: 5,
            rings: 2,
            prior: 0.5,
            max_components: 3,
            min_heading_sd: 0.05,
            min_speed_sd: 0.05,
            max_iterations: 100,
            mixture: true,
        }
    }
}

impl FlowParams {
    /// Sets the number of direction bins.
    pub fn with_bins(mut self, bins: usize) -> Self {
        self.bins = bins;
        self
    }
    /// Sets the observations a cell needs and the rings it may pool.
    pub fn with_pooling(mut self, min_observations: usize, rings: usize) -> Self {
        (self.min_observations, self.rings) = (min_observations, rings);
        self
    }
    /// Sets the pseudo-count per bin.
    pub fn with_prior(mut self, prior: f64) -> Self {
        self.prior = prior;
        self
    }
    /// Fits the mixture too, or only the histogram.
    pub fn with_mixture(mut self, mixture: bool) -> Self {
        self.mixture = mixture;
        self
    }
    /// Sets the most components of a cell's mixture.
    pub fn with_max_components(mut self, components: usize) -> Self {
        self.max_components = components;
        self
    }

    /// The rules, checked: at least 2 bins and at most 360, `min_observations` ≥ 1,
    /// `max_components` 1 to 8, `prior` finite and > 0, the floors finite and > 0,
    /// `max_iterations` ≥ 1.
    ///
    /// # Errors
    /// [`AffordanceError::InvalidParameter`] naming the first rule broken.
    pub fn check(self) -> Result<Self> {
        let counts = [
            ("bins", self.bins, 2, 360, "must be 2 to 360"),
            (
                "min_observations",
                self.min_observations,
                1,
                usize::MAX,
                "must be at least 1",
            ),
            (
                "max_components",
                self.max_components,
                1,
                8,
                "must be 1 to 8",
            ),
            (
                "max_iterations",
                self.max_iterations,
                1,
                usize::MAX,
                "must be at least 1",
            ),
            ("rings", self.rings, 0, 1 << 16, "must be at most 65536"),
        ];
        for (name, value, lo, hi, rule) in counts {
            if !(lo..=hi).contains(&value) {
                return Err(haunts_core::InvalidParameter {
                    name,
                    value: value as f64,
                    rule,
                }
                .into());
            }
        }
        haunts_core::positive("prior", self.prior)?;
        haunts_core::positive("min_heading_sd", self.min_heading_sd)?;
        haunts_core::positive("min_speed_sd", self.min_speed_sd)?;
        Ok(self)
    }
}

/// Where a cell's distribution comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CellSource {
    /// Its own observations (at least `min_observations`).
    Own,
    /// The observations of the cells up to this many rings away.
    Rings(usize),
    /// Too few observations within reach: the uniform direction.
    Uniform,
}

/// One component of a cell's semi-wrapped mixture: weight, mean heading (in `[−π, π)`) and
/// speed, and the covariance of (heading, speed).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FlowComponent {
    /// Mixing weight.
    pub weight: f64,
    /// Mean heading, radians, in `[−π, π)`.
    pub heading: f64,
    /// Mean speed, m/s.
    pub speed: f64,
    /// Covariance `[σ²θ, σθv, σ²v]`.
    pub covariance: [f64; 3],
}

impl FlowComponent {
    /// The component's heading marginal at `theta`: a normal of variance `σ²θ` wrapped on the
    /// circle (copies `k = −2…2`).
    pub fn heading_density(&self, theta: f64) -> f64 {
        let var = self.covariance[0];
        let d0 = wrap(theta - self.heading);
        (-2..=2)
            .map(|k| {
                let d = d0 + TAU * f64::from(k);
                (-0.5 * d * d / var).exp()
            })
            .sum::<f64>()
            / (TAU * var).sqrt()
    }
}

/// Per cell of a grid, the distribution of the direction people walked (see the
/// [module](self)).
#[derive(Debug, Clone, PartialEq)]
pub struct FlowMap {
    geometry: GridGeometry,
    params: FlowParams,
    /// Per cell: where its distribution comes from.
    sources: Vec<CellSource>,
    /// Per cell: the observations behind it (its own or its pool's; 0 when uniform).
    pooled: Vec<u32>,
    /// Per cell, `bins` pooled counts (zeros when uniform).
    counts: Vec<f32>,
    /// Per cell, its pool's observations per cell of the pool (its own count where it stands
    /// on its own; 0 when uniform): the traffic through it.
    traffic: Vec<f32>,
    /// Per cell, the semi-wrapped mixture (empty when uniform or not fitted).
    mixtures: Vec<Vec<FlowComponent>>,
    /// Observations inside the grid, and outside (not used).
    used: usize,
    outside: usize,
}

/// An angle in `[−π, π)`.
fn wrap(a: f64) -> f64 {
    (a + PI).rem_euclid(TAU) - PI
}

/// The bin of `heading` among `bins` bins centred on multiples of `2π / bins`.
pub fn bin_of(heading: f64, bins: usize) -> usize {
    let w = TAU / bins as f64;
    ((heading / w).round().rem_euclid(bins as f64) as usize).min(bins - 1)
}

impl FlowMap {
    /// Fits both forms over `geometry` from `observations`. Non-finite observations and
    /// those outside the grid are not used (counted: [`FlowMap::outside`]).
    ///
    /// # Errors
    /// [`AffordanceError::InvalidParameter`] for parameters that break
    /// [`FlowParams::check`]; the work budget's error
    /// ([`haunts_occupancy::OccupancyError::WorkTooLarge`] inside) when the counting
    /// ((cells + observations) × bins × (rings + 1)) or, with the mixture, the EM (the
    /// observations × the pooled square's cells × iterations × the components of every
    /// mixture tried × 5 wrapped copies, at most) would be over it.
    pub fn fit(
        observations: &[FlowObservation],
        geometry: GridGeometry,
        params: &FlowParams,
    ) -> Result<Self> {
        let params = params.check()?;
        let (w, h, b) = (geometry.width(), geometry.height(), params.bins);
        let pooled_square = ((2 * params.rings + 1) as f64).powi(2);
        haunts_occupancy::budget::check_work(
            "flow map counts",
            &[
                (
                    "cells + observations",
                    (geometry.len() + observations.len()) as f64,
                ),
                ("bins", b as f64),
                ("rings + 1", (params.rings + 1) as f64),
            ],
        )?;
        if params.mixture {
            haunts_occupancy::budget::check_work(
                "flow map mixtures",
                &[
                    ("observations", observations.len() as f64),
                    ("cells pooled", pooled_square.min(geometry.len() as f64)),
                    ("iterations", params.max_iterations as f64),
                    // Mixtures of 1 to K components are fitted: K(K + 1)/2 in all.
                    (
                        "components",
                        (params.max_components * (params.max_components + 1) / 2) as f64,
                    ),
                    ("wrapped copies", 5.0),
                ],
            )?;
        }
        // The observations grouped by cell (a counting sort), and the counts per bin.
        let mut cell_of = Vec::with_capacity(observations.len());
        let mut outside = 0;
        for o in observations {
            let i = if o.is_finite() {
                geometry
                    .world_to_cell(o.position)
                    .and_then(|c| geometry.index(c))
            } else {
                None
            };
            if i.is_none() {
                outside += 1;
            }
            cell_of.push(i);
        }
        let mut start = vec![0usize; geometry.len() + 1];
        for i in cell_of.iter().flatten() {
            start[i + 1] += 1;
        }
        for i in 0..geometry.len() {
            start[i + 1] += start[i];
        }
        let mut fill = start.clone();
        let mut order = vec![0usize; start[geometry.len()]];
        for (k, i) in cell_of.iter().enumerate() {
            if let Some(i) = *i {
                order[fill[i]] = k;
                fill[i] += 1;
            }
        }
        // Summed-area tables of the counts per bin: (w + 1) × (h + 1) per bin.
        let stride = w + 1;
        let mut sat = vec![0.0f64; b * stride * (h + 1)];
        for (k, i) in cell_of.iter().enumerate() {
            if let Some(i) = *i {
                let (x, y) = (i % w, i / w);
                let bin = bin_of(observations[k].heading, b);
                sat[bin * stride * (h + 1) + (y + 1) * stride + (x + 1)] += 1.0;
            }
        }
        for bin in 0..b {
            let t = &mut sat[bin * stride * (h + 1)..(bin + 1) * stride * (h + 1)];
            for y in 1..=h {
                for x in 1..=w {
                    t[y * stride + x] += t[(y - 1) * stride + x] + t[y * stride + x - 1]
                        - t[(y - 1) * stride + x - 1];
                }
            }
        }
        let window = |bin: usize, x0: usize, y0: usize, x1: usize, y1: usize| {
            // Cells x0..x1, y0..y1 (exclusive ends).
            let t = &sat[bin * stride * (h + 1)..];
            t[y1 * stride + x1] - t[y0 * stride + x1] - t[y1 * stride + x0] + t[y0 * stride + x0]
        };
        let cells = geometry.len();
        let mut sources = Vec::with_capacity(cells);
        let mut pooled = Vec::with_capacity(cells);
        let mut counts = vec![0.0f32; cells * b];
        let mut traffic = vec![0.0f32; cells];
        let mut mixtures = vec![Vec::new(); cells];
        let mut here = vec![0.0f64; b];
        let mut jobs = Vec::new();
        for i in 0..cells {
            let (x, y) = (i % w, i / w);
            let mut chosen = None;
            for r in 0..=params.rings {
                let (x0, y0) = (x.saturating_sub(r), y.saturating_sub(r));
                let (x1, y1) = ((x + r + 1).min(w), (y + r + 1).min(h));
                here.iter_mut()
                    .enumerate()
                    .for_each(|(bin, c)| *c = window(bin, x0, y0, x1, y1));
                let n = here.iter().sum::<f64>().round() as usize;
                if n >= params.min_observations {
                    chosen = Some((r, n, (x0, y0, x1, y1)));
                    break;
                }
            }
            let Some((r, n, (x0, y0, x1, y1))) = chosen else {
                sources.push(CellSource::Uniform);
                pooled.push(0);
                continue;
            };
            sources.push(if r == 0 {
                CellSource::Own
            } else {
                CellSource::Rings(r)
            });
            pooled.push(u32::try_from(n).unwrap_or(u32::MAX));
            traffic[i] = (n as f64 / ((x1 - x0) * (y1 - y0)) as f64) as f32;
            for (c, &v) in counts[i * b..(i + 1) * b].iter_mut().zip(&here) {
                *c = v as f32;
            }
            if params.mixture {
                jobs.push((i, (x0, y0, x1, y1)));
            }
        }
        // The mixtures, cell by cell in parallel (each cell's EM is its own: the same on
        // any number of threads).
        let fitted = crate::parallel::map_slice(&jobs, |&(i, (x0, y0, x1, y1))| {
            let pool: Vec<&FlowObservation> = (y0..y1)
                .flat_map(|yy| (x0..x1).map(move |xx| yy * w + xx))
                .flat_map(|j| order[start[j]..start[j + 1]].iter())
                .map(|&k| &observations[k])
                .collect();
            let here: Vec<f64> = counts[i * b..(i + 1) * b]
                .iter()
                .map(|&c| f64::from(c))
                .collect();
            fit_mixture(&pool, &here, &params)
        });
        for ((i, _), mixture) in jobs.iter().zip(fitted) {
            mixtures[*i] = mixture;
        }
        Ok(Self {
            geometry,
            params,
            sources,
            pooled,
            counts,
            traffic,
            mixtures,
            used: observations.len() - outside,
            outside,
        })
    }

    /// The grid.
    pub fn geometry(&self) -> &GridGeometry {
        &self.geometry
    }
    /// The parameters it was fitted with (checked).
    pub fn params(&self) -> &FlowParams {
        &self.params
    }
    /// Observations used (finite, inside the grid).
    pub fn used(&self) -> usize {
        self.used
    }
    /// Observations not used (not finite, or outside the grid).
    pub fn outside(&self) -> usize {
        self.outside
    }
    /// How many cells stand on their own observations, pool their rings, and are uniform.
    pub fn source_counts(&self) -> (usize, usize, usize) {
        self.sources.iter().fold((0, 0, 0), |(o, r, u), s| match s {
            CellSource::Own => (o + 1, r, u),
            CellSource::Rings(_) => (o, r + 1, u),
            CellSource::Uniform => (o, r, u + 1),
        })
    }
    /// The index of the cell holding `p`, if inside the grid.
    fn index_at(&self, p: Point2<f64>) -> Option<usize> {
        self.geometry
            .world_to_cell(p)
            .and_then(|c| self.geometry.index(c))
    }
    /// Where the distribution of the cell holding `p` comes from and how many observations
    /// are behind it; `None` outside the grid.
    pub fn source_at(&self, p: Point2<f64>) -> Option<(CellSource, usize)> {
        let i = self.index_at(p)?;
        Some((self.sources[i], self.pooled[i] as usize))
    }
    /// The pooled counts per direction bin of the cell holding `p` (zeros where uniform).
    pub fn counts_at(&self, p: Point2<f64>) -> Option<&[f32]> {
        let (i, b) = (self.index_at(p)?, self.params.bins);
        Some(&self.counts[i * b..(i + 1) * b])
    }
    /// The semi-wrapped mixture of the cell holding `p` (empty where uniform, or when
    /// [`FlowParams::mixture`] is off).
    pub fn mixture_at(&self, p: Point2<f64>) -> Option<&[FlowComponent]> {
        Some(&self.mixtures[self.index_at(p)?])
    }

    /// The density of heading `heading` (radians, per radian) at `p` by `form`: the cell's,
    /// shrunk towards uniform (see the [module](self)); `1/2π` outside the grid, at a cell
    /// without enough observations within reach, or for a non-finite input.
    pub fn density(&self, form: FlowForm, p: Point2<f64>, heading: f64) -> f64 {
        let uniform = 1.0 / TAU;
        if !heading.is_finite() {
            return uniform;
        }
        let Some(i) = self.index_at(p) else {
            return uniform;
        };
        let b = self.params.bins;
        if self.sources[i] == CellSource::Uniform
            || (form == FlowForm::Mixture && self.mixtures[i].is_empty())
        {
            return uniform;
        }
        let n = f64::from(self.pooled[i]);
        let a = b as f64 * self.params.prior;
        let fitted = match form {
            FlowForm::Histogram => {
                f64::from(self.counts[i * b + bin_of(heading, b)]) / n * b as f64 / TAU
            }
            FlowForm::Mixture => self.mixtures[i]
                .iter()
                .map(|c| c.weight * c.heading_density(heading))
                .sum(),
        };
        (n * fitted + a * uniform) / (n + a)
    }

    /// `ln` of [`FlowMap::density`].
    pub fn log_density(&self, form: FlowForm, p: Point2<f64>, heading: f64) -> f64 {
        self.density(form, p, heading).ln()
    }

    /// The centre of the fullest bin of the cell at `p` (the first of equals), in `[−π, π)`;
    /// `None` outside the grid or where the direction is uniform.
    pub fn dominant(&self, p: Point2<f64>) -> Option<f64> {
        let i = self.index_at(p)?;
        if self.sources[i] == CellSource::Uniform {
            return None;
        }
        let b = self.params.bins;
        let (best, _) = self.counts[i * b..(i + 1) * b].iter().enumerate().fold(
            None,
            |best: Option<(usize, f32)>, (i, &c)| match best {
                Some((_, m)) if m >= c => best,
                _ => Some((i, c)),
            },
        )?;
        Some(wrap(best as f64 * TAU / self.params.bins as f64))
    }

    /// The traffic through the cell at `p`: the observations of its pool per cell of the pool
    /// (its own count where it stands on its own, [`CellSource::Own`]); 0 outside the grid or
    /// where the direction is uniform.
    pub fn traffic_at(&self, p: Point2<f64>) -> f64 {
        self.index_at(p).map_or(0.0, |i| f64::from(self.traffic[i]))
    }

    /// The largest [`FlowMap::traffic_at`] of the grid (0 for a map without observations).
    pub fn max_traffic(&self) -> f64 {
        self.traffic.iter().copied().fold(0.0f32, f32::max).into()
    }

    /// How much of the traffic at `p` walks against `heading` (radians): the cell's
    /// [`traffic`](FlowMap::traffic_at) times `Σ_b s_b · max(0, −cos(θ_b − heading))` over its
    /// histogram's bins (share `s_b`, centre `θ_b`): people met head-on count fully, across
    /// (90°) not at all, those walking the same way not at all. In observations per cell, from
    /// 0 (nobody, or nobody against) to the cell's traffic; 0 outside the grid, where the
    /// direction is uniform, and for a non-finite heading. Divided by
    /// [`FlowMap::max_traffic`] it is a cost in `[0, 1]` for a planner
    /// (`haunts_planning::DirectionalCost`).
    pub fn against(&self, p: Point2<f64>, heading: f64) -> f64 {
        let Some(i) = self.index_at(p) else {
            return 0.0;
        };
        let (b, n) = (self.params.bins, f64::from(self.pooled[i]));
        if self.sources[i] == CellSource::Uniform || n <= 0.0 || !heading.is_finite() {
            return 0.0;
        }
        let opposed: f64 = self.counts[i * b..(i + 1) * b]
            .iter()
            .enumerate()
            .map(|(k, &c)| {
                let centre = k as f64 * TAU / b as f64;
                f64::from(c) * (-(centre - heading).cos()).max(0.0)
            })
            .sum();
        f64::from(self.traffic[i]) * opposed / n
    }

    /// The mean log-likelihood per observation of `test`'s headings by `form`, nats, over the
    /// finite observations (all, inside or outside the grid: outside scores uniform), with
    /// their number; `None` when none is finite.
    pub fn mean_log_likelihood(
        &self,
        form: FlowForm,
        test: &[FlowObservation],
    ) -> Option<(f64, usize)> {
        let (sum, n) = test
            .iter()
            .filter(|o| o.is_finite())
            .fold((0.0, 0usize), |(s, n), o| {
                (s + self.log_density(form, o.position, o.heading), n + 1)
            });
        (n > 0).then(|| (sum / n as f64, n))
    }
}

/// The uniform direction's log-density, `−ln 2π`, the reference every flow score compares
/// with.
pub const UNIFORM_DIRECTION_LOGLIK: f64 = -1.837_877_066_409_345_5;

/// Largest standard deviation of a component's heading, radians: wider is all but uniform,
/// and the copies `|k| ≤ 2` then still hold all of the wrapped normal's mass but 1e-14.
const MAX_HEADING_SD: f64 = 2.0;

/// A semi-wrapped Gaussian mixture over (heading, speed) of `pool`, with 1 to
/// `max_components` components chosen by BIC, each started on one of the fullest bins of
/// `counts`.
fn fit_mixture(
    pool: &[&FlowObservation],
    counts: &[f64],
    params: &FlowParams,
) -> Vec<FlowComponent> {
    // Starting headings: the fullest bins, fullest first.
    let mut bins: Vec<usize> = (0..counts.len()).filter(|&i| counts[i] > 0.0).collect();
    bins.sort_by(|&a, &b| counts[b].total_cmp(&counts[a]).then(a.cmp(&b)));
    let n = pool.len() as f64;
    let mut best: Option<(f64, Vec<FlowComponent>)> = None;
    for k in 1..=params.max_components.min(bins.len()).min(pool.len()) {
        let starts: Vec<f64> = bins[..k]
            .iter()
            .map(|&b| wrap(b as f64 * TAU / counts.len() as f64))
            .collect();
        let (mixture, loglik) = em(pool, &starts, params);
        let bic = -2.0 * loglik + (6 * k - 1) as f64 * n.ln();
        if best.as_ref().is_none_or(|(b, _)| bic < *b) {
            best = Some((bic, mixture));
        }
    }
    best.map(|(_, m)| m).unwrap_or_default()
}

/// EM for a semi-wrapped mixture started at headings `starts`; returns the mixture and its
/// log-likelihood (of the joint (heading, speed) density).
fn em(pool: &[&FlowObservation], starts: &[f64], params: &FlowParams) -> (Vec<FlowComponent>, f64) {
    let n = pool.len();
    let k = starts.len();
    let mean_speed = pool.iter().map(|o| o.speed).sum::<f64>() / n as f64;
    let speed_var = (pool
        .iter()
        .map(|o| (o.speed - mean_speed).powi(2))
        .sum::<f64>()
        / n as f64)
        .max(params.min_speed_sd.powi(2));
    // Every component starts half a 45° sector wide (STeF-map's bin), whatever the
    // histogram's bins: EM narrows or widens it.
    let bin = TAU / 8.0;
    let mut comps: Vec<FlowComponent> = starts
        .iter()
        .map(|&h| FlowComponent {
            weight: 1.0 / k as f64,
            heading: h,
            speed: mean_speed,
            covariance: [(0.5 * bin).powi(2), 0.0, speed_var],
        })
        .collect();
    const WRAPS: [f64; 5] = [-2.0, -1.0, 0.0, 1.0, 2.0];
    // Responsibilities per observation, component and wrap.
    let mut resp = vec![0.0; n * k * WRAPS.len()];
    let mut last = f64::NEG_INFINITY;
    let mut loglik = f64::NEG_INFINITY;
    for _ in 0..params.max_iterations {
        // E step.
        let mut total = 0.0;
        for (i, o) in pool.iter().enumerate() {
            let row = &mut resp[i * k * WRAPS.len()..(i + 1) * k * WRAPS.len()];
            let mut sum = 0.0;
            for (j, c) in comps.iter().enumerate() {
                let [a, bb, d] = c.covariance;
                let det = a * d - bb * bb;
                let norm = c.weight / (TAU * det.sqrt());
                let dv = o.speed - c.speed;
                let d0 = wrap(o.heading - c.heading);
                for (w, &kk) in WRAPS.iter().enumerate() {
                    let dt = d0 + TAU * kk;
                    let q = (d * dt * dt - 2.0 * bb * dt * dv + a * dv * dv) / det;
                    let v = norm * (-0.5 * q).exp();
                    row[j * WRAPS.len() + w] = v;
                    sum += v;
                }
            }
            if sum > 0.0 && sum.is_finite() {
                row.iter_mut().for_each(|r| *r /= sum);
                total += sum.ln();
            } else {
                // Far from every component (numerically): shared evenly.
                row.iter_mut()
                    .for_each(|r| *r = 1.0 / (k * WRAPS.len()) as f64);
                total += -745.0;
            }
        }
        loglik = total;
        if total - last < 1e-6 * n as f64 {
            break;
        }
        last = total;
        // M step, each wrapped copy at its unwrapped heading.
        for (j, c) in comps.iter_mut().enumerate() {
            let (mut r, mut st, mut sv) = (0.0, 0.0, 0.0);
            for (i, o) in pool.iter().enumerate() {
                let d0 = wrap(o.heading - c.heading);
                for (w, &kk) in WRAPS.iter().enumerate() {
                    let g = resp[(i * k + j) * WRAPS.len() + w];
                    r += g;
                    st += g * (d0 + TAU * kk);
                    sv += g * o.speed;
                }
            }
            if r <= 1e-12 {
                c.weight = 0.0;
                continue;
            }
            let (mt, mv) = (st / r, sv / r);
            let (mut a, mut bb, mut d) = (0.0, 0.0, 0.0);
            for (i, o) in pool.iter().enumerate() {
                let d0 = wrap(o.heading - c.heading);
                for (w, &kk) in WRAPS.iter().enumerate() {
                    let g = resp[(i * k + j) * WRAPS.len() + w];
                    let (dt, dv) = (d0 + TAU * kk - mt, o.speed - mv);
                    a += g * dt * dt;
                    bb += g * dt * dv;
                    d += g * dv * dv;
                }
            }
            let (a, d) = (
                (a / r).clamp(
                    params.min_heading_sd.powi(2),
                    MAX_HEADING_SD * MAX_HEADING_SD,
                ),
                (d / r).max(params.min_speed_sd.powi(2)),
            );
            // Keep the covariance positive definite: the correlation below 0.99 in size.
            let limit = 0.99 * (a * d).sqrt();
            let bb = (bb / r).clamp(-limit, limit);
            c.weight = r / n as f64;
            c.heading = wrap(c.heading + mt);
            c.speed = mv;
            c.covariance = [a, bb, d];
        }
        comps.retain(|c| c.weight > 0.0);
        if comps.len() != k {
            // A component emptied: restart the bookkeeping with the survivors.
            let starts: Vec<f64> = comps.iter().map(|c| c.heading).collect();
            return em(pool, &starts, params);
        }
    }
    (comps, loglik)
}
