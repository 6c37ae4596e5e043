//! Geometric features of one cluster of laser hits, of the kind `leg_tracker`'s random forest
//! classifies (Leigh et al., ICRA 2015, Table I, after Arras et al. 2007).
//!
//! The points `p₁ … pₙ` of a cluster are taken in beam order; `c = (1/n) Σ pᵢ` is their
//! centroid, `ûᵢ = pᵢ / |pᵢ|` the direction of beam `i`, and `S = Σ (pᵢ − c)(pᵢ − c)ᵀ` their
//! scatter matrix. Every feature but `occluded` depends on the points alone, and all are
//! invariant to a rotation of the scan about the laser (the median is taken in the
//! *bearing frame*, whose x axis points from the laser to `c`, so it rotates with the
//! cluster), and to the direction the scan turns in. Angles at a point are measured on the
//! side that faces the laser: with `γ ∈ [0, π]` the angle between two vectors and
//! `s ∈ {−1, 0, 1}` the sign of `(m − pᵢ)·ûᵢ` (`m` the midpoint of the two other points:
//! positive when `pᵢ` is nearer to the laser than `m`, a bulge towards it as a leg shows),
//! the angle is `π + s(π − γ)`: `π` on a line, more on a leg, less in a concave corner.
//!
//! | # | name | formula |
//! |---|---|---|
//! | 0 | `points` | `n` |
//! | 1 | `width` | `‖pₙ − p₁‖` |
//! | 2 | `length` | extent of the points along the major eigenvector `e` of `S`: `max (pᵢ − c)·e − min (pᵢ − c)·e` |
//! | 3 | `std` | `√(Σ ‖pᵢ − c‖² / (n − 1))` (0 for `n = 1`) |
//! | 4 | `median_deviation` | `(1/n) Σ ‖qᵢ − q̃‖`, `qᵢ` the points in the bearing frame, `q̃` their coordinate-wise median |
//! | 5 | `occluded` | 1 if the hit of the beam just before `p₁` or just after `pₙ` is nearer to the laser than that end point (something in front hides part of the object), else 0 |
//! | 6 | `linearity` | `Σ ((pᵢ − c)·ν)²` for the normal `ν` of the total-least-squares line: `λ_min(S)` |
//! | 7 | `circularity` | `Σ (r − ‖pᵢ − o‖)²` for the least-squares circle `(o, r)` (the algebraic fit `‖p − o‖² = r²` linear in `o` and `r² − ‖o‖²`) |
//! | 8 | `radius` | `r` of that circle (capped at 10 m; a circle that cannot be fitted, as on collinear points, counts as that cap with `circularity = linearity`) |
//! | 9 | `boundary_length` | `Σᵢ lᵢ`, `lᵢ = ‖pᵢ₊₁ − pᵢ‖` |
//! | 10 | `boundary_regularity` | standard deviation of the `lᵢ` (population; 0 below two segments) |
//! | 11 | `mean_curvature` | `(1/(n−2)) Σ sᵢ 4Aᵢ / (‖a‖‖b‖‖c‖)` over the triples `(pᵢ₋₁, pᵢ, pᵢ₊₁)`: the Menger curvature (`Aᵢ` the triangle's area), signed as above |
//! | 12 | `mean_angle` | mean angular difference: `(1/(n−2)) Σ βᵢ`, `βᵢ` the angle at `pᵢ` between `pᵢ₋₁` and `pᵢ₊₁` (laser side) |
//! | 13 | `inscribed_angle_mean` | `(1/(n−2)) Σ αᵢ`, `αᵢ` the angle at `pᵢ` between `p₁` and `pₙ` (laser side), for `i = 2 … n−1`; on a circular arc of central angle `φ` every `αᵢ = π + φ/2` (inscribed angle theorem) |
//! | 14 | `inscribed_angle_std` | population standard deviation of the `αᵢ` |
//! | 15 | `distance` | `‖c‖`, distance from the laser |
//!
//! Features that need three points are 0 for smaller clusters.

use haunts_occupancy::LaserScan;
use nalgebra::{Matrix3, Point2, Vector2, Vector3};

use crate::detect::cluster::{Cluster, hit};

/// Number of features of a cluster.
pub const FEATURES: usize = 16;

/// The features' names, in the order of [`cluster_features`]'s array.
pub const FEATURE_NAMES: [&str; FEATURES] = [
    "points",
    "width",
    "length",
    "std",
    "median_deviation",
    "occluded",
    "linearity",
    "circularity",
    "radius",
    "boundary_length",
    "boundary_regularity",
    "mean_curvature",
    "mean_angle",
    "inscribed_angle_mean",
    "inscribed_angle_std",
    "distance",
];

/// The largest radius of the best-fit circle, metres: far more than any leg, so nearly
/// straight clusters all read as this.
const MAX_RADIUS: f64 = 10.0;

/// The features of `cluster`, a cluster of `scan` (see the [module docs](self) for each
/// formula).
///
/// # Complexity
/// O(n log n) in the cluster's points (the median).
///
/// # Example
/// ```
/// use haunts_occupancy::LaserScan;
/// use haunts_tracking::detect::{ClusterParams, clusters};
/// use haunts_tracking::detect::features::{FEATURE_NAMES, cluster_features};
///
/// // Five beams on a straight wall, 2 m ahead (x = 2), one degree apart.
/// let inc = 1f64.to_radians();
/// let ranges = (0..5).map(|i| 2.0 / ((i as f64 - 2.0) * inc).cos()).collect();
/// let scan = LaserScan::new(0.0, -2.0 * inc, inc, 0.03, 11.0, ranges, vec![])?;
/// let found = clusters(&scan, &ClusterParams::default())?;
/// let f = cluster_features(&scan, &found[0]);
/// let at = |name: &str| f[FEATURE_NAMES.iter().position(|n| *n == name).unwrap()];
/// assert_eq!(at("points"), 5.0);
/// approx::assert_abs_diff_eq!(at("linearity"), 0.0, epsilon = 1e-12);
/// // (Readings are taken at float32 precision, as a ROS scan carries them.)
/// approx::assert_abs_diff_eq!(at("mean_angle"), std::f64::consts::PI, epsilon = 1e-4);
/// approx::assert_abs_diff_eq!(at("distance"), 2.0, epsilon = 1e-3);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn cluster_features(scan: &LaserScan, cluster: &Cluster) -> [f64; FEATURES] {
    let occluded = match (
        cluster.indices.first(),
        cluster.indices.last(),
        cluster.points.first(),
        cluster.points.last(),
    ) {
        (Some(&a), Some(&b), Some(pa), Some(pb)) => {
            let nearer = |k: Option<usize>, end: &Point2<f64>| {
                k.and_then(|k| hit(scan, k))
                    .is_some_and(|q| q.coords.norm() < end.coords.norm())
            };
            nearer(a.checked_sub(1), pa) || nearer(Some(b + 1), pb)
        }
        _ => false,
    };
    point_features(&cluster.points, occluded)
}

/// The angle at `p` between `a` and `b`, on the side facing the laser (see the module
/// docs); `π` when degenerate.
fn laser_side_angle(a: &Point2<f64>, p: &Point2<f64>, b: &Point2<f64>) -> f64 {
    let (u, v) = (a - p, b - p);
    let gamma = u.perp(&v).abs().atan2(u.dot(&v));
    std::f64::consts::PI + bulge(a, p, b) * (std::f64::consts::PI - gamma)
}

/// `s`: the sign of `(m − p)·p̂`, `m` the midpoint of `a` and `b`.
fn bulge(a: &Point2<f64>, p: &Point2<f64>, b: &Point2<f64>) -> f64 {
    let m = nalgebra::center(a, b);
    let toward = (m - p).dot(&p.coords);
    if toward > 0.0 {
        1.0
    } else if toward < 0.0 {
        -1.0
    } else {
        0.0
    }
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_unstable_by(f64::total_cmp);
    let n = v.len();
    if n == 0 {
        0.0
    } else {
        0.5 * (v[(n - 1) / 2] + v[n / 2])
    }
}

fn mean_std(v: impl Iterator<Item = f64> + Clone) -> (f64, f64) {
    let n = v.clone().count();
    if n == 0 {
        return (0.0, 0.0);
    }
    let mean = v.clone().sum::<f64>() / n as f64;
    let var = v.map(|x| (x - mean) * (x - mean)).sum::<f64>() / n as f64;
    (mean, var.sqrt())
}

/// The features of the points `p₁ … pₙ` of a cluster in beam order (sensor frame), with the
/// `occluded` flag given (see the [module docs](self)).
///
/// # Complexity
/// O(n log n).
pub fn point_features(points: &[Point2<f64>], occluded: bool) -> [f64; FEATURES] {
    let mut f = [0.0; FEATURES];
    let n = points.len();
    let (Some(first), Some(last)) = (points.first(), points.last()) else {
        return f;
    };
    let nf = n as f64;
    let c = points.iter().fold(Vector2::zeros(), |s, p| s + p.coords) / nf;
    let (mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0);
    for p in points {
        let d = p.coords - c;
        sxx += d.x * d.x;
        sxy += d.x * d.y;
        syy += d.y * d.y;
    }
    let half_trace = 0.5 * (sxx + syy);
    let root = (0.25 * (sxx - syy) * (sxx - syy) + sxy * sxy).sqrt();
    let (big, small) = (half_trace + root, (half_trace - root).max(0.0));
    // Major eigenvector of [[sxx, sxy], [sxy, syy]].
    let major = if sxy.abs() > 0.0 {
        Vector2::new(big - syy, sxy)
    } else if sxx >= syy {
        Vector2::new(1.0, 0.0)
    } else {
        Vector2::new(0.0, 1.0)
    };
    let major = major.try_normalize(0.0).unwrap_or(Vector2::new(1.0, 0.0));
    let (lo, hi) = points
        .iter()
        .map(|p| (p.coords - c).dot(&major))
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), t| {
            (lo.min(t), hi.max(t))
        });

    f[0] = nf;
    f[1] = (last - first).norm();
    f[2] = hi - lo;
    f[3] = if n > 1 {
        ((sxx + syy) / (nf - 1.0)).sqrt()
    } else {
        0.0
    };
    // Median in the bearing frame.
    let u = c.try_normalize(0.0).unwrap_or(Vector2::new(1.0, 0.0));
    let v = Vector2::new(-u.y, u.x);
    let q: Vec<Vector2<f64>> = points
        .iter()
        .map(|p| Vector2::new(p.coords.dot(&u), p.coords.dot(&v)))
        .collect();
    let mut xs: Vec<f64> = q.iter().map(|q| q.x).collect();
    let mut ys: Vec<f64> = q.iter().map(|q| q.y).collect();
    let med = Vector2::new(median(&mut xs), median(&mut ys));
    f[4] = q.iter().map(|q| (q - med).norm()).sum::<f64>() / nf;
    f[5] = f64::from(u8::from(occluded));
    f[6] = small;
    let (circularity, radius) = circle_fit(points, &c).unwrap_or((small, MAX_RADIUS));
    f[7] = circularity;
    f[8] = radius;
    let segments = points.windows(2).map(|w| (w[1] - w[0]).norm());
    f[9] = segments.clone().sum();
    f[10] = if n > 2 { mean_std(segments).1 } else { 0.0 };
    if n > 2 {
        let triples = points.windows(3);
        let k = (n - 2) as f64;
        f[11] = triples
            .clone()
            .map(|w| {
                let (a, b, c) = (
                    (w[1] - w[0]).norm(),
                    (w[2] - w[1]).norm(),
                    (w[2] - w[0]).norm(),
                );
                let area2 = (w[1] - w[0]).perp(&(w[2] - w[0])).abs();
                let denom = a * b * c;
                if denom > 0.0 {
                    bulge(&w[0], &w[1], &w[2]) * 2.0 * area2 / denom
                } else {
                    0.0
                }
            })
            .sum::<f64>()
            / k;
        f[12] = triples
            .map(|w| laser_side_angle(&w[0], &w[1], &w[2]))
            .sum::<f64>()
            / k;
        let inscribed = points[1..n - 1]
            .iter()
            .map(|p| laser_side_angle(first, p, last));
        let (mean, std) = mean_std(inscribed);
        f[13] = mean;
        f[14] = std;
    }
    f[15] = c.norm();
    f
}

/// `(Σ (r − ‖pᵢ − o‖)², r)` of the algebraic least-squares circle, or `None` when it cannot
/// be fitted or its radius exceeds `MAX_RADIUS`.
fn circle_fit(points: &[Point2<f64>], c: &Vector2<f64>) -> Option<(f64, f64)> {
    if points.len() < 3 {
        return None;
    }
    // In coordinates centred on c: 2x·a + 2y·b + k = x² + y², r² = k + a² + b².
    let mut ata = Matrix3::zeros();
    let mut atb = Vector3::zeros();
    for p in points {
        let d = p.coords - c;
        let row = Vector3::new(2.0 * d.x, 2.0 * d.y, 1.0);
        ata += row * row.transpose();
        atb += row * d.norm_squared();
    }
    let sol = ata.lu().solve(&atb)?;
    if !sol.iter().all(|v| v.is_finite()) {
        return None;
    }
    let o = Vector2::new(sol.x, sol.y);
    let r2 = sol.z + o.norm_squared();
    let r = r2.max(0.0).sqrt();
    if !(r > 0.0 && r <= MAX_RADIUS) {
        return None;
    }
    let fit = points
        .iter()
        .map(|p| {
            let e = r - (p.coords - c - o).norm();
            e * e
        })
        .sum();
    Some((fit, r))
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;
    use approx::assert_abs_diff_eq;
    use nalgebra::Rotation2;
    use std::f64::consts::PI;

    fn at(f: &[f64; FEATURES], name: &str) -> f64 {
        f[FEATURE_NAMES.iter().position(|n| *n == name).unwrap()]
    }

    /// `k` points on the near side of a circle of radius `r` at `(d, 0)`, spanning the
    /// central angle `phi` symmetrically about the laser's line of sight.
    fn arc(d: f64, r: f64, phi: f64, k: usize) -> Vec<Point2<f64>> {
        (0..k)
            .map(|i| {
                let t = -phi / 2.0 + phi * i as f64 / (k - 1) as f64;
                Point2::new(d - r * t.cos(), r * t.sin())
            })
            .collect()
    }

    #[test]
    fn an_arc_has_its_radius_curvature_and_inscribed_angle() {
        let (r, phi, k) = (0.06, 2.0, 9);
        let f = point_features(&arc(2.0, r, phi, k), false);
        assert_eq!(at(&f, "points"), 9.0);
        assert_abs_diff_eq!(at(&f, "radius"), r, epsilon = 1e-9);
        assert_abs_diff_eq!(at(&f, "circularity"), 0.0, epsilon = 1e-18);
        // The Menger curvature of three points on a circle is 1/r; a leg bulges towards
        // the laser, so it is positive.
        assert_abs_diff_eq!(at(&f, "mean_curvature"), 1.0 / r, epsilon = 1e-6);
        assert_abs_diff_eq!(
            at(&f, "inscribed_angle_mean"),
            PI + phi / 2.0,
            epsilon = 1e-9
        );
        assert_abs_diff_eq!(at(&f, "inscribed_angle_std"), 0.0, epsilon = 1e-9);
        // Equal steps δ = φ/(k−1): the angle at each point is π + δ on the laser side.
        let delta = phi / (k - 1) as f64;
        assert_abs_diff_eq!(at(&f, "mean_angle"), PI + delta, epsilon = 1e-9);
        assert_abs_diff_eq!(
            at(&f, "width"),
            2.0 * r * (phi / 2.0).sin(),
            epsilon = 1e-12
        );
        let chord = 2.0 * r * (delta / 2.0).sin();
        assert_abs_diff_eq!(
            at(&f, "boundary_length"),
            chord * (k - 1) as f64,
            epsilon = 1e-12
        );
        assert_abs_diff_eq!(at(&f, "boundary_regularity"), 0.0, epsilon = 1e-12);
        // Seen from behind (the far side), the same arc is concave: negative curvature.
        let far: Vec<Point2<f64>> = arc(2.0, r, phi, k)
            .iter()
            .map(|p| Point2::new(4.0 - p.x, p.y))
            .collect();
        let g = point_features(&far, false);
        assert_abs_diff_eq!(at(&g, "mean_curvature"), -1.0 / r, epsilon = 1e-6);
        assert_abs_diff_eq!(
            at(&g, "inscribed_angle_mean"),
            PI - phi / 2.0,
            epsilon = 1e-9
        );
    }

    #[test]
    fn a_line_is_linear_flat_and_straight() {
        let pts: Vec<Point2<f64>> = (0..7)
            .map(|i| Point2::new(1.0 + 0.03 * i as f64, 0.5 + 0.04 * i as f64))
            .collect();
        let f = point_features(&pts, true);
        assert_abs_diff_eq!(at(&f, "linearity"), 0.0, epsilon = 1e-12);
        assert_abs_diff_eq!(at(&f, "width"), 0.3, epsilon = 1e-12);
        assert_abs_diff_eq!(at(&f, "length"), 0.3, epsilon = 1e-12);
        assert_abs_diff_eq!(at(&f, "boundary_length"), 0.3, epsilon = 1e-12);
        assert_abs_diff_eq!(at(&f, "mean_curvature"), 0.0, epsilon = 1e-9);
        assert_abs_diff_eq!(at(&f, "mean_angle"), PI, epsilon = 1e-9);
        assert_abs_diff_eq!(at(&f, "inscribed_angle_mean"), PI, epsilon = 1e-9);
        assert_eq!(at(&f, "radius"), MAX_RADIUS);
        assert_eq!(at(&f, "occluded"), 1.0);
        // Sample standard deviation about the centroid: spacing 0.05, offsets −3..3.
        let std = (0.05f64 * 0.05 * 28.0 / 6.0).sqrt();
        assert_abs_diff_eq!(at(&f, "std"), std, epsilon = 1e-12);
        assert_abs_diff_eq!(
            at(&f, "distance"),
            (1.09f64.powi(2) + 0.62f64.powi(2)).sqrt(),
            epsilon = 1e-12
        );
    }

    #[test]
    fn a_scan_marks_occluded_clusters() {
        // Beams 0..=2 at 1 m hide the start of a wall at 3 m (beams 3..=8).
        let mut ranges = vec![1.0, 1.0, 1.0];
        ranges.extend([3.0; 6]);
        let scan = LaserScan::new(0.0, 0.0, 0.01, 0.03, 11.0, ranges, vec![]).unwrap();
        let found = crate::detect::cluster::clusters(&scan, &Default::default()).unwrap();
        assert_eq!(found.len(), 2);
        assert_eq!(at(&cluster_features(&scan, &found[0]), "occluded"), 0.0);
        assert_eq!(at(&cluster_features(&scan, &found[1]), "occluded"), 1.0);
    }

    proptest::proptest! {
        #[test]
        fn features_are_invariant_to_rotation_about_the_laser(
            raw in proptest::collection::vec((0.5..6.0f64, -0.2..0.2f64), 1..25),
            angle in -PI..PI,
            occluded: bool,
        ) {
            // Points in beam order: sorted by bearing.
            let mut pts: Vec<Point2<f64>> = raw
                .iter()
                .enumerate()
                .map(|(i, &(r, dy))| Point2::new(r, dy + 0.01 * i as f64))
                .collect();
            pts.sort_by(|a, b| a.y.atan2(a.x).total_cmp(&b.y.atan2(b.x)));
            let rot = Rotation2::new(angle);
            let turned: Vec<Point2<f64>> = pts.iter().map(|p| rot * p).collect();
            let (a, b) = (point_features(&pts, occluded), point_features(&turned, occluded));
            for k in 0..FEATURES {
                let tol = 1e-6 * (1.0 + a[k].abs());
                proptest::prop_assert!(
                    (a[k] - b[k]).abs() <= tol || ((k == 7 || k == 8) && a[8] > 0.9 * MAX_RADIUS),
                    "{}: {} vs {}", FEATURE_NAMES[k], a[k], b[k]
                );
            }
            // The reverse scan direction gives the same features too.
            let mut back = pts.clone();
            back.reverse();
            let c = point_features(&back, occluded);
            for k in 0..FEATURES {
                let tol = 1e-6 * (1.0 + a[k].abs());
                proptest::prop_assert!(
                    (a[k] - c[k]).abs() <= tol || ((k == 7 || k == 8) && a[8] > 0.9 * MAX_RADIUS),
                    "reversed {}: {} vs {}", FEATURE_NAMES[k], a[k], c[k]
                );
            }
        }
    }
}
