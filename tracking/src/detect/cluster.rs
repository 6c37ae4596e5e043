//! The clustering of `leg_tracker`'s laser processor: the clusters its learned leg detector
//! is trained and run on, so that labels made with `leg_tracker`'s tools line up with ours.
//!
//! Unlike the seed-000 split at gaps ([`crate::detect::LegDetector`]), a cluster here is
//! grown from its lowest beam by a breadth-first search over nearby beams, and clusters may
//! interleave (a leg in front of a wall can hold beams on both sides of a wall beam).

use haunts_occupancy::LaserScan;
use nalgebra::Point2;

use crate::Result;
use crate::detect::rule;

/// Parameters of [`clusters`].
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub struct ClusterParams {
    /// Two hits closer than this join one cluster, metres (`leg_tracker`'s
    /// `cluster_dist_euclid`: 0.13).
    pub distance: f64,
    /// Clusters with fewer hits are dropped (`leg_tracker`'s `min_points_per_cluster`: 3).
    pub min_points: usize,
}

impl Default for ClusterParams {
    /// `leg_tracker`'s defaults, with which its training set was labelled: 0.13 m, 3 points.
    fn default() -> Self {
        Self {
            distance: 0.13,
            min_points: 3,
        }
    }
}

impl ClusterParams {
    /// Sets [`ClusterParams::distance`].
    pub fn with_distance(mut self, v: f64) -> Self {
        self.distance = v;
        self
    }
    /// Sets [`ClusterParams::min_points`].
    pub fn with_min_points(mut self, v: usize) -> Self {
        self.min_points = v;
        self
    }

    /// The parameters, if every rule holds.
    ///
    /// # Errors
    /// [`crate::TrackingError::InvalidParameter`] naming `distance` (must be finite and
    /// > 0) or `min_points` (must be ≥ 1).
    pub fn check(self) -> Result<Self> {
        haunts_core::positive("distance", self.distance)?;
        rule(
            self.min_points >= 1,
            "min_points",
            self.min_points as f64,
            "must be >= 1",
        )?;
        Ok(self)
    }
}

/// One cluster of hits: its beams in increasing index order and their points.
#[derive(Debug, Clone, PartialEq)]
pub struct Cluster {
    /// Beam indices, increasing.
    pub indices: Vec<usize>,
    /// The hits of those beams in the sensor frame, metres, in the same order.
    pub points: Vec<Point2<f64>>,
}

impl Cluster {
    /// The mean of the points (the position `leg_tracker` labels and reports).
    pub fn centroid(&self) -> Point2<f64> {
        let n = self.points.len().max(1) as f64;
        Point2::from(
            self.points
                .iter()
                .fold(nalgebra::Vector2::zeros(), |s, p| s + p.coords)
                / n,
        )
    }
}

/// `v` at the precision of a `float32`, the type of every field of a ROS
/// `sensor_msgs/LaserScan`: what `leg_tracker` computes with. A scan read from text (whole
/// millimetres) rounds back to exactly the values the laser sent.
pub(crate) fn f32_precision(v: f64) -> f64 {
    v as f32 as f64
}

/// The range of beam `i` at `float32` precision if it is a hit (`range_min < r <
/// range_max`, which NaN and ±inf fail).
pub(crate) fn hit_range(scan: &LaserScan, i: usize) -> Option<f64> {
    let r = f32_precision(*scan.ranges.get(i)?);
    (r > f32_precision(scan.range_min) && r < f32_precision(scan.range_max)).then_some(r)
}

/// The hit of beam `i` (see [`hit_range`]), in the sensor frame.
pub(crate) fn hit(scan: &LaserScan, i: usize) -> Option<Point2<f64>> {
    let r = hit_range(scan, i)?;
    let a = f32_precision(scan.angle_min) + i as f64 * f32_precision(scan.angle_increment);
    Some(Point2::new(a.cos() * r, a.sin() * r))
}

/// The clusters of `scan` as `leg_tracker`'s laser processor makes them.
///
/// A beam is a hit when `range_min < r < range_max`; ranges and angles are taken at the
/// `float32` precision of a ROS scan, as `leg_tracker` sees them (so that readings of exactly
/// `d` or at the range limits fall on the same side). Clusters grow from the lowest hit not
/// yet clustered: each hit `s` taken into the cluster (breadth first) pulls in every hit
/// still unclustered whose index is below `s + ⌊asin(d / r_s) / Δθ⌋` (the beams whose
/// lateral offset at range `r_s` is under `d`; none when `d > r_s`) and that lies closer
/// than `d = distance` to it. Clusters of fewer than `min_points` hits are dropped.
/// Clusters are returned in the order of their lowest beam.
///
/// # Errors
/// As [`ClusterParams::check`].
///
/// # Complexity
/// O(Σ w) over the hits taken, where `w` is the number of still unclustered beams between
/// the cluster's first beam and the hit's search limit (near-linear in the beams for a
/// laser's usual scans).
///
/// # Example
/// ```
/// use haunts_occupancy::LaserScan;
/// use haunts_tracking::detect::{ClusterParams, clusters};
///
/// // Beams 0..=2 at 2 m, a gap of no return, beams 4..=7 at 3 m.
/// let ranges = vec![2.0, 2.0, 2.0, 0.0, 3.0, 3.0, 3.0, 3.0];
/// let scan = LaserScan::new(0.0, 0.0, 0.01, 0.03, 11.0, ranges, vec![])?;
/// let found = clusters(&scan, &ClusterParams::default())?;
/// assert_eq!(found.len(), 2);
/// assert_eq!(found[0].indices, vec![0, 1, 2]);
/// assert_eq!(found[1].indices, vec![4, 5, 6, 7]);
/// approx::assert_abs_diff_eq!(found[1].centroid().x, 3.0, epsilon = 1e-2);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn clusters(scan: &LaserScan, params: &ClusterParams) -> Result<Vec<Cluster>> {
    let params = params.check()?;
    let n = scan.ranges.len();
    let points: Vec<Option<Point2<f64>>> = (0..n).map(|i| hit(scan, i)).collect();
    // `next[i]`: the lowest unclustered hit ≥ i (n when none), found with path halving.
    let mut next: Vec<usize> = (0..=n).collect();
    for (i, p) in points.iter().enumerate() {
        if p.is_none() {
            next[i] = i + 1;
        }
    }
    fn find(next: &mut [usize], mut i: usize) -> usize {
        while next[i] != i {
            next[i] = next[next[i]];
            i = next[i];
        }
        i
    }
    let d = params.distance;
    let inc = f32_precision(scan.angle_increment).abs();
    let mut out = Vec::new();
    let mut queue = Vec::new();
    loop {
        let first = find(&mut next, 0);
        if first >= n {
            break;
        }
        next[first] = first + 1;
        queue.clear();
        queue.push(first);
        let mut q = 0;
        while q < queue.len() {
            let s = queue[q];
            q += 1;
            let (Some(ps), Some(rs)) = (points[s], hit_range(scan, s)) else {
                continue;
            };
            let ratio = d / rs;
            if ratio.is_nan() || ratio > 1.0 || inc == 0.0 {
                continue;
            }
            let expand = (ratio.asin() / inc).floor();
            let limit = if expand >= (n - s) as f64 {
                n
            } else {
                s + expand as usize
            };
            let mut k = find(&mut next, first);
            while k < limit {
                if let Some(pk) = points[k] {
                    if (pk - ps).norm() < d {
                        next[k] = k + 1;
                        queue.push(k);
                    }
                }
                k = find(&mut next, k + 1);
            }
        }
        if queue.len() >= params.min_points {
            let mut indices = queue.clone();
            indices.sort_unstable();
            let points = indices.iter().filter_map(|&i| points[i]).collect();
            out.push(Cluster { indices, points });
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;

    /// A plain transcription of `lp.py` (quadratic), the reference of the fast version.
    fn reference(scan: &LaserScan, d: f64, min_points: usize) -> Vec<Vec<usize>> {
        let n = scan.ranges.len();
        let pts: Vec<Option<Point2<f64>>> = (0..n).map(|i| hit(scan, i)).collect();
        let mut avail: Vec<bool> = pts.iter().map(Option::is_some).collect();
        let mut out = Vec::new();
        while let Some(first) = avail.iter().position(|&a| a) {
            avail[first] = false;
            let mut queue = vec![first];
            let mut q = 0;
            while q < queue.len() {
                let s = queue[q];
                q += 1;
                let ratio = d / hit_range(scan, s).unwrap();
                if ratio > 1.0 {
                    continue;
                }
                let inc = f32_precision(scan.angle_increment);
                let limit = n.min(s + (ratio.asin() / inc) as usize);
                for k in 0..limit {
                    if avail[k] && (pts[k].unwrap() - pts[s].unwrap()).norm() < d {
                        avail[k] = false;
                        queue.push(k);
                    }
                }
            }
            queue.sort_unstable();
            if queue.len() >= min_points {
                out.push(queue);
            }
        }
        out
    }

    proptest::proptest! {
        #[test]
        fn the_fast_clustering_is_the_reference_one(
            ranges in proptest::collection::vec(
                proptest::prop_oneof![0.0..0.02f64, 0.1..3.0f64, proptest::strategy::Just(0.0)],
                0..120,
            ),
            d in 0.05..0.5f64,
            min_points in 1usize..5,
        ) {
            let scan = LaserScan::new(0.0, -1.0, 0.0061, 0.03, 11.0, ranges, vec![]).unwrap();
            let fast: Vec<Vec<usize>> = clusters(
                &scan,
                &ClusterParams::default().with_distance(d).with_min_points(min_points),
            )
            .unwrap()
            .into_iter()
            .map(|c| c.indices)
            .collect();
            proptest::prop_assert_eq!(fast, reference(&scan, d, min_points));
        }
    }

    #[test]
    fn bad_parameters_are_named() {
        let d = ClusterParams::default();
        for (p, name) in [
            (d.with_distance(0.0), "distance"),
            (d.with_min_points(0), "min_points"),
        ] {
            assert!(matches!(
                p.check(),
                Err(crate::TrackingError::InvalidParameter(haunts_core::InvalidParameter { name: n, .. })) if n == name
            ));
        }
    }
}
