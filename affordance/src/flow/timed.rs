//! Flow at a time of day (issue 53): STeF-map's reading (Molina et al., 2018), each cell's
//! direction histogram with every bin's rate over time a FreMEn model (Krajník et al.): the
//! rate of people through the cell in bin `b` at time `t` is
//!
//! `r_b(t) = μ_b + Σ_{k ∈ K_b} (2/T) (C_bk cos ω_k t + S_bk sin ω_k t)`,  clamped at 0,
//!
//! over the `N_b` observations of the cell's pool in bin `b` at times `t_j` spanning `T`
//! seconds: `μ_b = N_b / T`, `C_bk = Σ_j cos ω_k t_j`, `S_bk = Σ_j sin ω_k t_j` (the point
//! process's Fourier coefficients), `ω_k = 2πk / day` for `k = 1 … harmonics`, and `K_b` the
//! [`TimedFlowParams::order`] frequencies of largest amplitude `√(C² + S²)` (FreMEn's
//! choice of the strongest spectral components; periods that divide a day, the rhythm
//! seed 001 and the hypertime model use). The direction density at `t` is the static
//! histogram's with the bins' shares `s_b(t) = r_b(t) / Σ r(t)` in place of `N_b / N`, or
//! (with [`FlowForm::Mixture`]) the static mixture's heading density `m(θ)` in bin `b` scaled
//! by `s_b(t) / (N_b / N)` and divided by `Σ_b s_b(t) / (N_b / N) · M_b` (`M_b` the mixture's
//! mass in bin `b`, by the midpoint rule), so that it integrates to one; either is shrunk
//! towards uniform by the static map's pseudo-count. At order 0 it *is* the static map. The
//! pooling (which cells a cell borrows from) is the static map's.
//!
//! Periods longer than the data cannot be learnt: a caller compares this map with the static
//! one only where the observations span more than a day (the `flow_map` example), and picks
//! the order on the training data's own held-out part ([`choose_order`]).

use std::f64::consts::TAU;

use haunts_occupancy::GridGeometry;
use nalgebra::Point2;

use super::{CellSource, FlowForm, FlowMap, FlowObservation, FlowParams, bin_of, hold_out_last};
use crate::Result;

/// A day, seconds: the longest period modelled.
const DAY: f64 = 86_400.0;

/// Parameters of [`TimedFlowMap::fit`].
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub struct TimedFlowParams {
    /// Candidate frequencies: periods of a day divided by 1 … `harmonics` (6: down to 4 h).
    pub harmonics: usize,
    /// Frequencies kept per cell and bin, the strongest (2; 0 is the static map).
    pub order: usize,
    /// The static form the bins' rhythm modulates: the histogram (its shares replaced by
    /// the shares at `t`), or the mixture (its heading density in each bin scaled by the
    /// bin's share at `t` over its static share, renormalised over the circle).
    pub form: FlowForm,
}

impl Default for TimedFlowParams {
    fn default() -> Self {
        Self {
            harmonics: 6,
            order: 2,
            form: FlowForm::Histogram,
        }
    }
}

impl TimedFlowParams {
    /// Sets the number of candidate harmonics of a day.
    pub fn with_harmonics(mut self, harmonics: usize) -> Self {
        self.harmonics = harmonics;
        self
    }
    /// Sets the frequencies kept per cell and bin.
    pub fn with_order(mut self, order: usize) -> Self {
        self.order = order;
        self
    }
    /// Sets the static form the rhythm modulates.
    pub fn with_form(mut self, form: FlowForm) -> Self {
        self.form = form;
        self
    }
    /// The rules, checked: 1 to 48 harmonics, an order of at most `harmonics`.
    ///
    /// # Errors
    /// [`crate::AffordanceError::InvalidParameter`] naming the rule broken.
    pub fn check(self) -> Result<Self> {
        let rules = [
            (
                "harmonics",
                self.harmonics,
                (1..=48).contains(&self.harmonics),
                "must be 1 to 48",
            ),
            (
                "order",
                self.order,
                self.order <= self.harmonics,
                "must be at most harmonics",
            ),
        ];
        for (name, value, ok, rule) in rules {
            if !ok {
                return Err(haunts_core::InvalidParameter {
                    name,
                    value: value as f64,
                    rule,
                }
                .into());
            }
        }
        Ok(self)
    }
}

/// One kept frequency of a cell's bin: `ω`, and the sums `C`, `S` over its observations.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Component {
    omega: f64,
    c: f64,
    s: f64,
}

/// A flow map whose direction histogram changes with the time of day (see the
/// [module](self)).
#[derive(Debug, Clone, PartialEq)]
pub struct TimedFlowMap {
    base: FlowMap,
    params: TimedFlowParams,
    /// The observations' span, seconds.
    span: f64,
    /// Per cell and bin, the pooled count.
    counts: Vec<f64>,
    /// Per cell and bin, the kept components.
    components: Vec<Vec<Component>>,
    /// Per cell and bin, the mass of the static mixture's heading density in the bin (with
    /// [`FlowForm::Mixture`]; empty otherwise).
    bin_mass: Vec<f64>,
}

impl TimedFlowMap {
    /// Fits the static map (`flow`, its mixture fitted only for [`FlowForm::Mixture`]) and
    /// each cell's bins' rhythms.
    ///
    /// # Errors
    /// As [`FlowMap::fit`] and [`TimedFlowParams::check`]; the work budget's error when the
    /// pooled sums (observations × the pooled square × harmonics) would be over it.
    pub fn fit(
        observations: &[FlowObservation],
        geometry: GridGeometry,
        flow: &FlowParams,
        params: &TimedFlowParams,
    ) -> Result<Self> {
        let params = params.check()?;
        let mixture = params.form == FlowForm::Mixture;
        let base = FlowMap::fit(observations, geometry, &flow.with_mixture(mixture))?;
        let b = base.params.bins;
        let rings = base.params.rings;
        haunts_occupancy::budget::check_work(
            "timed flow map",
            &[
                ("observations", observations.len() as f64),
                ("cells pooled", ((2 * rings + 1) as f64).powi(2)),
                ("harmonics", params.harmonics as f64),
            ],
        )?;
        let (w, h) = (geometry.width(), geometry.height());
        // The observations inside, by cell.
        let mut by_cell: Vec<Vec<(usize, f64)>> = vec![Vec::new(); geometry.len()];
        let (mut first, mut last) = (f64::INFINITY, f64::NEG_INFINITY);
        for o in observations.iter().filter(|o| o.is_finite()) {
            if let Some(i) = base.index_at(o.position) {
                by_cell[i].push((bin_of(o.heading, b), o.time));
                first = first.min(o.time);
                last = last.max(o.time);
            }
        }
        let span = if last > first { last - first } else { 0.0 };
        let omegas: Vec<f64> = (1..=params.harmonics)
            .map(|k| TAU * k as f64 / DAY)
            .collect();
        let mut counts = vec![0.0; geometry.len() * b];
        let mut components = vec![Vec::new(); geometry.len() * b];
        let mut sums = vec![(0.0f64, 0.0f64); b * omegas.len()];
        for i in 0..geometry.len() {
            let r = match base.sources[i] {
                CellSource::Own => 0,
                CellSource::Rings(r) => r,
                CellSource::Uniform => continue,
            };
            let (x, y) = (i % w, i / w);
            sums.iter_mut().for_each(|s| *s = (0.0, 0.0));
            for yy in y.saturating_sub(r)..(y + r + 1).min(h) {
                for xx in x.saturating_sub(r)..(x + r + 1).min(w) {
                    for &(bin, t) in &by_cell[yy * w + xx] {
                        counts[i * b + bin] += 1.0;
                        for (k, &omega) in omegas.iter().enumerate() {
                            let (s, c) = (omega * t).sin_cos();
                            let e = &mut sums[bin * omegas.len() + k];
                            e.0 += c;
                            e.1 += s;
                        }
                    }
                }
            }
            for bin in 0..b {
                let mut all: Vec<Component> = omegas
                    .iter()
                    .enumerate()
                    .map(|(k, &omega)| {
                        let (c, s) = sums[bin * omegas.len() + k];
                        Component { omega, c, s }
                    })
                    .collect();
                // The strongest first (ties: the lower frequency).
                all.sort_by(|p, q| {
                    q.c.hypot(q.s)
                        .total_cmp(&p.c.hypot(p.s))
                        .then(p.omega.total_cmp(&q.omega))
                });
                all.truncate(params.order);
                components[i * b + bin] = all;
            }
        }
        // The mixture's mass per bin, by the midpoint rule (16 points a bin).
        let mut bin_mass = Vec::new();
        if mixture {
            let width = TAU / b as f64;
            bin_mass = vec![0.0; geometry.len() * b];
            for (i, mix) in base.mixtures.iter().enumerate() {
                for bin in 0..b {
                    bin_mass[i * b + bin] = (0..16)
                        .map(|k| {
                            let theta = (bin as f64 - 0.5 + (k as f64 + 0.5) / 16.0) * width;
                            mix.iter()
                                .map(|c| c.weight * c.heading_density(theta))
                                .sum::<f64>()
                        })
                        .sum::<f64>()
                        * width
                        / 16.0;
                }
            }
        }
        Ok(Self {
            base,
            params,
            span,
            counts,
            components,
            bin_mass,
        })
    }

    /// The static map it is built on (histogram only; its pooling is this map's).
    pub fn base(&self) -> &FlowMap {
        &self.base
    }
    /// The parameters (checked).
    pub fn params(&self) -> &TimedFlowParams {
        &self.params
    }
    /// The span of the observations used, seconds.
    pub fn span(&self) -> f64 {
        self.span
    }

    /// The density of `heading` (per radian) at `p` and time `t` (seconds): the static map's
    /// (of [`TimedFlowParams::form`]) with the bins' shares at `t` (see the [module](self));
    /// at order 0 the static map's density exactly; `1/2π` where the static map is uniform,
    /// and for a non-finite input.
    pub fn density(&self, p: Point2<f64>, heading: f64, t: f64) -> f64 {
        let uniform = 1.0 / TAU;
        let form = self.params.form;
        if self.params.order == 0 {
            return self.base.density(form, p, heading);
        }
        let Some(i) = self.base.index_at(p) else {
            return uniform;
        };
        if !(heading.is_finite() && t.is_finite()) || self.base.sources[i] == CellSource::Uniform {
            return uniform;
        }
        let b = self.base.params.bins;
        let n: f64 = self.counts[i * b..(i + 1) * b].iter().sum();
        if n <= 0.0 {
            return uniform;
        }
        let rate = |bin: usize| {
            let j = i * b + bin;
            if self.span <= 0.0 {
                return self.counts[j];
            }
            let wave: f64 = self.components[j]
                .iter()
                .map(|c| {
                    let (s, co) = (c.omega * t).sin_cos();
                    c.c * co + c.s * s
                })
                .sum();
            (self.counts[j] + 2.0 * wave).max(0.0) / self.span
        };
        let total: f64 = (0..b).map(rate).sum();
        // Each bin's share at t (the static share where nothing is left at t).
        let share = |bin: usize| {
            if total > 0.0 {
                rate(bin) / total
            } else {
                self.counts[i * b + bin] / n
            }
        };
        let a = b as f64 * self.base.params.prior;
        let mixture = &self.base.mixtures[i];
        let fitted = if form == FlowForm::Mixture && !mixture.is_empty() {
            // The mixture, each bin scaled by its share at t over its static share (1 where
            // the bin saw nobody), renormalised by the scaled masses.
            let scale = |bin: usize| {
                let c = self.counts[i * b + bin];
                if c > 0.0 { share(bin) / (c / n) } else { 1.0 }
            };
            let z: f64 = (0..b)
                .map(|bin| scale(bin) * self.bin_mass[i * b + bin])
                .sum();
            let mix: f64 = mixture
                .iter()
                .map(|c| c.weight * c.heading_density(heading))
                .sum();
            if z > 0.0 {
                mix * scale(bin_of(heading, b)) / z
            } else {
                mix
            }
        } else {
            share(bin_of(heading, b)) * b as f64 / TAU
        };
        (n * fitted + a * uniform) / (n + a)
    }

    /// The mean log-likelihood per observation of `test`'s headings at their times, nats,
    /// over the finite observations, with their number; `None` when none is finite.
    pub fn mean_log_likelihood(&self, test: &[FlowObservation]) -> Option<(f64, usize)> {
        let (sum, n) = test
            .iter()
            .filter(|o| o.is_finite())
            .fold((0.0, 0usize), |(s, n), o| {
                (s + self.density(o.position, o.heading, o.time).ln(), n + 1)
            });
        (n > 0).then(|| (sum / n as f64, n))
    }
}

/// The order of `orders` whose map, fitted on the first part of `observations` (in time),
/// scores their last `hold_out` share best (order 0 is the static histogram), with every
/// order's mean log-likelihood; ties go to the smaller order. `geometry` is the grid of both.
///
/// # Errors
/// As [`TimedFlowMap::fit`]; [`crate::AffordanceError::InvalidParameter`] when either part
/// is empty or `orders` is.
pub fn choose_order(
    observations: &[FlowObservation],
    geometry: GridGeometry,
    flow: &FlowParams,
    params: &TimedFlowParams,
    orders: &[usize],
    hold_out: f64,
) -> Result<(usize, Vec<(usize, f64)>)> {
    let (train, test) = hold_out_last(observations, hold_out);
    let empty = |name, n: usize| haunts_core::InvalidParameter {
        name,
        value: n as f64,
        rule: "must not be empty",
    };
    if train.is_empty() || test.is_empty() {
        return Err(empty("observations (a part of)", train.len().min(test.len())).into());
    }
    if orders.is_empty() {
        return Err(empty("orders", 0).into());
    }
    let mut scores = Vec::with_capacity(orders.len());
    for &order in orders {
        let map = TimedFlowMap::fit(&train, geometry, flow, &params.with_order(order))?;
        let (score, _) = map
            .mean_log_likelihood(&test)
            .ok_or_else(|| empty("held-out observations", 0))?;
        scores.push((order, score));
    }
    let best = scores
        .iter()
        .fold(None, |best: Option<(usize, f64)>, &(o, s)| match best {
            Some((_, b)) if b >= s => best,
            _ => Some((o, s)),
        })
        .map_or(0, |(o, _)| o);
    Ok((best, scores))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn order_zero_is_the_static_histogram() {
        let seen: Vec<FlowObservation> = (0..500)
            .map(|i| {
                let t = i as f64 * 700.0;
                let heading = if (t / 3600.0) as u64 % 24 < 12 {
                    0.0
                } else {
                    3.1
                };
                FlowObservation::new(t, Point2::new((i % 7) as f64 + 0.5, 1.5), heading, 1.0)
            })
            .collect();
        let g = GridGeometry::new(1.0, Point2::origin(), 8, 3).unwrap();
        let flow = FlowParams::default();
        let zero =
            TimedFlowMap::fit(&seen, g, &flow, &TimedFlowParams::default().with_order(0)).unwrap();
        for o in &seen[..50] {
            for h in [0.0, 1.0, 3.1] {
                let a = zero.density(o.position, h, o.time);
                let b = zero.base().density(FlowForm::Histogram, o.position, h);
                assert!((a - b).abs() <= 1e-12 * b, "{a} vs {b}");
            }
        }
    }

    /// The modulation itself (order > 0, no short cut): observations whose every bin is seen
    /// at evenly spaced times over whole days have no rhythm (every `C`, `S` sums to zero),
    /// so the map at any time is the static one, for both forms.
    #[test]
    fn without_a_rhythm_the_timed_map_is_the_static_one() {
        let (n, days) = (8 * 600, 5.0);
        let step = days * DAY / n as f64;
        let seen: Vec<FlowObservation> = (0..n)
            .map(|j| {
                // By j % 8, each class of times stepping by 8 Δ over the whole five days; the
                // classes fall in bins 0, 0, 0, 2, 2, 4, 5, 6, so the bins' counts differ.
                let bin = [0, 0, 0, 2, 2, 4, 5, 6][j % 8];
                let heading = bin as f64 * TAU / 8.0 + 0.1 * ((j / 8) % 3) as f64 - 0.1;
                let p = Point2::new(((j / 8) % 4) as f64 + 0.5, 0.5);
                FlowObservation::new(j as f64 * step, p, heading, 1.0)
            })
            .collect();
        let g = GridGeometry::new(1.0, Point2::origin(), 4, 1).unwrap();
        let flow = FlowParams::default();
        for form in [FlowForm::Histogram, FlowForm::Mixture] {
            let params = TimedFlowParams::default().with_form(form).with_order(3);
            let timed = TimedFlowMap::fit(&seen, g, &flow, &params).unwrap();
            for t in [3.0 * 3600.0, DAY + 40_000.0, 3.7 * DAY] {
                for h in [0.0, 0.8, 2.0, -2.5] {
                    let p = Point2::new(1.5, 0.5);
                    let (a, b) = (timed.density(p, h, t), timed.base().density(form, p, h));
                    // The mixture's renormalisation is by the midpoint rule: 16 points a bin.
                    let tolerance = if form == FlowForm::Mixture {
                        2e-3
                    } else {
                        1e-9
                    };
                    assert!(
                        (a - b).abs() <= tolerance * b,
                        "{form:?} {t} {h}: {a} vs {b}"
                    );
                }
            }
        }
    }
}
