//! Detectors turn one laser scan into person detections in the sensor frame; the seed-000 leg
//! detector is the one for 2-D laser scans taken at leg height.
//!
//! A [`Detection`] is a position with a covariance and a confidence. A [`Detector`] maps a
//! [`LaserScan`] to detections; [`LegDetector`] is the seed-000 clustering (split at gaps,
//! keep short clusters that are not lines, pair legs into people) and [`FixedDetector`] a
//! trivial one for tests.

use haunts_occupancy::{LaserScan, Pose2, Reading};
use nalgebra::{Matrix2, Point2, Vector2};

use crate::{Result, TrackingError};

mod cluster;
pub mod features;
pub mod forest;
mod learned;
pub mod recurring;
pub mod static_map;
#[cfg(feature = "train")]
pub mod training;
pub use cluster::{Cluster, ClusterParams, clusters};
pub use features::cluster_features;
pub use forest::LegForest;
#[cfg(feature = "train")]
pub use forest::train::{ForestParams, train_forest};
pub use learned::{ForestDetector, ForestDetectorParams, ScoredCluster};
pub use recurring::{RecurringObjects, RecurringParams};
pub use static_map::{StaticMap, StaticMapParams};
#[cfg(feature = "train")]
pub use training::{LabelledScan, LegLabel, ScanLabels};

/// One person candidate: where, how uncertain, how sure.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Detection {
    /// Position, metres, in the frame of the scan it came from (or the frame it was moved to
    /// with [`Detection::transformed`]).
    pub position: Point2<f64>,
    /// Covariance of the position, m²; symmetric positive definite.
    pub covariance: Matrix2<f64>,
    /// How sure the detector is, ≥ 0 (1 for a leg pair, less for a single leg).
    pub confidence: f64,
}

impl Detection {
    /// A detection with an isotropic covariance `std² · I` and confidence 1.
    pub fn isotropic(position: Point2<f64>, std: f64) -> Self {
        Self {
            position,
            covariance: Matrix2::identity() * (std * std),
            confidence: 1.0,
        }
    }

    /// The same detection seen from another frame: `pose` maps the current frame into the
    /// new one (position `pose · p`, covariance `R Σ Rᵀ`).
    pub fn transformed(&self, pose: &Pose2) -> Self {
        let r = pose.rotation.to_rotation_matrix();
        let r = r.matrix();
        Self {
            position: pose * self.position,
            covariance: r * self.covariance * r.transpose(),
            confidence: self.confidence,
        }
    }

    /// The covariance after checking it: symmetrised, finite and positive definite.
    ///
    /// # Errors
    /// [`TrackingError::InvalidDetection`] for a non-finite position or a negative or
    /// non-finite confidence; [`TrackingError::SingularCovariance`] for a covariance that is
    /// not finite or not positive definite (its determinant must exceed `1e-12` times its
    /// squared trace). `index` is reported in the error.
    pub fn checked_covariance(&self, index: usize) -> Result<Matrix2<f64>> {
        let finite = self.position.coords.iter().all(|v| v.is_finite());
        if !(finite && self.confidence.is_finite() && self.confidence >= 0.0) {
            return Err(TrackingError::InvalidDetection { index });
        }
        symmetric_positive_definite(&self.covariance)
            .ok_or(TrackingError::SingularCovariance { index })
    }
}

/// `(Σ + Σᵀ)/2` if it is finite and positive definite (determinant above `1e-12 · trace²`).
pub(crate) fn symmetric_positive_definite(c: &Matrix2<f64>) -> Option<Matrix2<f64>> {
    let s = (c + c.transpose()) * 0.5;
    if !s.iter().all(|v| v.is_finite()) {
        return None;
    }
    let trace = s[(0, 0)] + s[(1, 1)];
    let det = s[(0, 0)] * s[(1, 1)] - s[(0, 1)] * s[(1, 0)];
    (s[(0, 0)] > 0.0 && s[(1, 1)] > 0.0 && det > 1e-12 * trace * trace).then_some(s)
}

/// Checks every detection of a slice (see [`Detection::checked_covariance`]).
///
/// # Errors
/// The first bad detection's error, with its index.
pub(crate) fn check_detections(detections: &[Detection]) -> Result<()> {
    for (i, d) in detections.iter().enumerate() {
        d.checked_covariance(i)?;
    }
    Ok(())
}

/// Turns a scan into person detections in the scan's frame.
///
/// Object safe and `Send + Sync`, so detectors can be boxed and shared across threads.
#[auto_impl::auto_impl(&, &mut, Box, Arc)]
pub trait Detector: Send + Sync {
    /// The detections in `scan`, in the sensor frame.
    ///
    /// # Errors
    /// Implementation specific; the detectors of this crate never fail on a scan that
    /// [`LaserScan::check`] accepts.
    fn detect(&self, scan: &LaserScan) -> Result<Vec<Detection>>;

    /// The detections in `scan` built only from evidence at sensor-frame points that `keep`
    /// accepts: how a map of static objects ([`crate::detect::static_map`]) removes posts
    /// and table legs before they are paired with anything. The default keeps the
    /// detections whose position `keep` accepts; [`LegDetector`] filters its legs before
    /// pairing them.
    ///
    /// # Errors
    /// As [`Detector::detect`].
    fn detect_where(
        &self,
        scan: &LaserScan,
        keep: &dyn Fn(&Point2<f64>) -> bool,
    ) -> Result<Vec<Detection>> {
        let mut found = self.detect(scan)?;
        found.retain(|d| keep(&d.position));
        Ok(found)
    }

    /// The positions that [`Detector::detect_where`]'s `keep` decides on, in the sensor
    /// frame: by default the detections' positions; [`LegDetector`]'s legs.
    ///
    /// # Errors
    /// As [`Detector::detect`].
    fn candidates(&self, scan: &LaserScan) -> Result<Vec<Point2<f64>>> {
        Ok(self.detect(scan)?.iter().map(|d| d.position).collect())
    }
}

/// The trivial detector: the same detections for every scan (for tests and replay).
#[derive(Debug, Clone, Default, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct FixedDetector {
    /// What every call returns.
    pub detections: Vec<Detection>,
}

impl Detector for FixedDetector {
    fn detect(&self, _scan: &LaserScan) -> Result<Vec<Detection>> {
        Ok(self.detections.clone())
    }
}

/// Parameters of the [`LegDetector`] (seed 000, section IV-A-1).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub struct LegDetectorParams {
    /// Consecutive hits farther apart than this start a new cluster, metres (seed: 0.1).
    pub cluster_gap: f64,
    /// Clusters with fewer hits are dropped (three points are the fewest with a shape).
    pub min_points: usize,
    /// Longest leg cluster, metres, measured as the distance from its first to its last
    /// point (the chord the laser sees). The seed says 0.5; two legs side by side are at
    /// most about 0.3 m wide, and on the `leg_tracker` bag the longer clusters are wall
    /// pieces and furniture (0.3 is the default).
    pub max_cluster_length: f64,
    /// A cluster whose smaller/larger eigenvalue ratio of the point covariance is below this
    /// is a straight line (a piece of wall) and dropped. 0 (the default) keeps every
    /// cluster: a leg seen from 3–7 m gives 3–5 hits over 5–10 cm, whose curvature (about
    /// 1 cm) is the size of the range noise, so the test cannot tell it from a line — on the
    /// `leg_tracker` bag a threshold of 0.01 dropped the cluster nearest to 33 of the 133
    /// annotated people, while `max_cluster_length` already drops the long wall pieces.
    pub min_eigenvalue_ratio: f64,
    /// A cluster longer than this, metres, is wider than one leg (about 12 cm across) ...
    pub straight_length: f64,
    /// ... and if its eigenvalue ratio is also below this, it is a straight piece of a
    /// surface — a wall or the side of a sofa or cabinet seen at a grazing angle, where
    /// the hits are too far apart to join into one cluster — and dropped. Two legs side by
    /// side also make a long cluster, but not a straight one. Short clusters are left to
    /// [`LegDetectorParams::min_eigenvalue_ratio`] (a leg seen from afar gives a few hits
    /// whose curvature is within the range noise). 0 turns the test off.
    pub straight_eigenvalue_ratio: f64,
    /// The beams just beside a leg cluster must reach at least this much farther than its
    /// ends, metres (or return nothing, or be invalid): a leg stands in front of its
    /// background, while a piece of wall cut out by a gap has neighbours at its own range.
    pub min_background_gap: f64,
    /// Legs whose centres are closer than this are paired into one person, metres: about
    /// the longest stride seen at leg height.
    pub max_leg_separation: f64,
    /// The leg's centre lies this far behind the centroid of its visible points along the
    /// beam, metres (about a leg's radius; 0 keeps the centroid).
    pub leg_radius: f64,
    /// Clusters farther from the sensor than this are ignored, metres.
    pub max_range: f64,
    /// Standard deviation of a leg pair's position, metres: the fixed covariance is
    /// `person_std² · I`.
    pub person_std: f64,
    /// Whether an unpaired leg also yields a person candidate (people are often half
    /// occluded).
    pub single_legs: bool,
    /// Standard deviation of a single leg's candidate, metres: the person's centre may be a
    /// half-stride away from the leg seen.
    pub single_leg_std: f64,
    /// Confidence of a single leg's candidate (a pair has confidence 1).
    pub single_leg_confidence: f64,
}

impl Default for LegDetectorParams {
    /// The seed's 0.1 m gap; clusters of at least 3 hits shorter than 30 cm, with no line
    /// test for clusters up to 13 cm (see [`LegDetectorParams::min_eigenvalue_ratio`]) and
    /// longer ones dropped when their eigenvalue ratio is below 0.04; legs of about 5 cm
    /// radius, paired up to 0.7 m apart (a stride); candidates within 10 m; single legs
    /// kept at confidence 0.5.
    fn default() -> Self {
        Self {
            cluster_gap: 0.1,
            min_points: 3,
            max_cluster_length: 0.3,
            min_eigenvalue_ratio: 0.0,
            straight_length: 0.13,
            straight_eigenvalue_ratio: 0.04,
            min_background_gap: 0.0,
            max_leg_separation: 0.7,
            leg_radius: 0.05,
            max_range: 10.0,
            person_std: 0.1,
            single_legs: true,
            single_leg_std: 0.2,
            single_leg_confidence: 0.5,
        }
    }
}

/// Returns an error unless `ok`.
pub(crate) fn rule(ok: bool, name: &'static str, value: f64, rule: &'static str) -> Result<()> {
    if ok {
        Ok(())
    } else {
        Err(TrackingError::InvalidParameter(
            haunts_core::InvalidParameter { name, value, rule },
        ))
    }
}

impl LegDetectorParams {
    /// Sets [`LegDetectorParams::cluster_gap`].
    pub fn with_cluster_gap(mut self, v: f64) -> Self {
        self.cluster_gap = v;
        self
    }
    /// Sets [`LegDetectorParams::min_points`].
    pub fn with_min_points(mut self, v: usize) -> Self {
        self.min_points = v;
        self
    }
    /// Sets [`LegDetectorParams::max_cluster_length`].
    pub fn with_max_cluster_length(mut self, v: f64) -> Self {
        self.max_cluster_length = v;
        self
    }
    /// Sets [`LegDetectorParams::min_eigenvalue_ratio`].
    pub fn with_min_eigenvalue_ratio(mut self, v: f64) -> Self {
        self.min_eigenvalue_ratio = v;
        self
    }
    /// Sets [`LegDetectorParams::straight_length`].
    pub fn with_straight_length(mut self, v: f64) -> Self {
        self.straight_length = v;
        self
    }
    /// Sets [`LegDetectorParams::straight_eigenvalue_ratio`].
    pub fn with_straight_eigenvalue_ratio(mut self, v: f64) -> Self {
        self.straight_eigenvalue_ratio = v;
        self
    }
    /// Sets [`LegDetectorParams::min_background_gap`].
    pub fn with_min_background_gap(mut self, v: f64) -> Self {
        self.min_background_gap = v;
        self
    }
    /// Sets [`LegDetectorParams::max_leg_separation`].
    pub fn with_max_leg_separation(mut self, v: f64) -> Self {
        self.max_leg_separation = v;
        self
    }
    /// Sets [`LegDetectorParams::leg_radius`].
    pub fn with_leg_radius(mut self, v: f64) -> Self {
        self.leg_radius = v;
        self
    }
    /// Sets [`LegDetectorParams::max_range`].
    pub fn with_max_range(mut self, v: f64) -> Self {
        self.max_range = v;
        self
    }
    /// Sets [`LegDetectorParams::person_std`].
    pub fn with_person_std(mut self, v: f64) -> Self {
        self.person_std = v;
        self
    }
    /// Sets [`LegDetectorParams::single_legs`].
    pub fn with_single_legs(mut self, v: bool) -> Self {
        self.single_legs = v;
        self
    }
    /// Sets [`LegDetectorParams::single_leg_std`].
    pub fn with_single_leg_std(mut self, v: f64) -> Self {
        self.single_leg_std = v;
        self
    }
    /// Sets [`LegDetectorParams::single_leg_confidence`].
    pub fn with_single_leg_confidence(mut self, v: f64) -> Self {
        self.single_leg_confidence = v;
        self
    }

    /// The parameters, if every rule holds.
    ///
    /// # Errors
    /// [`TrackingError::InvalidParameter`] naming the first parameter that is not finite
    /// and > 0 (`cluster_gap`, `max_cluster_length`, `max_leg_separation`, `max_range`,
    /// `person_std`, `single_leg_std`), has `min_points < 2`, a `min_eigenvalue_ratio` or
    /// `straight_eigenvalue_ratio` outside `[0, 1]`, a negative or non-finite
    /// `straight_length`, a negative or non-finite `leg_radius`, or a
    /// `single_leg_confidence` outside `[0, 1]`.
    pub fn check(self) -> Result<Self> {
        haunts_core::positive("cluster_gap", self.cluster_gap)?;
        rule(
            self.min_points >= 2,
            "min_points",
            self.min_points as f64,
            "must be >= 2",
        )?;
        haunts_core::positive("max_cluster_length", self.max_cluster_length)?;
        rule(
            (0.0..=1.0).contains(&self.min_eigenvalue_ratio),
            "min_eigenvalue_ratio",
            self.min_eigenvalue_ratio,
            "must be in [0, 1]",
        )?;
        rule(
            self.straight_length.is_finite() && self.straight_length >= 0.0,
            "straight_length",
            self.straight_length,
            "must be finite and >= 0",
        )?;
        rule(
            (0.0..=1.0).contains(&self.straight_eigenvalue_ratio),
            "straight_eigenvalue_ratio",
            self.straight_eigenvalue_ratio,
            "must be in [0, 1]",
        )?;
        rule(
            self.min_background_gap.is_finite(),
            "min_background_gap",
            self.min_background_gap,
            "must be finite",
        )?;
        haunts_core::positive("max_leg_separation", self.max_leg_separation)?;
        rule(
            self.leg_radius.is_finite() && self.leg_radius >= 0.0,
            "leg_radius",
            self.leg_radius,
            "must be finite and >= 0",
        )?;
        haunts_core::positive("max_range", self.max_range)?;
        haunts_core::positive("person_std", self.person_std)?;
        haunts_core::positive("single_leg_std", self.single_leg_std)?;
        rule(
            (0.0..=1.0).contains(&self.single_leg_confidence),
            "single_leg_confidence",
            self.single_leg_confidence,
            "must be in [0, 1]",
        )?;
        Ok(self)
    }
}

/// One leg candidate: a short cluster of hits that is not a line.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Leg {
    /// The leg's estimated centre, sensor frame, metres: the centroid of its hits pushed
    /// [`LegDetectorParams::leg_radius`] away from the sensor.
    pub centre: Point2<f64>,
    /// Number of hits in the cluster.
    pub points: usize,
    /// Distance from the cluster's first to its last hit, metres.
    pub length: f64,
    /// Smaller over larger eigenvalue of the hits' covariance (0 for a line, 1 for a disc).
    pub eigenvalue_ratio: f64,
    /// How much farther the beams just beside the cluster reach than its end points, metres
    /// (the smaller of the two sides; infinite where a side beam returns nothing): a leg
    /// stands in front of its background.
    #[cfg_attr(
        feature = "serde",
        serde(with = "haunts_occupancy::serde_float::value")
    )]
    pub background_gap: f64,
}

/// The seed-000 leg detector (section IV-A-1).
///
/// 1. The scan's hits are split into clusters wherever two consecutive hits are more than
///    [`LegDetectorParams::cluster_gap`] apart; a reading that is not a hit (NaN, ±inf,
///    zero, below `range_min`, at or beyond `range_max`) also ends a cluster and is skipped.
/// 2. A cluster is a leg if it has at least `min_points` hits, its length (first to last
///    hit) is below `max_cluster_length`, its centre is within `max_range`, and the ratio of
///    the small to the large eigenvalue of its point covariance is at least
///    `min_eigenvalue_ratio` (it is not a straight line).
/// 3. Legs are paired greedily, closest pair first, while their distance is below
///    `max_leg_separation`; a pair gives a person at the midpoint with the fixed covariance
///    `person_std² · I` and confidence 1. With `single_legs`, each unpaired leg gives a
///    candidate at its centre with `single_leg_std² · I` and `single_leg_confidence`.
///
/// Detections are returned pairs first, each group in scan order.
///
/// # Complexity
/// O(n) in the beams plus O(l² log l) in the legs found.
///
/// # Example
/// ```
/// use haunts_occupancy::LaserScan;
/// use haunts_tracking::detect::{Detector, LegDetector, LegDetectorParams};
///
/// // Two legs, 0.3 m apart, 2 m ahead: arcs of 6 cm radius seen from the sensor.
/// let inc = 0.25f64.to_radians();
/// let mut ranges = vec![f64::INFINITY; 400];
/// for (i, r) in ranges.iter_mut().enumerate() {
///     let a = -50f64.to_radians() + i as f64 * inc;
///     let dir = nalgebra::Vector2::new(a.cos(), a.sin());
///     for cy in [-0.15, 0.15] {
///         // Nearest intersection of the beam with a circle at (2, cy), radius 0.06.
///         let c = nalgebra::Vector2::new(2.0, cy);
///         let b = dir.dot(&c);
///         let disc = b * b - c.norm_squared() + 0.06 * 0.06;
///         if disc >= 0.0 {
///             *r = r.min(b - disc.sqrt());
///         }
///     }
/// }
/// let scan = LaserScan::new(0.0, -50f64.to_radians(), inc, 0.05, 20.0, ranges, vec![])?;
/// let detector = LegDetector::new(LegDetectorParams::default())?;
/// let people = detector.detect(&scan)?;
/// assert_eq!(people.len(), 1);
/// approx::assert_abs_diff_eq!(people[0].position.x, 2.0, epsilon = 0.03);
/// approx::assert_abs_diff_eq!(people[0].position.y, 0.0, epsilon = 0.01);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(try_from = "LegDetectorFields"))]
pub struct LegDetector {
    params: LegDetectorParams,
}

impl LegDetector {
    /// A detector with checked parameters.
    ///
    /// # Errors
    /// As [`LegDetectorParams::check`].
    pub fn new(params: LegDetectorParams) -> Result<Self> {
        Ok(Self {
            params: params.check()?,
        })
    }

    /// The parameters.
    pub fn params(&self) -> &LegDetectorParams {
        &self.params
    }

    /// The leg candidates of a scan, in scan order (steps 1–2 of [`LegDetector`]).
    pub fn legs(&self, scan: &LaserScan) -> Vec<Leg> {
        let p = &self.params;
        let gap2 = p.cluster_gap * p.cluster_gap;
        let mut legs = Vec::new();
        let mut cluster: Vec<Point2<f64>> = Vec::with_capacity(64);
        let (sin_inc, cos_inc) = scan.angle_increment.sin_cos();
        // The beam direction is rotated incrementally: exact to ~1e-13 over a few thousand
        // beams, and much cheaper than a sin/cos per beam.
        let mut dir = Vector2::new(scan.angle_min.cos(), scan.angle_min.sin());
        for (i, &range) in scan.ranges.iter().enumerate() {
            if i % 256 == 0 {
                let a = scan.angle_min + i as f64 * scan.angle_increment;
                dir = Vector2::new(a.cos(), a.sin());
            }
            match scan.reading(range) {
                Reading::Hit(r) => {
                    let point = Point2::from(dir * r);
                    if cluster
                        .last()
                        .is_some_and(|last| (point - last).norm_squared() > gap2)
                    {
                        self.close(scan, i, &mut cluster, &mut legs);
                    }
                    cluster.push(point);
                }
                Reading::MaxRange | Reading::Invalid => {
                    self.close(scan, i, &mut cluster, &mut legs);
                }
            }
            dir = Vector2::new(
                dir.x * cos_inc - dir.y * sin_inc,
                dir.x * sin_inc + dir.y * cos_inc,
            );
        }
        self.close(scan, scan.len(), &mut cluster, &mut legs);
        legs
    }

    /// Turns the finished cluster into a leg if it is one, and empties it.
    /// Hits are consecutive beams, so the cluster holds beams `end - len .. end`.
    fn close(
        &self,
        scan: &LaserScan,
        end: usize,
        cluster: &mut Vec<Point2<f64>>,
        legs: &mut Vec<Leg>,
    ) {
        if let Some(leg) = self.leg(scan, end, cluster) {
            legs.push(leg);
        }
        cluster.clear();
    }

    fn leg(&self, scan: &LaserScan, end: usize, cluster: &[Point2<f64>]) -> Option<Leg> {
        let p = &self.params;
        let (first, last) = (cluster.first()?, cluster.last()?);
        if cluster.len() < p.min_points {
            return None;
        }
        let length = (last - first).norm();
        if length >= p.max_cluster_length {
            return None;
        }
        let n = cluster.len() as f64;
        let mean = cluster.iter().fold(Vector2::zeros(), |s, q| s + q.coords) / n;
        let (mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0);
        for q in cluster {
            let d = q.coords - mean;
            sxx += d.x * d.x;
            sxy += d.x * d.y;
            syy += d.y * d.y;
        }
        let (sxx, sxy, syy) = (sxx / n, sxy / n, syy / n);
        // Eigenvalues of [[sxx, sxy], [sxy, syy]].
        let half_trace = 0.5 * (sxx + syy);
        let root = (0.25 * (sxx - syy) * (sxx - syy) + sxy * sxy).sqrt();
        let (big, small) = (half_trace + root, (half_trace - root).max(0.0));
        let ratio = if big > 0.0 { small / big } else { 0.0 };
        if ratio < p.min_eigenvalue_ratio
            || (length > p.straight_length && ratio < p.straight_eigenvalue_ratio)
        {
            return None;
        }
        let distance = mean.norm();
        if distance > p.max_range {
            return None;
        }
        let centre = if distance > 0.0 {
            mean * (1.0 + p.leg_radius / distance)
        } else {
            mean
        };
        let start = end - cluster.len();
        let beyond = |index: Option<usize>, near: f64| match index
            .and_then(|k| scan.ranges.get(k))
            .map(|&r| scan.reading(r))
        {
            Some(Reading::Hit(r)) => r - near,
            // No return, an invalid reading, or the scan's edge: nothing seen behind.
            _ => f64::INFINITY,
        };
        let background_gap = beyond(start.checked_sub(1), first.coords.norm())
            .min(beyond(Some(end), last.coords.norm()));
        if background_gap < p.min_background_gap {
            return None;
        }
        Some(Leg {
            background_gap,
            centre: Point2::from(centre),
            points: cluster.len(),
            length,
            eigenvalue_ratio: ratio,
        })
    }

    /// Pairs legs into person candidates (step 3 of [`LegDetector`]).
    pub fn pair(&self, legs: &[Leg]) -> Vec<Detection> {
        let p = &self.params;
        let scored: Vec<(Point2<f64>, f64)> = legs.iter().map(|l| (l.centre, 1.0)).collect();
        let single = p
            .single_legs
            .then_some((p.single_leg_std, p.single_leg_confidence));
        pair_legs(&scored, p.max_leg_separation, p.person_std, single)
    }
}

/// Pairs scored legs `(centre, confidence)` into people: greedily, closest pair first,
/// while their distance is below `max_separation`; a pair gives a person at the midpoint
/// with covariance `person_std² · I` and the mean of its legs' confidences. With `single =
/// Some((std, factor))`, each unpaired leg gives a candidate at its centre with `std² · I`
/// and its confidence times `factor`. Pairs first, each group in scan order.
pub(crate) fn pair_legs(
    legs: &[(Point2<f64>, f64)],
    max_separation: f64,
    person_std: f64,
    single: Option<(f64, f64)>,
) -> Vec<Detection> {
    let mut pairs = Vec::new();
    for i in 0..legs.len() {
        for j in i + 1..legs.len() {
            let d = (legs[i].0 - legs[j].0).norm();
            if d < max_separation {
                pairs.push((d, i, j));
            }
        }
    }
    // Closest first; ties by scan order, so the result never depends on sort stability.
    pairs.sort_by(|a, b| a.0.total_cmp(&b.0).then((a.1, a.2).cmp(&(b.1, b.2))));
    let mut used = vec![false; legs.len()];
    let mut chosen = Vec::new();
    for (_, i, j) in pairs {
        if !used[i] && !used[j] {
            used[i] = true;
            used[j] = true;
            chosen.push((i, j));
        }
    }
    chosen.sort_unstable();
    let pair_cov = Matrix2::identity() * (person_std * person_std);
    let mut out: Vec<Detection> = chosen
        .into_iter()
        .map(|(i, j)| Detection {
            position: nalgebra::center(&legs[i].0, &legs[j].0),
            covariance: pair_cov,
            confidence: 0.5 * (legs[i].1 + legs[j].1),
        })
        .collect();
    if let Some((std, factor)) = single {
        let single_cov = Matrix2::identity() * (std * std);
        out.extend(
            legs.iter()
                .zip(&used)
                .filter(|(_, used)| !**used)
                .map(|(leg, _)| Detection {
                    position: leg.0,
                    covariance: single_cov,
                    confidence: leg.1 * factor,
                }),
        );
    }
    out
}

impl Detector for LegDetector {
    fn detect(&self, scan: &LaserScan) -> Result<Vec<Detection>> {
        Ok(self.pair(&self.legs(scan)))
    }

    fn detect_where(
        &self,
        scan: &LaserScan,
        keep: &dyn Fn(&Point2<f64>) -> bool,
    ) -> Result<Vec<Detection>> {
        let mut legs = self.legs(scan);
        legs.retain(|leg| keep(&leg.centre));
        Ok(self.pair(&legs))
    }

    fn candidates(&self, scan: &LaserScan) -> Result<Vec<Point2<f64>>> {
        Ok(self.legs(scan).iter().map(|leg| leg.centre).collect())
    }
}

/// The fields of a [`LegDetector`] as deserialised, before [`LegDetector::new`] checks them.
#[cfg(feature = "serde")]
#[derive(serde::Deserialize)]
struct LegDetectorFields {
    params: LegDetectorParams,
}

#[cfg(feature = "serde")]
impl TryFrom<LegDetectorFields> for LegDetector {
    type Error = TrackingError;
    fn try_from(f: LegDetectorFields) -> Result<Self> {
        Self::new(f.params)
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;
    use approx::assert_relative_eq;

    fn scan(ranges: Vec<f64>) -> LaserScan {
        LaserScan::new(0.0, -1.0, 0.01, 0.05, 20.0, ranges, vec![]).unwrap()
    }

    #[test]
    fn every_bad_parameter_is_named() {
        let d = LegDetectorParams::default();
        let cases = [
            (d.with_cluster_gap(0.0), "cluster_gap"),
            (d.with_min_points(1), "min_points"),
            (d.with_max_cluster_length(f64::NAN), "max_cluster_length"),
            (d.with_min_eigenvalue_ratio(1.5), "min_eigenvalue_ratio"),
            (d.with_max_leg_separation(-1.0), "max_leg_separation"),
            (d.with_leg_radius(-0.1), "leg_radius"),
            (d.with_max_range(f64::INFINITY), "max_range"),
            (d.with_person_std(0.0), "person_std"),
            (d.with_single_leg_std(f64::NAN), "single_leg_std"),
            (d.with_single_leg_confidence(2.0), "single_leg_confidence"),
        ];
        for (params, name) in cases {
            match params.check() {
                Err(TrackingError::InvalidParameter(haunts_core::InvalidParameter {
                    name: n,
                    ..
                })) => assert_eq!(n, name),
                other => panic!("{name}: {other:?}"),
            }
        }
        assert!(d.check().is_ok());
    }

    /// Ranges of beams hitting a circle of `radius` at `centre` (inf elsewhere).
    fn circle(scan: &LaserScan, centre: Vector2<f64>, radius: f64) -> Vec<f64> {
        (0..scan.len())
            .map(|i| {
                let a = scan.angle_min + i as f64 * scan.angle_increment;
                let b = Vector2::new(a.cos(), a.sin()).dot(&centre);
                let disc = b * b - centre.norm_squared() + radius * radius;
                if disc >= 0.0 {
                    b - disc.sqrt()
                } else {
                    f64::INFINITY
                }
            })
            .collect()
    }

    #[test]
    fn invalid_readings_split_clusters() {
        // A 10 cm leg at 1 m: ~20 hits on an arc; a NaN in the middle splits it in two.
        let mut s = scan(vec![f64::INFINITY; 200]);
        s.ranges = circle(&s, Vector2::new(1.0, 0.0), 0.1);
        let detector = LegDetector::new(LegDetectorParams::default()).unwrap();
        let whole = detector.legs(&s);
        assert_eq!(whole.len(), 1);
        let hits: Vec<usize> = (0..s.len()).filter(|&i| s.ranges[i].is_finite()).collect();
        let middle = hits[hits.len() / 2];
        s.ranges[middle] = f64::NAN;
        let legs = detector.legs(&s);
        assert_eq!(legs.len(), 2);
        assert_eq!(legs[0].points + legs[1].points, whole[0].points - 1);
        // Zero and too-short ranges split too.
        s.ranges[middle] = 0.0;
        assert_eq!(detector.legs(&s).len(), 2);
        s.ranges[middle] = 0.01;
        assert_eq!(detector.legs(&s).len(), 2);
    }

    #[test]
    fn transformed_rotates_the_covariance() {
        let d = Detection {
            position: Point2::new(1.0, 0.0),
            covariance: Matrix2::new(0.04, 0.0, 0.0, 0.01),
            confidence: 0.7,
        };
        let pose = Pose2::new(Vector2::new(1.0, 2.0), std::f64::consts::FRAC_PI_2);
        let t = d.transformed(&pose);
        assert_relative_eq!(t.position, Point2::new(1.0, 3.0), epsilon = 1e-12);
        assert_relative_eq!(
            t.covariance,
            Matrix2::new(0.01, 0.0, 0.0, 0.04),
            epsilon = 1e-12
        );
        assert_relative_eq!(t.confidence, 0.7);
    }

    #[test]
    fn bad_detections_are_typed_errors() {
        let good = Detection::isotropic(Point2::new(1.0, 1.0), 0.1);
        let singular = Detection {
            covariance: Matrix2::new(1.0, 1.0, 1.0, 1.0),
            ..good
        };
        let nan = Detection {
            position: Point2::new(f64::NAN, 0.0),
            ..good
        };
        let negative = Detection {
            confidence: -1.0,
            ..good
        };
        assert!(check_detections(&[good]).is_ok());
        assert!(matches!(
            check_detections(&[good, singular]),
            Err(TrackingError::SingularCovariance { index: 1 })
        ));
        assert!(matches!(
            check_detections(&[nan]),
            Err(TrackingError::InvalidDetection { index: 0 })
        ));
        assert!(matches!(
            check_detections(&[good, good, negative]),
            Err(TrackingError::InvalidDetection { index: 2 })
        ));
    }
}
