//! The dummy-target filter of seed 002 (Algorithm 1): drop trajectories too short, too
//! compact or too slow to be people (tracks on pillars, walls, trees).
//!
//! A trajectory is kept only when it has at least α samples, its first and last positions
//! are at least β metres apart, and its mean speed is at least γ m/s (seed 002, Algorithm 1,
//! line 9). The seed gives no values for α, β, γ ("heuristically set"); the defaults of
//! [`DummyFilterParams`] are chosen for people seen by a 2-D laser at 7.5–15 Hz.

use crate::{Result, TrackingError, Trajectory};

/// How [`filter_dummies`] measures a trajectory's mean speed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum SpeedMeasure {
    /// Path length (sum of the distances between consecutive samples) / duration (the
    /// default). Noise on a standing target adds path length, so γ must be above what
    /// position jitter alone produces.
    #[default]
    PathLength,
    /// Seed 002, Algorithm 1, lines 7–8: the norm of the mean velocity. With velocities by
    /// finite differences weighted by their time steps this is |last − first| / duration,
    /// which ignores jitter but calls a person who walks away and back slow.
    NetDisplacement,
}

/// Thresholds of the dummy-target filter (seed 002, Algorithm 1: α, β, γ).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub struct DummyFilterParams {
    /// α: the fewest samples a kept trajectory has. Default 10 (about 1 s of tracking at
    /// 7.5–10 Hz: shorter tracks are mostly spurious).
    pub min_samples: usize,
    /// β: the least distance between the first and last positions, metres. Default 1.0 m
    /// (two strides; a standing person's track drifts by tens of centimetres).
    pub min_displacement: f64,
    /// γ: the least mean speed, m/s. Default 0.3 m/s (slow indoor walking is ≈ 0.5–1 m/s;
    /// jitter of a few centimetres per scan on a static object stays below this).
    pub min_mean_speed: f64,
    /// How mean speed is measured. Default [`SpeedMeasure::PathLength`].
    pub speed: SpeedMeasure,
}

impl Default for DummyFilterParams {
    fn default() -> Self {
        Self {
            min_samples: 10,
            min_displacement: 1.0,
            min_mean_speed: 0.3,
            speed: SpeedMeasure::PathLength,
        }
    }
}

impl DummyFilterParams {
    /// Sets α, the fewest samples.
    pub fn with_min_samples(mut self, samples: usize) -> Self {
        self.min_samples = samples;
        self
    }

    /// Sets β, the least first-to-last displacement, metres.
    pub fn with_min_displacement(mut self, metres: f64) -> Self {
        self.min_displacement = metres;
        self
    }

    /// Sets γ, the least mean speed, m/s.
    pub fn with_min_mean_speed(mut self, metres_per_second: f64) -> Self {
        self.min_mean_speed = metres_per_second;
        self
    }

    /// Sets how mean speed is measured.
    pub fn with_speed(mut self, speed: SpeedMeasure) -> Self {
        self.speed = speed;
        self
    }

    /// The parameters, after checking that β and γ are finite and ≥ 0.
    ///
    /// # Errors
    /// [`TrackingError::InvalidParameter`] naming `min_displacement` or `min_mean_speed`.
    pub fn check(self) -> Result<Self> {
        for (name, value) in [
            ("min_displacement", self.min_displacement),
            ("min_mean_speed", self.min_mean_speed),
        ] {
            haunts_core::non_negative(name, value)?;
        }
        Ok(self)
    }
}

/// Why a trajectory was dropped.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum DropReason {
    /// Fewer samples than α.
    TooShort {
        /// Its number of samples.
        samples: usize,
    },
    /// First and last positions closer than β.
    TooLittleDisplacement {
        /// Their distance, metres (0 for an empty trajectory).
        metres: f64,
    },
    /// Mean speed below γ.
    TooSlow {
        /// Its mean speed, m/s (0 when the trajectory lasts no time).
        mean_speed: f64,
    },
}

/// A dropped trajectory and every rule it failed.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Dropped {
    /// The trajectory, unchanged.
    pub trajectory: Trajectory,
    /// The failed rules, in the order samples, displacement, speed (at least one).
    pub reasons: Vec<DropReason>,
}

/// The outcome of [`filter_dummies`].
#[derive(Debug, Clone, PartialEq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct DummyReport {
    /// The trajectories that passed, in input order.
    pub kept: Vec<Trajectory>,
    /// The others, in input order, with their reasons.
    pub dropped: Vec<Dropped>,
}

/// The quantities Algorithm 1 tests, for one trajectory.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct TrajectoryStats {
    /// Number of samples (S).
    pub samples: usize,
    /// Distance between the first and last positions, metres (0 when empty).
    pub displacement: f64,
    /// Sum of the distances between consecutive samples, metres.
    pub path_length: f64,
    /// Last time − first time, seconds (0 when fewer than two samples).
    pub duration: f64,
}

impl TrajectoryStats {
    /// The statistics of a trajectory, after checking its samples.
    ///
    /// # Errors
    /// [`TrackingError::InvalidTrajectory`] when a time or position is not finite, or a time
    /// is earlier than the one before it.
    pub fn of(trajectory: &Trajectory) -> Result<Self> {
        let invalid = |sample, rule| TrackingError::InvalidTrajectory {
            id: trajectory.id,
            sample,
            rule,
        };
        let samples = &trajectory.samples;
        for (i, (t, p)) in samples.iter().enumerate() {
            if !(t.is_finite() && p.x.is_finite() && p.y.is_finite()) {
                return Err(invalid(i, "time or position is not finite"));
            }
            if i > 0 && *t < samples[i - 1].0 {
                return Err(invalid(i, "time is earlier than the sample before"));
            }
        }
        let (displacement, duration) = match (samples.first(), samples.last()) {
            (Some(first), Some(last)) => ((last.1 - first.1).norm(), last.0 - first.0),
            _ => (0.0, 0.0),
        };
        let path_length = samples.windows(2).map(|w| (w[1].1 - w[0].1).norm()).sum();
        Ok(Self {
            samples: samples.len(),
            displacement,
            path_length,
            duration,
        })
    }

    /// Mean speed, m/s, measured as asked; 0 when the trajectory lasts no time.
    pub fn mean_speed(&self, measure: SpeedMeasure) -> f64 {
        if self.duration <= 0.0 {
            return 0.0;
        }
        let distance = match measure {
            SpeedMeasure::PathLength => self.path_length,
            SpeedMeasure::NetDisplacement => self.displacement,
        };
        distance / self.duration
    }
}

/// Splits trajectories (in world coordinates) into the kept and the dropped dummy targets
/// (seed 002, Algorithm 1). A trajectory is kept when `samples ≥ α`, `displacement ≥ β` and
/// `mean speed ≥ γ` (a value equal to its threshold passes); otherwise it is dropped with
/// every failed rule. A trajectory that lasts no time has mean speed 0.
///
/// # Errors
/// - [`TrackingError::InvalidParameter`] for bad parameters.
/// - [`TrackingError::InvalidTrajectory`] for a sample with a non-finite time or position,
///   or times that go back.
///
/// # Complexity
/// `O(total samples)`.
///
/// # Example
/// ```
/// use haunts_tracking::Trajectory;
/// use haunts_tracking::track::dummy::{DropReason, DummyFilterParams, filter_dummies};
/// use nalgebra::Point2;
///
/// // A walker: 2 m in 2 s. A pillar: 10 samples jittering in place.
/// let walker = Trajectory { id: 1, samples: (0..=20).map(|k| (k as f64 * 0.1, Point2::new(k as f64 * 0.1, 0.0))).collect() };
/// let pillar = Trajectory { id: 2, samples: (0..10).map(|k| (k as f64 * 0.1, Point2::new(3.0, 0.01 * (k % 2) as f64))).collect() };
/// let report = filter_dummies(vec![walker, pillar], &DummyFilterParams::default())?;
/// assert_eq!(report.kept.iter().map(|t| t.id).collect::<Vec<_>>(), vec![1]);
/// assert_eq!(report.dropped[0].trajectory.id, 2);
/// assert!(matches!(report.dropped[0].reasons[0], DropReason::TooLittleDisplacement { .. }));
/// # Ok::<(), haunts_tracking::TrackingError>(())
/// ```
pub fn filter_dummies(
    trajectories: Vec<Trajectory>,
    params: &DummyFilterParams,
) -> Result<DummyReport> {
    let params = params.check()?;
    let mut report = DummyReport::default();
    for trajectory in trajectories {
        let stats = TrajectoryStats::of(&trajectory)?;
        let mean_speed = stats.mean_speed(params.speed);
        let mut reasons = Vec::new();
        if stats.samples < params.min_samples {
            reasons.push(DropReason::TooShort {
                samples: stats.samples,
            });
        }
        if stats.displacement < params.min_displacement {
            reasons.push(DropReason::TooLittleDisplacement {
                metres: stats.displacement,
            });
        }
        if mean_speed < params.min_mean_speed {
            reasons.push(DropReason::TooSlow { mean_speed });
        }
        if reasons.is_empty() {
            report.kept.push(trajectory);
        } else {
            report.dropped.push(Dropped {
                trajectory,
                reasons,
            });
        }
    }
    Ok(report)
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use approx::assert_relative_eq;
    use nalgebra::Point2;

    use super::*;

    /// A trajectory through `points` at one sample per `dt` seconds.
    fn traj(id: u64, dt: f64, points: &[(f64, f64)]) -> Trajectory {
        Trajectory {
            id,
            samples: points
                .iter()
                .enumerate()
                .map(|(k, &(x, y))| (k as f64 * dt, Point2::new(x, y)))
                .collect(),
        }
    }

    /// `n` samples along x, `step` metres apart, `dt` seconds apart.
    fn line(id: u64, n: usize, step: f64, dt: f64) -> Trajectory {
        let points: Vec<(f64, f64)> = (0..n).map(|k| (k as f64 * step, 0.0)).collect();
        traj(id, dt, &points)
    }

    fn params() -> DummyFilterParams {
        DummyFilterParams::default()
            .with_min_samples(5)
            .with_min_displacement(1.0)
            .with_min_mean_speed(0.5)
    }

    #[test]
    fn each_rule_passes_at_its_boundary_and_fails_just_below() {
        // 5 samples, 0.25 m and 0.5 s apart: displacement 1.0 m, speed 0.5 m/s — all equal.
        let report = filter_dummies(vec![line(1, 5, 0.25, 0.5)], &params()).unwrap();
        assert_eq!(report.kept.len(), 1);

        // One sample too few, far and fast enough.
        let short = line(2, 4, 0.5, 0.5);
        let report = filter_dummies(vec![short], &params()).unwrap();
        assert_eq!(
            report.dropped[0].reasons,
            vec![DropReason::TooShort { samples: 4 }]
        );

        // Displacement a hair under 1 m (speed still ≥ 0.5 m/s).
        let compact = line(3, 5, 0.2499, 0.4);
        let report = filter_dummies(vec![compact], &params()).unwrap();
        let [DropReason::TooLittleDisplacement { metres }] = report.dropped[0].reasons[..] else {
            panic!("{:?}", report.dropped[0].reasons);
        };
        assert_relative_eq!(metres, 0.9996, epsilon = 1e-12);

        // Speed a hair under 0.5 m/s.
        let slow = line(4, 5, 0.25, 0.5001);
        let report = filter_dummies(vec![slow], &params()).unwrap();
        let [DropReason::TooSlow { mean_speed }] = report.dropped[0].reasons[..] else {
            panic!("{:?}", report.dropped[0].reasons);
        };
        assert_relative_eq!(mean_speed, 1.0 / 2.0004, epsilon = 1e-12);
    }

    #[test]
    fn a_pillar_fails_every_rule_and_keeps_its_order() {
        let pillar = traj(9, 0.1, &[(3.0, 0.0), (3.01, 0.0), (3.0, 0.0)]);
        let walker = line(1, 10, 0.15, 0.1);
        let other = line(5, 10, 0.15, 0.1);
        let report = filter_dummies(vec![walker, pillar, other], &params()).unwrap();
        assert_eq!(
            report.kept.iter().map(|t| t.id).collect::<Vec<_>>(),
            vec![1, 5]
        );
        let reasons = &report.dropped[0].reasons;
        assert_eq!(reasons.len(), 3);
        assert_eq!(reasons[0], DropReason::TooShort { samples: 3 });
        assert_eq!(
            reasons[1],
            DropReason::TooLittleDisplacement { metres: 0.0 }
        );
        // Path 0.02 m in 0.2 s.
        let DropReason::TooSlow { mean_speed } = reasons[2] else {
            panic!("{reasons:?}");
        };
        assert_relative_eq!(mean_speed, 0.1, epsilon = 1e-12);
    }

    #[test]
    fn zero_duration_and_empty_trajectories_are_slow() {
        let frozen = Trajectory {
            id: 1,
            samples: vec![(1.0, Point2::new(0.0, 0.0)), (1.0, Point2::new(5.0, 0.0))],
        };
        let report = filter_dummies(
            vec![
                frozen,
                Trajectory {
                    id: 2,
                    samples: vec![],
                },
            ],
            &params().with_min_samples(0),
        )
        .unwrap();
        assert!(report.kept.is_empty());
        assert_eq!(
            report.dropped[0].reasons,
            vec![DropReason::TooSlow { mean_speed: 0.0 }]
        );
        assert_eq!(
            report.dropped[1].reasons,
            vec![
                DropReason::TooLittleDisplacement { metres: 0.0 },
                DropReason::TooSlow { mean_speed: 0.0 }
            ]
        );
    }

    #[test]
    fn path_length_and_net_displacement_speeds_differ_on_a_round_trip() {
        // Out 2 m and back 1 m in 3 s: path 3 m (1 m/s), net 1 m (1/3 m/s).
        let there_and_back = traj(
            1,
            0.5,
            &[
                (0.0, 0.0),
                (1.0, 0.0),
                (2.0, 0.0),
                (1.5, 0.0),
                (1.0, 0.0),
                (1.0, 0.0),
                (1.0, 0.0),
            ],
        );
        let stats = TrajectoryStats::of(&there_and_back).unwrap();
        assert_relative_eq!(stats.path_length, 3.0);
        assert_relative_eq!(stats.duration, 3.0);
        assert_relative_eq!(stats.mean_speed(SpeedMeasure::PathLength), 1.0);
        assert_relative_eq!(stats.mean_speed(SpeedMeasure::NetDisplacement), 1.0 / 3.0);
        let by_path = filter_dummies(vec![there_and_back.clone()], &params()).unwrap();
        assert_eq!(by_path.kept.len(), 1);
        let by_net = filter_dummies(
            vec![there_and_back],
            &params().with_speed(SpeedMeasure::NetDisplacement),
        )
        .unwrap();
        assert!(matches!(
            by_net.dropped[0].reasons[..],
            [DropReason::TooSlow { .. }]
        ));
    }

    #[test]
    fn bad_parameters_and_samples_are_errors() {
        for (p, name) in [
            (params().with_min_displacement(-1.0), "min_displacement"),
            (params().with_min_displacement(f64::NAN), "min_displacement"),
            (
                params().with_min_mean_speed(f64::INFINITY),
                "min_mean_speed",
            ),
        ] {
            assert!(matches!(
                filter_dummies(vec![], &p),
                Err(TrackingError::InvalidParameter(haunts_core::InvalidParameter { name: n, .. })) if n == name
            ));
        }
        let nan = traj(7, 0.1, &[(0.0, 0.0), (f64::NAN, 0.0)]);
        assert!(matches!(
            filter_dummies(vec![nan], &params()),
            Err(TrackingError::InvalidTrajectory {
                id: 7,
                sample: 1,
                ..
            })
        ));
        let mut backwards = line(8, 3, 1.0, 1.0);
        backwards.samples[2].0 = 0.5;
        assert!(matches!(
            filter_dummies(vec![backwards], &params()),
            Err(TrackingError::InvalidTrajectory {
                id: 8,
                sample: 2,
                ..
            })
        ));
    }
}
