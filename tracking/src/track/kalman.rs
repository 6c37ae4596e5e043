//! A constant-velocity Kalman tracker with global-nearest-neighbour association: the strong
//! baseline of leg_tracker and SPENCER.

use nalgebra::{Matrix4, Matrix4x2, Point2, Vector2, Vector4};

use crate::Result;
use crate::detect::{Detection, rule};
use crate::track::assign::min_cost_assignment;
use crate::track::{
    Clock, ConfirmRule, Evidence, Step, Track, TrackLists, Tracker, check_confirm_mean, check_gap,
    check_history,
};

/// Parameters of the [`KalmanTracker`].
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub struct KalmanParams {
    /// Standard deviation of a walking person's acceleration, m/s²: the process noise of
    /// the constant-velocity model (white acceleration, constant over each step).
    pub acceleration_std: f64,
    /// Standard deviation of a new track's speed along each axis, m/s (about a walking
    /// speed: a new track may be standing or walking in any direction).
    pub initial_speed_std: f64,
    /// Largest squared Mahalanobis distance between a track's predicted position and a
    /// detection it may take (χ² with 2 degrees of freedom: 9.21 keeps 99 %).
    pub gate: f64,
    /// Largest Euclidean distance between a track's predicted position and a detection it
    /// may take, metres: a bound on how far a person walks in one step whatever the
    /// covariance says.
    pub max_gate_distance: f64,
    /// Hits after which a tentative track is confirmed and reported.
    pub confirm_hits: usize,
    /// A tentative track is dropped when unseen for longer than this, seconds.
    pub tentative_missing_time: f64,
    /// Besides `confirm_hits`, a tentative track needs evidence that it is a person:
    /// `confirm_strong_hits` detections at least this confident (1 = a leg pair with the
    /// default leg detector: people show two legs now and then, a table leg or a post
    /// never does) ...
    pub confirm_confidence: f64,
    /// ... (how many such detections) ...
    pub confirm_strong_hits: usize,
    /// ... or to have moved this far from where it was born, metres (people walk, posts do
    /// not) ...
    pub min_travel: f64,
    /// ... or (when given) a running average of its detections' confidences of at least
    /// this (`leg_tracker`'s rule; with [`crate::detect::ForestDetector`], the forest's
    /// cross-validated operating point).
    pub confirm_mean_confidence: Option<f64>,
    /// A confirmed track is deleted after this many seconds without a detection.
    pub max_missing_time: f64,
    /// A confirmed track is reported while its last detection is at most this many seconds
    /// old (0: only tracks detected in the current update; leg_tracker's
    /// `publish_occluded: false`).
    pub max_report_coast: f64,
    /// Only detections at least this confident start new tracks (1 = leg pairs only with the
    /// default leg detector); weaker ones can still update existing tracks.
    pub min_birth_confidence: f64,
    /// A step longer than this, seconds, resets the tracker (see [`Tracker`]).
    pub max_time_gap: f64,
    /// Longest history kept per track (`None`: everything).
    pub max_history: Option<usize>,
}

impl Default for KalmanParams {
    /// Walking people: acceleration σ 1.5 m/s², initial speed σ 1 m/s; 99 % gate, at most
    /// 1 m per step; births from any detection of confidence ≥ 0.5 (single legs too);
    /// confirmed after 3 hits and either two leg pairs or 1.2 m walked (a second at a
    /// walking pace: farther than a post's apparent wander when its detections alternate
    /// between it and its neighbours); tentative tracks dropped after 0.5 s unseen
    /// (people a few metres away are missed by the detector in about half the scans),
    /// confirmed ones after 1 s, reported while seen within 0.5 s; resets on gaps over 5 s.
    fn default() -> Self {
        Self {
            acceleration_std: 1.5,
            initial_speed_std: 1.0,
            gate: 9.21,
            max_gate_distance: 1.0,
            confirm_hits: 3,
            tentative_missing_time: 0.5,
            confirm_confidence: 1.0,
            confirm_strong_hits: 2,
            min_travel: 1.2,
            confirm_mean_confidence: None,
            max_missing_time: 1.0,
            max_report_coast: 0.5,
            min_birth_confidence: 0.5,
            max_time_gap: 5.0,
            max_history: None,
        }
    }
}

impl KalmanParams {
    fn confirm_rule(&self) -> ConfirmRule {
        ConfirmRule {
            hits: self.confirm_hits,
            strong_confidence: self.confirm_confidence,
            strong_hits: self.confirm_strong_hits,
            min_travel: self.min_travel,
            mean_confidence: self.confirm_mean_confidence,
        }
    }

    /// Sets [`KalmanParams::acceleration_std`].
    pub fn with_acceleration_std(mut self, v: f64) -> Self {
        self.acceleration_std = v;
        self
    }
    /// Sets [`KalmanParams::initial_speed_std`].
    pub fn with_initial_speed_std(mut self, v: f64) -> Self {
        self.initial_speed_std = v;
        self
    }
    /// Sets [`KalmanParams::gate`].
    pub fn with_gate(mut self, v: f64) -> Self {
        self.gate = v;
        self
    }
    /// Sets [`KalmanParams::max_gate_distance`].
    pub fn with_max_gate_distance(mut self, v: f64) -> Self {
        self.max_gate_distance = v;
        self
    }
    /// Sets [`KalmanParams::confirm_hits`].
    pub fn with_confirm_hits(mut self, v: usize) -> Self {
        self.confirm_hits = v;
        self
    }
    /// Sets [`KalmanParams::tentative_missing_time`].
    pub fn with_tentative_missing_time(mut self, v: f64) -> Self {
        self.tentative_missing_time = v;
        self
    }
    /// Sets [`KalmanParams::confirm_strong_hits`].
    pub fn with_confirm_strong_hits(mut self, v: usize) -> Self {
        self.confirm_strong_hits = v;
        self
    }
    /// Sets [`KalmanParams::confirm_confidence`].
    pub fn with_confirm_confidence(mut self, v: f64) -> Self {
        self.confirm_confidence = v;
        self
    }
    /// Sets [`KalmanParams::confirm_mean_confidence`].
    pub fn with_confirm_mean_confidence(mut self, v: Option<f64>) -> Self {
        self.confirm_mean_confidence = v;
        self
    }
    /// Sets [`KalmanParams::min_travel`].
    pub fn with_min_travel(mut self, v: f64) -> Self {
        self.min_travel = v;
        self
    }
    /// Sets [`KalmanParams::max_missing_time`].
    pub fn with_max_missing_time(mut self, v: f64) -> Self {
        self.max_missing_time = v;
        self
    }
    /// Sets [`KalmanParams::max_report_coast`].
    pub fn with_max_report_coast(mut self, v: f64) -> Self {
        self.max_report_coast = v;
        self
    }
    /// Sets [`KalmanParams::min_birth_confidence`].
    pub fn with_min_birth_confidence(mut self, v: f64) -> Self {
        self.min_birth_confidence = v;
        self
    }
    /// Sets [`KalmanParams::max_time_gap`].
    pub fn with_max_time_gap(mut self, v: f64) -> Self {
        self.max_time_gap = v;
        self
    }
    /// Sets [`KalmanParams::max_history`].
    pub fn with_max_history(mut self, v: Option<usize>) -> Self {
        self.max_history = v;
        self
    }

    /// The parameters, if every rule holds.
    ///
    /// # Errors
    /// [`crate::TrackingError::InvalidParameter`] naming the first parameter that breaks its rule:
    /// `acceleration_std`, `initial_speed_std`, `gate`, `max_gate_distance`,
    /// `max_missing_time` and `max_time_gap` finite and > 0; `confirm_hits` ≥ 1;
    /// `tentative_missing_time`, `min_travel` and `max_report_coast` finite and ≥ 0;
    /// `confirm_confidence` and `min_birth_confidence` finite; `max_history` ≥ 1 when
    /// given.
    pub fn check(self) -> Result<Self> {
        for (name, v) in [
            ("acceleration_std", self.acceleration_std),
            ("initial_speed_std", self.initial_speed_std),
            ("gate", self.gate),
            ("max_gate_distance", self.max_gate_distance),
            ("max_missing_time", self.max_missing_time),
        ] {
            haunts_core::positive(name, v)?;
        }
        rule(
            self.min_travel.is_finite() && self.min_travel >= 0.0,
            "min_travel",
            self.min_travel,
            "must be finite and >= 0",
        )?;
        rule(
            self.confirm_hits >= 1,
            "confirm_hits",
            self.confirm_hits as f64,
            "must be >= 1",
        )?;
        rule(
            self.tentative_missing_time.is_finite() && self.tentative_missing_time >= 0.0,
            "tentative_missing_time",
            self.tentative_missing_time,
            "must be finite and >= 0",
        )?;
        rule(
            self.max_report_coast.is_finite() && self.max_report_coast >= 0.0,
            "max_report_coast",
            self.max_report_coast,
            "must be finite and >= 0",
        )?;
        rule(
            self.confirm_confidence.is_finite(),
            "confirm_confidence",
            self.confirm_confidence,
            "must be finite",
        )?;
        rule(
            self.min_birth_confidence.is_finite(),
            "min_birth_confidence",
            self.min_birth_confidence,
            "must be finite",
        )?;
        check_confirm_mean(self.confirm_mean_confidence)?;
        check_gap(self.max_time_gap)?;
        check_history(self.max_history)?;
        Ok(self)
    }
}

/// One track's filter state.
#[derive(Debug, Clone, PartialEq)]
struct Filter {
    track: Track,
    /// `(x, y, vx, vy)`.
    x: Vector4<f64>,
    p: Matrix4<f64>,
    confirmed: bool,
    evidence: Evidence,
    born: f64,
    last_hit: f64,
}

/// A constant-velocity Kalman filter per person, associated to detections by global nearest
/// neighbour.
///
/// Each update:
/// 1. predicts every track with the constant-velocity model; the process noise is a white
///    acceleration of σ = `acceleration_std`, constant over the step
///    (`Q = σ² G Gᵀ`, `G = (dt²/2, dt²/2, dt, dt)` per axis);
/// 2. gates track–detection pairs by the squared Mahalanobis distance `νᵀ S⁻¹ ν ≤ gate`
///    (`S = H P Hᵀ + R`, `R` the detection's covariance) and by `|ν| ≤ max_gate_distance`,
///    and solves the assignment that matches the most pairs at the least total squared
///    Mahalanobis distance (Kuhn–Munkres, gated);
/// 3. corrects matched tracks (Joseph form); a tentative track is confirmed once it has
///    `confirm_hits` hits and either `confirm_strong_hits` detections of at least
///    `confirm_confidence` (leg pairs) or an estimate `min_travel` metres from where it was
///    born;
/// 4. drops tentative tracks unseen for more than `tentative_missing_time` seconds and
///    confirmed ones unseen for more than `max_missing_time`;
/// 5. starts a tentative track at every unmatched detection with confidence ≥
///    `min_birth_confidence`.
///
/// Only confirmed tracks detected within `max_report_coast` seconds are reported.
///
/// # Complexity
/// O(t·d) to gate `t` tracks against `d` detections, plus the assignment of the gated ones.
///
/// # Example
/// ```
/// use haunts_tracking::detect::Detection;
/// use haunts_tracking::track::kalman::{KalmanParams, KalmanTracker};
/// use haunts_tracking::track::Tracker;
/// use nalgebra::Point2;
///
/// let mut kf = KalmanTracker::new(KalmanParams::default())?;
/// // A person walking along x at 1 m/s, seen at 10 Hz.
/// for k in 0..20 {
///     let t = k as f64 * 0.1;
///     kf.update(t, &[Detection::isotropic(Point2::new(t, 1.0), 0.05)])?;
/// }
/// let tracks = kf.tracks();
/// assert_eq!(tracks.len(), 1);
/// approx::assert_abs_diff_eq!(tracks[0].position.x, 1.9, epsilon = 0.05);
/// approx::assert_abs_diff_eq!(tracks[0].velocity.x, 1.0, epsilon = 0.1);
/// # Ok::<(), haunts_tracking::TrackingError>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct KalmanTracker {
    params: KalmanParams,
    clock: Clock,
    next_id: u64,
    filters: Vec<Filter>,
    book: TrackLists,
}

impl KalmanTracker {
    /// A tracker with checked parameters and no track.
    ///
    /// # Errors
    /// As [`KalmanParams::check`].
    pub fn new(params: KalmanParams) -> Result<Self> {
        let params = params.check()?;
        Ok(Self {
            params,
            clock: Clock::new(params.max_time_gap),
            next_id: 0,
            filters: Vec::new(),
            book: TrackLists::default(),
        })
    }

    /// The parameters.
    pub fn params(&self) -> &KalmanParams {
        &self.params
    }

    /// The filters' states predicted `dt` seconds ahead (unchanged for `dt ≤ 0`).
    fn predicted(&self, dt: f64) -> Vec<(Vector4<f64>, Matrix4<f64>)> {
        let mut f = Matrix4::identity();
        f[(0, 2)] = dt;
        f[(1, 3)] = dt;
        let s2 = self.params.acceleration_std * self.params.acceleration_std;
        let (a, b, c) = (dt.powi(4) / 4.0, dt.powi(3) / 2.0, dt * dt);
        let q = Matrix4::new(
            a, 0.0, b, 0.0, //
            0.0, a, 0.0, b, //
            b, 0.0, c, 0.0, //
            0.0, b, 0.0, c,
        ) * s2;
        self.filters
            .iter()
            .map(|filter| {
                if dt > 0.0 {
                    (f * filter.x, f * filter.p * f.transpose() + q)
                } else {
                    (filter.x, filter.p)
                }
            })
            .collect()
    }

    /// Squared Mahalanobis distances of every predicted track–detection pair, row-major by
    /// track; `INFINITY` outside the gates.
    fn costs(
        &self,
        predicted: &[(Vector4<f64>, Matrix4<f64>)],
        detections: &[Detection],
    ) -> Vec<f64> {
        let mut cost = Vec::with_capacity(predicted.len() * detections.len());
        for (x, p) in predicted {
            let position = Point2::new(x[0], x[1]);
            let p = p.fixed_view::<2, 2>(0, 0).into_owned();
            for d in detections {
                let nu = d.position - position;
                let m = (p + d.covariance)
                    .try_inverse()
                    .map(|inv| (nu.transpose() * inv * nu)[(0, 0)])
                    .unwrap_or(f64::INFINITY);
                let inside = m <= self.params.gate && nu.norm() <= self.params.max_gate_distance;
                cost.push(if inside { m } else { f64::INFINITY });
            }
        }
        cost
    }

    fn correct(filter: &mut Filter, d: &Detection) {
        let h = Matrix4x2::<f64>::identity().transpose();
        let s = filter.p.fixed_view::<2, 2>(0, 0) + d.covariance;
        let Some(s_inv) = s.try_inverse() else {
            return;
        };
        let k = filter.p * h.transpose() * s_inv;
        let nu = d.position.coords - Vector2::new(filter.x[0], filter.x[1]);
        filter.x += k * nu;
        let i_kh = Matrix4::identity() - k * h;
        filter.p = i_kh * filter.p * i_kh.transpose() + k * d.covariance * k.transpose();
    }

    fn birth(&mut self, time: f64, d: &Detection) {
        let rule = self.params.confirm_rule();
        let evidence = Evidence::new(d.position, d.confidence, &rule);
        let v = self.params.initial_speed_std * self.params.initial_speed_std;
        let mut p = Matrix4::zeros();
        p.fixed_view_mut::<2, 2>(0, 0).copy_from(&d.covariance);
        p[(2, 2)] = v;
        p[(3, 3)] = v;
        let id = self.next_id;
        self.next_id += 1;
        self.filters.push(Filter {
            track: Track {
                id,
                position: d.position,
                velocity: Vector2::zeros(),
                covariance: d.covariance,
                age: 0.0,
                hits: 1,
                confidence: d.confidence,
                history: Vec::new(),
            },
            x: Vector4::new(d.position.x, d.position.y, 0.0, 0.0),
            p,
            confirmed: evidence.confirms(&rule),
            evidence,
            born: time,
            last_hit: time,
        });
    }

    /// Ends every live track (confirmed ones move to the finished list).
    fn close_all(&mut self) {
        let coast = self.params.max_report_coast;
        for filter in self.filters.drain(..) {
            if filter.confirmed {
                self.book.finish(filter.track, filter.last_hit + coast);
            }
        }
    }
}

impl Tracker for KalmanTracker {
    fn update(&mut self, time: f64, detections: &[Detection]) -> Result<&TrackLists> {
        let step = self.clock.check(time, detections)?;
        let detections: Vec<Detection> = detections
            .iter()
            .map(|d| Detection {
                covariance: (d.covariance + d.covariance.transpose()) * 0.5,
                ..*d
            })
            .collect();
        let predicted = match step {
            Step::Advance(dt) => self.predicted(dt),
            Step::First | Step::Reset => Vec::new(),
        };
        let cost = self.costs(&predicted, &detections);
        // Everything that can fail is done: from here on the state changes.
        let pairs =
            min_cost_assignment(&cost, predicted.len(), detections.len(), self.params.gate)?;
        self.clock.commit(time, step, &mut self.book);
        if step == Step::Reset {
            self.close_all();
        }
        for (filter, (x, p)) in self.filters.iter_mut().zip(predicted) {
            filter.x = x;
            filter.p = p;
        }

        let rule = self.params.confirm_rule();
        let mut used = vec![false; detections.len()];
        for &(t, d) in &pairs {
            used[d] = true;
            let filter = &mut self.filters[t];
            Self::correct(filter, &detections[d]);
            filter.track.hits += 1;
            filter.last_hit = time;
            let position = Point2::new(filter.x[0], filter.x[1]);
            filter
                .evidence
                .add(&position, detections[d].confidence, &rule);
            filter.track.confidence = filter.evidence.mean_confidence();
            filter.confirmed |= filter.evidence.confirms(&rule);
        }
        let params = self.params;
        let mut kept = Vec::with_capacity(self.filters.len());
        for filter in self.filters.drain(..) {
            let dead = if filter.confirmed {
                time - filter.last_hit > params.max_missing_time
            } else {
                time - filter.last_hit > params.tentative_missing_time
            };
            if dead {
                if filter.confirmed {
                    let last = filter.last_hit + params.max_report_coast;
                    self.book.finish(filter.track, last);
                }
            } else {
                kept.push(filter);
            }
        }
        self.filters = kept;
        for (d, used) in detections.iter().zip(used) {
            if !used && d.confidence >= params.min_birth_confidence {
                self.birth(time, d);
            }
        }

        self.book.clear_live();
        for filter in &mut self.filters {
            let track = &mut filter.track;
            track.position = Point2::new(filter.x[0], filter.x[1]);
            track.velocity = Vector2::new(filter.x[2], filter.x[3]);
            track.covariance = filter.p.fixed_view::<2, 2>(0, 0).into_owned();
            track.age = time - filter.born;
            track.record(time, params.max_history);
            let seen = time - filter.last_hit <= params.max_report_coast;
            self.book.list(track, filter.confirmed, seen);
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
        let d = KalmanParams::default();
        for (params, name) in [
            (d.with_acceleration_std(0.0), "acceleration_std"),
            (d.with_initial_speed_std(f64::NAN), "initial_speed_std"),
            (d.with_gate(-1.0), "gate"),
            (d.with_max_gate_distance(0.0), "max_gate_distance"),
            (d.with_max_missing_time(f64::INFINITY), "max_missing_time"),
            (d.with_confirm_hits(0), "confirm_hits"),
            (
                d.with_tentative_missing_time(-0.1),
                "tentative_missing_time",
            ),
            (d.with_min_travel(f64::NAN), "min_travel"),
            (d.with_confirm_confidence(f64::NAN), "confirm_confidence"),
            (d.with_max_report_coast(-1.0), "max_report_coast"),
            (
                d.with_min_birth_confidence(f64::NAN),
                "min_birth_confidence",
            ),
            (d.with_max_time_gap(0.0), "max_time_gap"),
            (d.with_max_history(Some(0)), "max_history"),
        ] {
            assert!(
                matches!(
                    KalmanTracker::new(params),
                    Err(TrackingError::InvalidParameter(haunts_core::InvalidParameter { name: n, .. })) if n == name
                ),
                "{name}"
            );
        }
    }

    #[test]
    fn the_track_confidence_is_the_running_average_and_confirms() {
        let params = KalmanParams::default()
            .with_min_birth_confidence(0.3)
            .with_confirm_mean_confidence(Some(0.5));
        let mut kf = KalmanTracker::new(params).unwrap();
        let at = |c| Detection {
            confidence: c,
            ..Detection::isotropic(Point2::new(1.0, 1.0), 0.1)
        };
        // 0.4, 0.4, 0.4: three hits, average below 0.5, no walk, no pair: tentative.
        for k in 0..3 {
            assert!(
                kf.update(k as f64 * 0.1, &[at(0.4)])
                    .unwrap()
                    .reported()
                    .is_empty()
            );
        }
        assert_eq!(kf.tentative()[0].hits, 3);
        approx::assert_relative_eq!(kf.tentative()[0].confidence, 0.4, epsilon = 1e-12);
        // 0.9 lifts the average of four to 0.525: confirmed and reported.
        let tracks = kf.update(0.3, &[at(0.9)]).unwrap();
        assert_eq!(tracks.reported().len(), 1);
        approx::assert_relative_eq!(tracks.reported()[0].confidence, 0.525, epsilon = 1e-12);
    }

    #[test]
    fn tentative_tracks_are_not_reported_and_die_when_unseen() {
        let params = KalmanParams::default()
            .with_confirm_hits(3)
            .with_tentative_missing_time(0.05);
        let mut kf = KalmanTracker::new(params).unwrap();
        let d = Detection::isotropic(Point2::new(1.0, 1.0), 0.1);
        assert!(kf.update(0.0, &[d]).unwrap().reported().is_empty());
        assert!(kf.update(0.1, &[d]).unwrap().reported().is_empty());
        assert!(kf.update(0.2, &[]).unwrap().reported().is_empty());
        // The tentative track died: two more hits do not confirm a new one yet.
        assert!(kf.update(0.3, &[d]).unwrap().reported().is_empty());
        assert!(kf.update(0.4, &[d]).unwrap().reported().is_empty());
        let tracks = kf.update(0.5, &[d]).unwrap();
        assert_eq!(tracks.reported().len(), 1);
        assert_eq!(tracks.reported()[0].id, 1);
        assert!(kf.finished().is_empty());
    }
}
