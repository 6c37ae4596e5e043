//! The particle-filter person tracker of seed 000 (section IV-A-3): one particle set per
//! person over (x, y, v, θ), weighed by the Gaussian combination of recent detections.

use nalgebra::{Matrix2, Point2, Vector2};
use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};
use rand_distr::StandardNormal;

use crate::Result;
use crate::detect::{Detection, rule};
use crate::track::combination::{CombinationParams, GaussianCombination};
use crate::track::{
    Clock, ConfirmRule, Evidence, Step, Track, TrackLists, Tracker, check_confirm_mean, check_gap,
    check_history,
};

/// Parameters of the [`ParticleTracker`].
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub struct ParticleParams {
    /// Particles per person (seed default: 500).
    pub particles: usize,
    /// Seed of the tracker's random numbers: equal seeds and inputs give equal tracks.
    pub seed: u64,
    /// Standard deviation of the random change of a particle's speed, m/s per √s (the
    /// seed's Gaussian noise on v; per step it is `speed_noise · √dt`).
    pub speed_noise: f64,
    /// Standard deviation of the random change of a particle's heading, rad per √s (the
    /// seed's Gaussian noise on θ).
    pub heading_noise: f64,
    /// Fastest a particle may move, m/s (a brisk walk or a jog).
    pub max_speed: f64,
    /// Standard deviation of a new particle's speed, m/s (its heading is uniform).
    pub initial_speed_std: f64,
    /// The Gaussian combination the particles are weighed with.
    pub combination: CombinationParams,
    /// A detection starts a person when the combination at its position reaches this
    /// (about "this many fresh detections here": more than 1 asks for repeated evidence).
    pub birth_threshold: f64,
    /// A detection closer than this to a tracked person starts nobody, metres: about the
    /// space one person takes.
    pub min_track_distance: f64,
    /// Two people closer than this are one: the one with fewer hits ends, metres.
    pub merge_distance: f64,
    /// A person is supported in an update when the combination's expected value under its
    /// particles' weights reaches this (the seed's confidence of the weights; 0.5 = a
    /// single leg's detection).
    pub min_confidence: f64,
    /// A confirmed person unsupported for longer than this ends, seconds.
    pub max_missing_time: f64,
    /// A person not yet confirmed ends when unsupported for longer than this, seconds.
    pub tentative_missing_time: f64,
    /// Supported updates after which a new person may be confirmed and reported.
    pub confirm_hits: usize,
    /// Besides `confirm_hits`, a new person needs evidence that it is one:
    /// `confirm_strong_hits` supported updates with a detection at least this confident
    /// within `min_track_distance` (1 = a leg pair with the default leg detector: people
    /// show both legs now and then, a post or a table leg never does) ...
    pub confirm_confidence: f64,
    /// ... (how many such updates) ...
    pub confirm_strong_hits: usize,
    /// ... or to have walked this far from where it was born, metres ...
    pub min_travel: f64,
    /// ... or (when given) a running average of the confidences of its supporting
    /// detections of at least this (`leg_tracker`'s rule; with
    /// [`crate::detect::ForestDetector`], the forest's cross-validated operating point).
    pub confirm_mean_confidence: Option<f64>,
    /// A person is reported while supported within this many seconds (0: supported in the
    /// current update only).
    pub max_report_coast: f64,
    /// A step longer than this, seconds, resets the tracker (see [`Tracker`]).
    pub max_time_gap: f64,
    /// Longest history kept per track (`None`: everything).
    pub max_history: Option<usize>,
}

impl Default for ParticleParams {
    /// 500 particles per person (seed 000); walking motion noise (speed 0.5 m/s/√s, heading
    /// 1 rad/√s, at most 2.5 m/s); a 0.4 s combination; births where it reaches 0.5 (any
    /// detection, a single leg too), at least 0.6 m from everyone; merges under 0.3 m;
    /// support at a combination value of 0.5; confirmed, as the Kalman tracker's tracks,
    /// after 3 supported updates and either two with a leg pair or 1.2 m walked; death
    /// after 0.5 s unsupported before confirmation and 1 s after; reported while supported
    /// within 0.5 s; resets on 5 s gaps.
    fn default() -> Self {
        Self {
            particles: 500,
            seed: 0,
            speed_noise: 0.5,
            heading_noise: 1.0,
            max_speed: 2.5,
            initial_speed_std: 0.5,
            combination: CombinationParams::default(),
            birth_threshold: 0.5,
            min_track_distance: 0.6,
            merge_distance: 0.3,
            min_confidence: 0.5,
            max_missing_time: 1.0,
            tentative_missing_time: 0.5,
            confirm_hits: 3,
            confirm_confidence: 1.0,
            confirm_strong_hits: 2,
            min_travel: 1.2,
            confirm_mean_confidence: None,
            max_report_coast: 0.5,
            max_time_gap: 5.0,
            max_history: None,
        }
    }
}

impl ParticleParams {
    fn confirm_rule(&self) -> ConfirmRule {
        ConfirmRule {
            hits: self.confirm_hits,
            strong_confidence: self.confirm_confidence,
            strong_hits: self.confirm_strong_hits,
            min_travel: self.min_travel,
            mean_confidence: self.confirm_mean_confidence,
        }
    }

    /// Sets [`ParticleParams::particles`].
    pub fn with_particles(mut self, v: usize) -> Self {
        self.particles = v;
        self
    }
    /// Sets [`ParticleParams::seed`].
    pub fn with_seed(mut self, v: u64) -> Self {
        self.seed = v;
        self
    }
    /// Sets [`ParticleParams::speed_noise`].
    pub fn with_speed_noise(mut self, v: f64) -> Self {
        self.speed_noise = v;
        self
    }
    /// Sets [`ParticleParams::heading_noise`].
    pub fn with_heading_noise(mut self, v: f64) -> Self {
        self.heading_noise = v;
        self
    }
    /// Sets [`ParticleParams::max_speed`].
    pub fn with_max_speed(mut self, v: f64) -> Self {
        self.max_speed = v;
        self
    }
    /// Sets [`ParticleParams::initial_speed_std`].
    pub fn with_initial_speed_std(mut self, v: f64) -> Self {
        self.initial_speed_std = v;
        self
    }
    /// Sets [`ParticleParams::combination`].
    pub fn with_combination(mut self, v: CombinationParams) -> Self {
        self.combination = v;
        self
    }
    /// Sets [`ParticleParams::birth_threshold`].
    pub fn with_birth_threshold(mut self, v: f64) -> Self {
        self.birth_threshold = v;
        self
    }
    /// Sets [`ParticleParams::min_track_distance`].
    pub fn with_min_track_distance(mut self, v: f64) -> Self {
        self.min_track_distance = v;
        self
    }
    /// Sets [`ParticleParams::merge_distance`].
    pub fn with_merge_distance(mut self, v: f64) -> Self {
        self.merge_distance = v;
        self
    }
    /// Sets [`ParticleParams::min_confidence`].
    pub fn with_min_confidence(mut self, v: f64) -> Self {
        self.min_confidence = v;
        self
    }
    /// Sets [`ParticleParams::max_missing_time`].
    pub fn with_max_missing_time(mut self, v: f64) -> Self {
        self.max_missing_time = v;
        self
    }
    /// Sets [`ParticleParams::tentative_missing_time`].
    pub fn with_tentative_missing_time(mut self, v: f64) -> Self {
        self.tentative_missing_time = v;
        self
    }
    /// Sets [`ParticleParams::confirm_hits`].
    pub fn with_confirm_hits(mut self, v: usize) -> Self {
        self.confirm_hits = v;
        self
    }
    /// Sets [`ParticleParams::confirm_confidence`].
    pub fn with_confirm_confidence(mut self, v: f64) -> Self {
        self.confirm_confidence = v;
        self
    }
    /// Sets [`ParticleParams::confirm_strong_hits`].
    pub fn with_confirm_strong_hits(mut self, v: usize) -> Self {
        self.confirm_strong_hits = v;
        self
    }
    /// Sets [`ParticleParams::confirm_mean_confidence`].
    pub fn with_confirm_mean_confidence(mut self, v: Option<f64>) -> Self {
        self.confirm_mean_confidence = v;
        self
    }
    /// Sets [`ParticleParams::min_travel`].
    pub fn with_min_travel(mut self, v: f64) -> Self {
        self.min_travel = v;
        self
    }
    /// Sets [`ParticleParams::max_report_coast`].
    pub fn with_max_report_coast(mut self, v: f64) -> Self {
        self.max_report_coast = v;
        self
    }
    /// Sets [`ParticleParams::max_time_gap`].
    pub fn with_max_time_gap(mut self, v: f64) -> Self {
        self.max_time_gap = v;
        self
    }
    /// Sets [`ParticleParams::max_history`].
    pub fn with_max_history(mut self, v: Option<usize>) -> Self {
        self.max_history = v;
        self
    }

    /// The parameters, if every rule holds.
    ///
    /// # Errors
    /// [`crate::TrackingError::InvalidParameter`] naming the first parameter that breaks
    /// its rule: `particles` ≥ 1; `max_speed`, `birth_threshold`, `max_missing_time` and
    /// `max_time_gap` finite and > 0; `speed_noise`, `heading_noise`, `initial_speed_std`,
    /// `min_track_distance`, `merge_distance`, `min_confidence`, `max_report_coast`,
    /// `tentative_missing_time` and `min_travel` finite and ≥ 0; `confirm_hits` ≥ 1;
    /// `confirm_confidence` finite; `max_history` ≥ 1 when given; and the combination's
    /// rules.
    pub fn check(self) -> Result<Self> {
        rule(
            self.particles >= 1,
            "particles",
            self.particles as f64,
            "must be >= 1",
        )?;
        for (name, v) in [
            ("max_speed", self.max_speed),
            ("birth_threshold", self.birth_threshold),
            ("max_missing_time", self.max_missing_time),
        ] {
            haunts_core::positive(name, v)?;
        }
        for (name, v) in [
            ("speed_noise", self.speed_noise),
            ("heading_noise", self.heading_noise),
            ("initial_speed_std", self.initial_speed_std),
            ("min_track_distance", self.min_track_distance),
            ("merge_distance", self.merge_distance),
            ("min_confidence", self.min_confidence),
            ("max_report_coast", self.max_report_coast),
            ("tentative_missing_time", self.tentative_missing_time),
            ("min_travel", self.min_travel),
        ] {
            rule(
                v.is_finite() && v >= 0.0,
                name,
                v,
                "must be finite and >= 0",
            )?;
        }
        rule(
            self.confirm_hits >= 1,
            "confirm_hits",
            self.confirm_hits as f64,
            "must be >= 1",
        )?;
        rule(
            self.confirm_confidence.is_finite(),
            "confirm_confidence",
            self.confirm_confidence,
            "must be finite",
        )?;
        check_confirm_mean(self.confirm_mean_confidence)?;
        check_gap(self.max_time_gap)?;
        check_history(self.max_history)?;
        self.combination.check()?;
        Ok(self)
    }
}

/// One hypothesis of a person's state; `cos`/`sin` cache the heading's.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Particle {
    x: f64,
    y: f64,
    v: f64,
    theta: f64,
    cos: f64,
    sin: f64,
}

/// One tracked person.
#[derive(Debug, Clone, PartialEq)]
struct Person {
    track: Track,
    particles: Vec<Particle>,
    born: f64,
    last_support: f64,
    reported_once: bool,
    confirmed: bool,
    evidence: Evidence,
}

/// The seed-000 particle-filter tracker.
///
/// Each update, with `g` the Gaussian combination of the detections so far (seed 000 IV-A-2:
/// each a Gaussian weighted by a factor falling linearly with its age; the new ones
/// added, the forgotten ones dropped):
/// 1. **Motion:** every particle's speed and heading get Gaussian noise
///    (`v += speed_noise·√dt·n₁`, `θ += heading_noise·√dt·n₂`; a negative speed turns the
///    heading round; speeds are capped at `max_speed`), then it moves `v·dt` along `θ`.
/// 2. **Likelihood:** a particle's weight is `g` at its position; the person's confidence is
///    the expected value of `g` under the weights (`Σ g² / Σ g`, about `g` at the detection
///    the cloud covers), and it is *supported* when that reaches `min_confidence`. Weights
///    are normalised per person (uniform if all are zero).
/// 3. **Estimate:** the weighted mean of the particles (position, velocity `v·(cos θ,
///    sin θ)`) and the weighted covariance of their positions.
/// 4. **Resampling:** sampling-importance resampling with the systematic scheme.
/// 5. **Confirmation and death:** a supported update adds to the person's evidence (the
///    most confident detection of the update within `min_track_distance`, and how far the
///    estimate is from where it was born); a new person is confirmed after
///    `confirm_hits` supported updates and either `confirm_strong_hits` of them with a
///    detection of at least `confirm_confidence` (leg pairs) or a walk of `min_travel`
///    metres. A person unsupported for more than `tentative_missing_time` seconds
///    (unconfirmed) or `max_missing_time` (confirmed) ends; of two people closer than
///    `merge_distance`, the unconfirmed one, then the one with fewer hits, then the younger
///    ends.
/// 6. **Birth:** a detection where `g ≥ birth_threshold`, at least `min_track_distance`
///    from every person, starts a person whose particles are drawn from the detection's
///    Gaussian, with speeds `|N(0, initial_speed_std)|` and uniform headings.
///
/// Confirmed people supported within `max_report_coast` seconds are reported. Random numbers come
/// from one Xoshiro256++ generator seeded with `seed`, so a run is reproducible.
///
/// # Complexity
/// O(p · n · k) per update for `n` people of `p` particles and `k` Gaussians near each
/// person (the combination is restricted to each particle cloud's neighbourhood).
///
/// # Example
/// ```
/// use haunts_tracking::detect::Detection;
/// use haunts_tracking::track::particle::{ParticleParams, ParticleTracker};
/// use haunts_tracking::track::Tracker;
/// use nalgebra::Point2;
///
/// let mut pf = ParticleTracker::new(ParticleParams::default().with_seed(7))?;
/// // A person walking along x at 1 m/s, seen at 10 Hz.
/// for k in 0..30 {
///     let t = k as f64 * 0.1;
///     pf.update(t, &[Detection::isotropic(Point2::new(t, 1.0), 0.1)])?;
/// }
/// let tracks = pf.tracks();
/// assert_eq!(tracks.len(), 1);
/// approx::assert_abs_diff_eq!(tracks[0].position.x, 2.9, epsilon = 0.15);
/// approx::assert_abs_diff_eq!(tracks[0].position.y, 1.0, epsilon = 0.1);
/// # Ok::<(), haunts_tracking::TrackingError>(())
/// ```
#[derive(Debug, Clone)]
pub struct ParticleTracker {
    params: ParticleParams,
    clock: Clock,
    rng: Xoshiro256PlusPlus,
    combination: GaussianCombination,
    next_id: u64,
    people: Vec<Person>,
    book: TrackLists,
    weights: Vec<f64>,
    scratch: Vec<Particle>,
}

impl ParticleTracker {
    /// A tracker with checked parameters and nobody tracked.
    ///
    /// # Errors
    /// As [`ParticleParams::check`].
    pub fn new(params: ParticleParams) -> Result<Self> {
        let params = params.check()?;
        Ok(Self {
            params,
            clock: Clock::new(params.max_time_gap),
            rng: Xoshiro256PlusPlus::seed_from_u64(params.seed),
            combination: GaussianCombination::new(params.combination)?,
            next_id: 0,
            people: Vec::new(),
            book: TrackLists::default(),
            weights: Vec::new(),
            scratch: Vec::new(),
        })
    }

    /// The parameters.
    pub fn params(&self) -> &ParticleParams {
        &self.params
    }

    /// Ends every person (those reported at least once move to the finished list).
    fn close_all(&mut self) {
        let coast = self.params.max_report_coast;
        for person in self.people.drain(..) {
            if person.reported_once {
                self.book.finish(person.track, person.last_support + coast);
            }
        }
        self.combination.clear();
    }

    /// Steps 1–4 for one person; returns whether it was supported.
    fn filter(&mut self, index: usize, time: f64, dt: f64, detections: &[Detection]) -> bool {
        let params = self.params;
        let Some(person) = self.people.get_mut(index) else {
            return false;
        };
        let rng = &mut self.rng;
        // 1. Motion.
        if dt > 0.0 {
            let (sv, st) = (
                params.speed_noise * dt.sqrt(),
                params.heading_noise * dt.sqrt(),
            );
            for p in &mut person.particles {
                let n1: f64 = rng.sample(StandardNormal);
                let n2: f64 = rng.sample(StandardNormal);
                p.v += sv * n1;
                p.theta += st * n2;
                if p.v < 0.0 {
                    p.v = -p.v;
                    p.theta += std::f64::consts::PI;
                }
                p.v = p.v.min(params.max_speed);
                (p.sin, p.cos) = p.theta.sin_cos();
                p.x += p.v * p.cos * dt;
                p.y += p.v * p.sin * dt;
            }
        }
        // 2. Likelihood from the combination near the cloud.
        let n = person.particles.len() as f64;
        let centre = person
            .particles
            .iter()
            .fold(Vector2::zeros(), |s, p| s + Vector2::new(p.x, p.y))
            / n;
        let centre = Point2::from(centre);
        let radius = person
            .particles
            .iter()
            .map(|p| (p.x - centre.x).hypot(p.y - centre.y))
            .fold(0.0, f64::max);
        let snapshot = self.combination.snapshot(time, &centre, radius);
        self.weights.clear();
        self.weights.extend(
            person
                .particles
                .iter()
                .map(|p| snapshot.value(&Point2::new(p.x, p.y))),
        );
        let total: f64 = self.weights.iter().sum();
        // The combination's expected value under the posterior: Σ g² / Σ g.
        let confidence = if total > 0.0 {
            self.weights.iter().map(|g| g * g).sum::<f64>() / total
        } else {
            0.0
        };
        if total > 0.0 && total.is_finite() {
            self.weights.iter_mut().for_each(|w| *w /= total);
        } else {
            self.weights.iter_mut().for_each(|w| *w = 1.0 / n);
        }
        // 3. Estimate.
        let (mut m, mut vel) = (Vector2::zeros(), Vector2::zeros());
        for (p, &w) in person.particles.iter().zip(&self.weights) {
            m += Vector2::new(p.x, p.y) * w;
            vel += Vector2::new(p.cos, p.sin) * (p.v * w);
        }
        let mut cov = Matrix2::zeros();
        for (p, &w) in person.particles.iter().zip(&self.weights) {
            let d = Vector2::new(p.x, p.y) - m;
            cov += d * d.transpose() * w;
        }
        person.track.position = Point2::from(m);
        person.track.velocity = vel;
        person.track.covariance = cov;
        // 4. Systematic resampling.
        let step = 1.0 / n;
        let mut u = rng.random_range(0.0..step);
        let mut cumulative = 0.0;
        let mut j = 0;
        self.scratch.clear();
        let last = person.particles.len() - 1;
        for (k, &w) in self.weights.iter().enumerate() {
            cumulative += w;
            while j < person.particles.len() && (u < cumulative || k == last) {
                self.scratch.push(person.particles[k]);
                u += step;
                j += 1;
            }
        }
        std::mem::swap(&mut person.particles, &mut self.scratch);
        let supported = confidence >= params.min_confidence;
        if supported {
            person.last_support = time;
            person.track.hits += 1;
            // The most confident detection of this update that belongs to the person.
            let near = detections
                .iter()
                .filter(|d| (d.position - person.track.position).norm() < params.min_track_distance)
                .map(|d| d.confidence)
                .fold(0.0, f64::max);
            let rule = params.confirm_rule();
            person.evidence.add(&person.track.position, near, &rule);
            person.track.confidence = person.evidence.mean_confidence();
            person.confirmed |= person.evidence.confirms(&rule);
        }
        supported
    }

    fn birth(&mut self, time: f64, d: &Detection) {
        let params = self.params;
        let rng = &mut self.rng;
        // Cholesky factor of the (checked, positive definite) covariance.
        let c = (d.covariance + d.covariance.transpose()) * 0.5;
        let l00 = c[(0, 0)].sqrt();
        let l10 = c[(1, 0)] / l00;
        let l11 = (c[(1, 1)] - l10 * l10).max(0.0).sqrt();
        let particles = (0..params.particles)
            .map(|_| {
                let n1: f64 = rng.sample(StandardNormal);
                let n2: f64 = rng.sample(StandardNormal);
                let nv: f64 = rng.sample(StandardNormal);
                let theta = rng.random_range(-std::f64::consts::PI..std::f64::consts::PI);
                let (sin, cos) = theta.sin_cos();
                Particle {
                    x: d.position.x + l00 * n1,
                    y: d.position.y + l10 * n1 + l11 * n2,
                    v: (params.initial_speed_std * nv).abs().min(params.max_speed),
                    theta,
                    cos,
                    sin,
                }
            })
            .collect();
        let id = self.next_id;
        self.next_id += 1;
        let rule = params.confirm_rule();
        let evidence = Evidence::new(d.position, d.confidence, &rule);
        self.people.push(Person {
            track: Track {
                id,
                position: d.position,
                velocity: Vector2::zeros(),
                covariance: c,
                age: 0.0,
                hits: 1,
                confidence: d.confidence,
                history: Vec::new(),
            },
            particles,
            born: time,
            last_support: time,
            reported_once: false,
            confirmed: evidence.confirms(&rule),
            evidence,
        });
    }

    fn end(&mut self, index: usize) {
        let person = self.people.remove(index);
        if person.reported_once {
            let last = person.last_support + self.params.max_report_coast;
            self.book.finish(person.track, last);
        }
    }
}

impl Tracker for ParticleTracker {
    fn update(&mut self, time: f64, detections: &[Detection]) -> Result<&TrackLists> {
        let step = self.clock.check(time, detections)?;
        if step == Step::Reset {
            self.close_all();
        }
        // Cannot fail now: time and detections are checked, and time is not before the
        // combination's latest (the clock's last time, or cleared by a reset).
        self.combination.forget(time)?;
        self.combination.add(time, detections)?;
        self.clock.commit(time, step, &mut self.book);
        let dt = match step {
            Step::Advance(dt) => dt,
            Step::First | Step::Reset => 0.0,
        };
        let params = self.params;
        for index in 0..self.people.len() {
            self.filter(index, time, dt, detections);
        }
        // 5. Deaths: unsupported for too long, then merges.
        let mut index = 0;
        while index < self.people.len() {
            let person = &self.people[index];
            let limit = if person.confirmed {
                params.max_missing_time
            } else {
                params.tentative_missing_time
            };
            if time - person.last_support > limit {
                self.end(index);
            } else {
                index += 1;
            }
        }
        'merge: loop {
            for a in 0..self.people.len() {
                for b in a + 1..self.people.len() {
                    let (pa, pb) = (&self.people[a], &self.people[b]);
                    if (pa.track.position - pb.track.position).norm() < params.merge_distance {
                        // The weaker one ends: unconfirmed, then fewer hits, then younger
                        // (larger id).
                        let weaker = if (pa.confirmed, pa.track.hits, pb.track.id)
                            < (pb.confirmed, pb.track.hits, pa.track.id)
                        {
                            a
                        } else {
                            b
                        };
                        self.end(weaker);
                        continue 'merge;
                    }
                }
            }
            break;
        }
        // 6. Births.
        for d in detections {
            let far = self
                .people
                .iter()
                .all(|p| (p.track.position - d.position).norm() >= params.min_track_distance);
            if far && self.combination.value(time, &d.position) >= params.birth_threshold {
                self.birth(time, d);
            }
        }
        self.book.clear_live();
        for person in &mut self.people {
            person.track.age = time - person.born;
            person.track.record(time, params.max_history);
            let seen = time - person.last_support <= params.max_report_coast;
            person.reported_once |= person.confirmed && seen;
            self.book.list(&person.track, person.confirmed, seen);
        }
        Ok(&self.book)
    }

    fn lists(&self) -> &TrackLists {
        &self.book
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;
    use crate::TrackingError;

    #[test]
    fn every_bad_parameter_is_named() {
        let d = ParticleParams::default();
        for (params, name) in [
            (d.with_particles(0), "particles"),
            (d.with_max_speed(0.0), "max_speed"),
            (d.with_birth_threshold(f64::NAN), "birth_threshold"),
            (d.with_max_missing_time(-1.0), "max_missing_time"),
            (d.with_speed_noise(-0.1), "speed_noise"),
            (d.with_heading_noise(f64::INFINITY), "heading_noise"),
            (d.with_initial_speed_std(-1.0), "initial_speed_std"),
            (d.with_min_track_distance(f64::NAN), "min_track_distance"),
            (d.with_merge_distance(-1.0), "merge_distance"),
            (d.with_min_confidence(-0.5), "min_confidence"),
            (d.with_max_report_coast(f64::NAN), "max_report_coast"),
            (d.with_max_time_gap(0.0), "max_time_gap"),
            (d.with_max_history(Some(0)), "max_history"),
            (
                d.with_tentative_missing_time(-1.0),
                "tentative_missing_time",
            ),
            (d.with_min_travel(f64::INFINITY), "min_travel"),
            (d.with_confirm_hits(0), "confirm_hits"),
            (d.with_confirm_confidence(f64::NAN), "confirm_confidence"),
            (
                d.with_combination(CombinationParams::default().with_horizon(0.0)),
                "horizon",
            ),
        ] {
            assert!(
                matches!(
                    ParticleTracker::new(params),
                    Err(TrackingError::InvalidParameter(haunts_core::InvalidParameter { name: n, .. })) if n == name
                ),
                "{name}"
            );
        }
    }

    #[test]
    fn systematic_resampling_keeps_the_particle_count() {
        let mut pf = ParticleTracker::new(ParticleParams::default().with_particles(37)).unwrap();
        let d = Detection::isotropic(Point2::new(0.0, 0.0), 0.1);
        for k in 0..5 {
            pf.update(k as f64 * 0.1, &[d]).unwrap();
        }
        assert_eq!(pf.people.len(), 1);
        assert_eq!(pf.people[0].particles.len(), 37);
    }
}
