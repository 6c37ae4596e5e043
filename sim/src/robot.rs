//! The robot: a closed patrol of fixed waypoints (seed 000 Fig. 7) driven at constant speed
//! with turns in place, at a set time of day, and wheel odometry that drifts.

use haunts_occupancy::Pose2;
use nalgebra::{Point2, Vector2};
use rand::{RngExt, SeedableRng, rngs::Xoshiro256PlusPlus};
use rand_distr::StandardNormal;

use crate::error::{Result, SimError, invalid};
use crate::rng::{Stream, stream_seed};
use crate::shapes::wrap_angle;

/// When and how fast the robot patrols.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub struct PatrolParams {
    /// Start of the daily patrol, seconds after midnight.
    pub start: f64,
    /// Length of the daily patrol, seconds (start + duration ≤ 86 400).
    pub duration: f64,
    /// Driving speed, m/s.
    pub speed: f64,
    /// Turning rate in place at waypoints, rad/s.
    pub turn_rate: f64,
    /// Patrols per day (≥ 1): the `k`-th starts at `start + k · interval`, always from the
    /// first waypoint. Between two patrols the robot is parked; odometry integrates the
    /// return to the first waypoint as one move.
    pub sessions: usize,
    /// Seconds between the starts of consecutive patrols (≥ `duration` when
    /// `sessions > 1`).
    pub interval: f64,
}

impl Default for PatrolParams {
    /// A 15-minute patrol at 12:30 (the lunch peak), 0.5 m/s, turning at 1 rad/s.
    fn default() -> Self {
        Self {
            start: 12.5 * 3600.0,
            duration: 900.0,
            speed: 0.5,
            turn_rate: 1.0,
            sessions: 1,
            interval: 3600.0,
        }
    }
}

impl PatrolParams {
    /// Patrolling all working day long, 7:00 to 19:00.
    pub fn all_day() -> Self {
        Self {
            start: 7.0 * 3600.0,
            duration: 12.0 * 3600.0,
            ..Self::default()
        }
    }

    /// `sessions` patrols of `duration` seconds, one every `interval` seconds from `start`
    /// (e.g. 5 minutes every hour from 8:00 to 18:00:
    /// `PatrolParams::sessions(8.0 * 3600.0, 300.0, 3600.0, 10)`),
    /// which sees the whole day's rhythm at a fraction of an all-day patrol's scans.
    pub fn sessions(start: f64, duration: f64, interval: f64, sessions: usize) -> Self {
        Self {
            start,
            duration,
            interval,
            sessions,
            ..Self::default()
        }
    }

    /// Start of each patrol of the day, seconds after midnight.
    pub(crate) fn session_starts(&self) -> impl Iterator<Item = f64> + '_ {
        (0..self.sessions).map(move |k| self.start + k as f64 * self.interval)
    }

    /// Sets the start, seconds after midnight.
    pub fn with_start(mut self, start: f64) -> Self {
        self.start = start;
        self
    }

    /// The scan count of a day at `rate` scans per second.
    pub fn scans_per_day(&self, rate: f64) -> f64 {
        self.sessions as f64 * (self.duration * rate).floor()
    }

    /// Sets the duration, seconds.
    pub fn with_duration(mut self, duration: f64) -> Self {
        self.duration = duration;
        self
    }

    /// The parameters if usable.
    ///
    /// # Errors
    /// [`SimError::InvalidParameter`]: `start ≥ 0`, `duration ≥ 0`, `1 ≤ sessions ≤ 10 000`,
    /// `interval` finite, and `≥ duration` when `sessions > 1`, the last patrol ending by
    /// midnight, speed and turn rate finite and positive.
    pub fn check(self) -> Result<Self> {
        let bad = |param, value, expected| Err(invalid(param, value, expected));
        if !(self.start.is_finite() && self.start >= 0.0) {
            return bad("patrol.start", self.start, "finite and >= 0");
        }
        if !(self.duration.is_finite()
            && self.duration >= 0.0
            && self.start + self.duration <= 86_400.0)
        {
            return bad("patrol.duration", self.duration, ">= 0, ending by midnight");
        }
        if !(1..=10_000).contains(&self.sessions) {
            return bad("patrol.sessions", self.sessions as f64, "in 1..=10000");
        }
        if !self.interval.is_finite() {
            return bad("patrol.interval", self.interval, "finite");
        }
        if self.sessions > 1 {
            let last_end = self.start + (self.sessions - 1) as f64 * self.interval + self.duration;
            if !(self.interval.is_finite() && self.interval >= self.duration) {
                return bad("patrol.interval", self.interval, ">= duration");
            }
            if last_end > 86_400.0 {
                return bad(
                    "patrol.interval",
                    self.interval,
                    "last patrol ending by midnight",
                );
            }
        }
        if !(self.speed.is_finite() && self.speed > 0.0) {
            return bad("patrol.speed", self.speed, "finite and > 0");
        }
        if !(self.turn_rate.is_finite() && self.turn_rate > 0.0) {
            return bad("patrol.turn_rate", self.turn_rate, "finite and > 0");
        }
        Ok(self)
    }
}

/// One piece of the patrol loop.
#[derive(Debug, Clone, Copy)]
enum Piece {
    Drive {
        from: Point2<f64>,
        to: Point2<f64>,
        heading: f64,
    },
    Turn {
        at: Point2<f64>,
        from: f64,
        by: f64,
    },
}

/// The closed patrol loop as timed pieces.
#[derive(Debug, Clone)]
pub(crate) struct Patrol {
    pieces: Vec<(f64, Piece)>,
    period: f64,
}

impl Patrol {
    /// The loop through `waypoints` (closed back to the first), or `None` with fewer than two
    /// distinct points.
    pub(crate) fn new(waypoints: &[Point2<f64>], params: &PatrolParams) -> Option<Self> {
        let mut pts: Vec<Point2<f64>> = Vec::new();
        for &p in waypoints.iter().chain(waypoints.first()) {
            if pts.last() != Some(&p) {
                pts.push(p);
            }
        }
        if pts.len() < 3 {
            // a → b → a at least.
            if pts.len() == 2 {
                pts.push(pts[0]);
            } else {
                return None;
            }
        }
        let headings: Vec<f64> = pts
            .windows(2)
            .map(|w| (w[1] - w[0]).y.atan2((w[1] - w[0]).x))
            .collect();
        let mut pieces = Vec::new();
        for (i, w) in pts.windows(2).enumerate() {
            let heading = headings[i];
            let d = (w[1] - w[0]).norm();
            pieces.push((
                d / params.speed,
                Piece::Drive {
                    from: w[0],
                    to: w[1],
                    heading,
                },
            ));
            let next = headings[(i + 1) % headings.len()];
            let by = wrap_angle(next - heading);
            if by != 0.0 {
                pieces.push((
                    by.abs() / params.turn_rate,
                    Piece::Turn {
                        at: w[1],
                        from: heading,
                        by,
                    },
                ));
            }
        }
        let period = pieces.iter().map(|(d, _)| d).sum();
        Some(Self { pieces, period })
    }

    /// The pose `elapsed` seconds after the patrol started (looping).
    pub(crate) fn pose(&self, elapsed: f64) -> Pose2 {
        let mut tau = if self.period > 0.0 {
            elapsed.rem_euclid(self.period)
        } else {
            0.0
        };
        let last = self.pieces.len().saturating_sub(1);
        for (i, (dur, piece)) in self.pieces.iter().enumerate() {
            if tau <= *dur || i == last {
                let f = if *dur > 0.0 {
                    (tau / dur).clamp(0.0, 1.0)
                } else {
                    1.0
                };
                return match *piece {
                    Piece::Drive { from, to, heading } => {
                        Pose2::new(from.coords + (to - from) * f, heading)
                    }
                    Piece::Turn { at, from, by } => Pose2::new(at.coords, from + by * f),
                };
            }
            tau -= dur;
        }
        Pose2::identity()
    }
}

/// How the wheel odometry drifts. Errors are random walks whose variance grows with the
/// distance driven and the angle turned, so the drift does not depend on the scan rate.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub struct OdometryParams {
    /// Standard deviation of the along-track error per √metre driven, m/√m.
    pub translation_noise: f64,
    /// Standard deviation of the heading error per √radian turned, rad/√rad.
    pub rotation_noise: f64,
    /// Standard deviation of the heading error per √metre driven, rad/√m.
    pub rotation_per_metre: f64,
    /// Systematic heading drift per metre driven, rad/m (an uneven wheel).
    pub heading_bias: f64,
}

impl Default for OdometryParams {
    fn default() -> Self {
        Self {
            translation_noise: 0.01,
            rotation_noise: 0.01,
            rotation_per_metre: 0.004,
            heading_bias: 0.0001,
        }
    }
}

impl OdometryParams {
    /// Perfect odometry.
    pub fn exact() -> Self {
        Self {
            translation_noise: 0.0,
            rotation_noise: 0.0,
            rotation_per_metre: 0.0,
            heading_bias: 0.0,
        }
    }

    /// The parameters if usable.
    ///
    /// # Errors
    /// [`SimError::InvalidParameter`]: noises finite, ≥ 0 and ≤ 10; bias finite with
    /// `|bias| ≤ 10`.
    pub fn check(self) -> Result<Self> {
        for (param, v) in [
            ("odometry.translation_noise", self.translation_noise),
            ("odometry.rotation_noise", self.rotation_noise),
            ("odometry.rotation_per_metre", self.rotation_per_metre),
        ] {
            if !(v.is_finite() && (0.0..=10.0).contains(&v)) {
                return Err(SimError::InvalidParameter(haunts_core::InvalidParameter {
                    name: param,
                    value: v,
                    rule: "must be in [0, 10]",
                }));
            }
        }
        if !(self.heading_bias.is_finite() && self.heading_bias.abs() <= 10.0) {
            return Err(SimError::InvalidParameter(haunts_core::InvalidParameter {
                name: "odometry.heading_bias",
                value: self.heading_bias,
                rule: "must be in [-10, 10]",
            }));
        }
        Ok(self)
    }

    /// The variance of the heading error after driving `distance` metres and turning
    /// `turned` radians (in absolute value) in total, bias excluded.
    pub fn heading_variance(&self, distance: f64, turned: f64) -> f64 {
        self.rotation_noise.powi(2) * turned + self.rotation_per_metre.powi(2) * distance
    }

    /// Odometry poses for the true poses `truth`: the first equals the true pose, each next
    /// one composes the true relative motion with noise drawn from `seed`'s odometry stream
    /// of `day`.
    pub(crate) fn integrate(&self, truth: &[Pose2], seed: u64, day: usize) -> Vec<Pose2> {
        let mut rng =
            Xoshiro256PlusPlus::seed_from_u64(stream_seed(seed, day as u64, Stream::Odometry, 0));
        let mut out = Vec::with_capacity(truth.len());
        let Some(&first) = truth.first() else {
            return out;
        };
        let mut odom = first;
        out.push(odom);
        for w in truth.windows(2) {
            let delta = w[0].inverse() * w[1];
            let t = delta.translation.vector;
            let d = t.norm();
            let turn = delta.rotation.angle();
            let n1: f64 = rng.sample(StandardNormal);
            let n2: f64 = rng.sample(StandardNormal);
            let along = if d > 0.0 {
                t / d * (self.translation_noise * d.sqrt() * n1)
            } else {
                Vector2::zeros()
            };
            let dtheta =
                turn + self.heading_variance(d, turn.abs()).sqrt() * n2 + self.heading_bias * d;
            odom *= Pose2::new(t + along, dtheta);
            out.push(odom);
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn patrol_loops_through_the_waypoints() {
        let w = [
            Point2::new(0.0, 0.0),
            Point2::new(4.0, 0.0),
            Point2::new(4.0, 2.0),
        ];
        let p = Patrol::new(&w, &PatrolParams::default()).unwrap();
        // 4 m at 0.5 m/s: the first waypoint after 8 s, heading 0.
        let a = p.pose(8.0);
        assert_relative_eq!(a.translation.vector, Vector2::new(4.0, 0.0), epsilon = 1e-9);
        let mid = p.pose(4.0);
        assert_relative_eq!(
            mid.translation.vector,
            Vector2::new(2.0, 0.0),
            epsilon = 1e-9
        );
        // Periodic.
        let again = p.pose(4.0 + p.period);
        assert_relative_eq!(
            again.translation.vector,
            mid.translation.vector,
            epsilon = 1e-9
        );
        assert!(Patrol::new(&w[..1], &PatrolParams::default()).is_none());
    }

    #[test]
    fn exact_odometry_is_the_truth() {
        let w = [
            Point2::new(0.0, 0.0),
            Point2::new(4.0, 0.0),
            Point2::new(4.0, 2.0),
        ];
        let p = Patrol::new(&w, &PatrolParams::default()).unwrap();
        let truth: Vec<Pose2> = (0..500).map(|i| p.pose(i as f64 * 0.1)).collect();
        let odom = OdometryParams::exact().integrate(&truth, 1, 0);
        for (a, b) in truth.iter().zip(&odom) {
            assert_relative_eq!(a.translation.vector, b.translation.vector, epsilon = 1e-9);
        }
        assert!(
            OdometryParams {
                rotation_noise: -1.0,
                ..OdometryParams::default()
            }
            .check()
            .is_err()
        );
    }
}
