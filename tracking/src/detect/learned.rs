//! The learned leg detector: `leg_tracker`'s clusters, scored by a random forest.

use haunts_occupancy::LaserScan;
use nalgebra::Point2;

use super::{Detection, Detector, pair_legs, rule};
use crate::Result;
use crate::detect::cluster::{Cluster, ClusterParams, clusters};
use crate::detect::features::cluster_features;
use crate::detect::forest::LegForest;

/// Parameters of the [`ForestDetector`].
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub struct ForestDetectorParams {
    /// The clustering (the one the forest was trained on: `leg_tracker`'s by default).
    pub cluster: ClusterParams,
    /// A cluster is a leg when its probability reaches this; `None`: the forest's own
    /// operating point ([`LegForest::threshold`], chosen by cross-validation on its training
    /// set).
    pub min_probability: Option<f64>,
    /// Clusters farther from the sensor than this are ignored, metres.
    pub max_range: f64,
    /// The leg's centre lies this far behind its points' centroid along the beam, metres.
    pub leg_radius: f64,
    /// Legs whose centres are closer than this are paired into one person, metres.
    pub max_leg_separation: f64,
    /// Standard deviation of a leg pair's position, metres.
    pub person_std: f64,
    /// Whether an unpaired leg also yields a person candidate.
    pub single_legs: bool,
    /// Standard deviation of a single leg's candidate, metres.
    pub single_leg_std: f64,
}

impl Default for ForestDetectorParams {
    /// `leg_tracker`'s clustering; legs at the forest's operating point within 10 m; the
    /// geometric detector's pairing (5 cm leg radius, pairs up to 0.7 m apart with σ 0.1
    /// m, single legs kept with σ 0.2 m).
    fn default() -> Self {
        Self {
            cluster: ClusterParams::default(),
            min_probability: None,
            max_range: 10.0,
            leg_radius: 0.05,
            max_leg_separation: 0.7,
            person_std: 0.1,
            single_legs: true,
            single_leg_std: 0.2,
        }
    }
}

impl ForestDetectorParams {
    /// Sets [`ForestDetectorParams::cluster`].
    pub fn with_cluster(mut self, v: ClusterParams) -> Self {
        self.cluster = v;
        self
    }
    /// Sets [`ForestDetectorParams::min_probability`].
    pub fn with_min_probability(mut self, v: Option<f64>) -> Self {
        self.min_probability = v;
        self
    }
    /// Sets [`ForestDetectorParams::max_range`].
    pub fn with_max_range(mut self, v: f64) -> Self {
        self.max_range = v;
        self
    }
    /// Sets [`ForestDetectorParams::leg_radius`].
    pub fn with_leg_radius(mut self, v: f64) -> Self {
        self.leg_radius = v;
        self
    }
    /// Sets [`ForestDetectorParams::max_leg_separation`].
    pub fn with_max_leg_separation(mut self, v: f64) -> Self {
        self.max_leg_separation = v;
        self
    }
    /// Sets [`ForestDetectorParams::person_std`].
    pub fn with_person_std(mut self, v: f64) -> Self {
        self.person_std = v;
        self
    }
    /// Sets [`ForestDetectorParams::single_legs`].
    pub fn with_single_legs(mut self, v: bool) -> Self {
        self.single_legs = v;
        self
    }
    /// Sets [`ForestDetectorParams::single_leg_std`].
    pub fn with_single_leg_std(mut self, v: f64) -> Self {
        self.single_leg_std = v;
        self
    }

    /// The parameters, if every rule holds.
    ///
    /// # Errors
    /// [`crate::TrackingError::InvalidParameter`] naming the clustering's parameter,
    /// `min_probability` (in `[0, 1]` when given), `leg_radius` (finite and ≥ 0), or
    /// `max_range`, `max_leg_separation`, `person_std`, `single_leg_std` (finite and > 0).
    pub fn check(self) -> Result<Self> {
        self.cluster.check()?;
        let m = self.min_probability.unwrap_or(0.0);
        rule(
            (0.0..=1.0).contains(&m),
            "min_probability",
            m,
            "must be in [0, 1] when given",
        )?;
        rule(
            self.leg_radius.is_finite() && self.leg_radius >= 0.0,
            "leg_radius",
            self.leg_radius,
            "must be finite and >= 0",
        )?;
        for (name, v) in [
            ("max_range", self.max_range),
            ("max_leg_separation", self.max_leg_separation),
            ("person_std", self.person_std),
            ("single_leg_std", self.single_leg_std),
        ] {
            haunts_core::positive(name, v)?;
        }
        Ok(self)
    }
}

/// A cluster with the forest's leg probability.
#[derive(Debug, Clone, PartialEq)]
pub struct ScoredCluster {
    /// The cluster.
    pub cluster: Cluster,
    /// Its centroid, sensor frame, metres.
    pub centroid: Point2<f64>,
    /// The forest's leg probability.
    pub probability: f64,
}

/// The learned leg detector (`leg_tracker`'s, with a forest of our own training):
///
/// 1. cluster the scan as `leg_tracker` does ([`crate::detect::clusters`]);
/// 2. give every cluster within `max_range` the forest's leg probability over its
///    [`crate::detect::features`] ([`ForestDetector::scored`]);
/// 3. clusters whose probability reaches `min_probability` (by default the forest's
///    operating point) are legs, centred `leg_radius` behind their centroid;
/// 4. legs are paired into people as the geometric detector pairs them; a pair's
///    confidence is the mean of its legs' probabilities, a single leg's its probability.
///
/// The trackers' confidence rule (`confirm_mean_confidence` of
/// [`crate::track::kalman::KalmanParams`] and [`crate::track::particle::ParticleParams`]) averages these
/// along a track.
///
/// # Complexity
/// O(b) in the beams for the clustering, plus O(n log n + Σ depth) per cluster of `n`
/// points, plus O(l² log l) to pair `l` legs.
///
/// # Example
/// ```
/// use haunts_occupancy::LaserScan;
/// use haunts_tracking::detect::{Detector, ForestDetector};
///
/// let detector = ForestDetector::shipped()?;
/// // An empty room seen as a circle of wall 3 m away: no leg there.
/// let scan = LaserScan::new(0.0, -2.356, 0.00614, 0.03, 11.0, vec![3.0; 768], vec![])?;
/// assert!(detector.detect(&scan)?.is_empty());
/// assert!(detector.scored(&scan)?.iter().all(|c| c.probability < 0.25));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct ForestDetector {
    forest: LegForest,
    params: ForestDetectorParams,
    min_probability: f64,
}

impl ForestDetector {
    /// A detector with `forest` and checked parameters.
    ///
    /// # Errors
    /// As [`ForestDetectorParams::check`].
    pub fn new(forest: LegForest, params: ForestDetectorParams) -> Result<Self> {
        let params = params.check()?;
        let min_probability = params.min_probability.unwrap_or(forest.threshold());
        Ok(Self {
            forest,
            params,
            min_probability,
        })
    }

    /// The shipped forest ([`LegForest::shipped`]) with the default parameters.
    ///
    /// # Errors
    /// As [`LegForest::shipped`].
    pub fn shipped() -> Result<Self> {
        Self::new(LegForest::shipped()?, ForestDetectorParams::default())
    }

    /// The parameters.
    pub fn params(&self) -> &ForestDetectorParams {
        &self.params
    }

    /// The forest.
    pub fn forest(&self) -> &LegForest {
        &self.forest
    }

    /// The probability a cluster needs to be a leg.
    pub fn min_probability(&self) -> f64 {
        self.min_probability
    }

    /// Every cluster of `scan` within `max_range`, with its leg probability (steps 1–2).
    ///
    /// # Errors
    /// None in practice (the parameters are checked on construction).
    pub fn scored(&self, scan: &LaserScan) -> Result<Vec<ScoredCluster>> {
        let found = clusters(scan, &self.params.cluster)?;
        Ok(found
            .into_iter()
            .filter_map(|cluster| {
                let centroid = cluster.centroid();
                (centroid.coords.norm() <= self.params.max_range).then(|| ScoredCluster {
                    probability: self.forest.probability(&cluster_features(scan, &cluster)),
                    centroid,
                    cluster,
                })
            })
            .collect())
    }

    /// The legs of `scan` (step 3): centre and probability, in scan order.
    ///
    /// # Errors
    /// As [`ForestDetector::scored`].
    pub fn legs(&self, scan: &LaserScan) -> Result<Vec<(Point2<f64>, f64)>> {
        let r = self.params.leg_radius;
        Ok(self
            .scored(scan)?
            .into_iter()
            .filter(|c| c.probability >= self.min_probability)
            .map(|c| {
                let d = c.centroid.coords.norm();
                let centre = if d > 0.0 {
                    c.centroid * (1.0 + r / d)
                } else {
                    c.centroid
                };
                (centre, c.probability)
            })
            .collect())
    }

    fn pair(&self, legs: &[(Point2<f64>, f64)]) -> Vec<Detection> {
        let p = &self.params;
        let single = p.single_legs.then_some((p.single_leg_std, 1.0));
        pair_legs(legs, p.max_leg_separation, p.person_std, single)
    }
}

impl Detector for ForestDetector {
    fn detect(&self, scan: &LaserScan) -> Result<Vec<Detection>> {
        Ok(self.pair(&self.legs(scan)?))
    }

    fn detect_where(
        &self,
        scan: &LaserScan,
        keep: &dyn Fn(&Point2<f64>) -> bool,
    ) -> Result<Vec<Detection>> {
        let mut legs = self.legs(scan)?;
        legs.retain(|leg| keep(&leg.0));
        Ok(self.pair(&legs))
    }

    fn candidates(&self, scan: &LaserScan) -> Result<Vec<Point2<f64>>> {
        Ok(self.legs(scan)?.iter().map(|leg| leg.0).collect())
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;

    #[test]
    fn bad_parameters_are_named() {
        let d = ForestDetectorParams::default();
        for (p, name) in [
            (d.with_min_probability(Some(1.5)), "min_probability"),
            (d.with_leg_radius(-1.0), "leg_radius"),
            (d.with_max_range(0.0), "max_range"),
            (d.with_person_std(f64::NAN), "person_std"),
            (
                d.with_cluster(ClusterParams::default().with_min_points(0)),
                "min_points",
            ),
        ] {
            assert!(matches!(
                p.check(),
                Err(crate::TrackingError::InvalidParameter(haunts_core::InvalidParameter { name: n, .. })) if n == name
            ));
        }
    }

    #[test]
    fn pairs_carry_the_mean_probability_and_singles_their_own() {
        let det = ForestDetector::shipped().unwrap();
        let legs = [
            (Point2::new(2.0, 0.0), 0.8),
            (Point2::new(2.0, 0.3), 0.4),
            (Point2::new(5.0, 0.0), 0.3),
        ];
        let people = det.pair(&legs);
        assert_eq!(people.len(), 2);
        approx::assert_relative_eq!(people[0].confidence, 0.6);
        approx::assert_relative_eq!(people[0].position, Point2::new(2.0, 0.15));
        approx::assert_relative_eq!(people[1].confidence, 0.3);
    }
}
