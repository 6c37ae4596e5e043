//! Umeyama's closed-form least-squares transform between two sets of corresponding 2-D points
//! (Umeyama 1991; seed 002 §4.4 registers sessions with it).

use haunts_occupancy::Pose2;
use nalgebra::{Point2, Similarity2, Vector2};

use crate::error::{Result, SimilarityError};

/// A transform estimated from correspondences: `dst ≈ scale · R · src + t`.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct UmeyamaFit {
    /// Rotation and translation (`R`, `t`).
    pub pose: Pose2,
    /// Scale `s` (exactly 1 for [`umeyama_rigid`]).
    pub scale: f64,
    /// Root-mean-square distance between the transformed source points and the targets.
    pub rms: f64,
}

impl UmeyamaFit {
    /// The transform as an nalgebra similarity.
    pub fn similarity(&self) -> Similarity2<f64> {
        Similarity2::from_isometry(self.pose, self.scale)
    }
    /// `s · R · p + t`.
    pub fn transform(&self, p: &Point2<f64>) -> Point2<f64> {
        let v = self.pose.rotation * p.coords * self.scale + self.pose.translation.vector;
        Point2::from(v)
    }
}

/// The rotation and translation minimising Σ‖dst − (R·src + t)‖² (proper rotation, no
/// reflection).
///
/// In 2-D two distinct points fix a rotation, so collinear points are fine; what is refused is
/// a source (or target) whose points all coincide.
///
/// # Errors
/// [`SimilarityError::LengthMismatch`], [`SimilarityError::TooFew`] (fewer than 2 pairs),
/// [`SimilarityError::NonFinitePoint`], [`SimilarityError::Degenerate`] (coincident points, or
/// a cross-covariance too small to fix a rotation).
///
/// # Complexity
/// O(n).
///
/// # Example
/// ```
/// use haunts_similarity::umeyama_rigid;
/// use nalgebra::{Isometry2, Point2, Vector2};
/// let truth = Isometry2::new(Vector2::new(1.0, -2.0), 0.3);
/// let src = [Point2::new(0.0, 0.0), Point2::new(1.0, 0.0), Point2::new(0.0, 2.0)];
/// let dst: Vec<_> = src.iter().map(|p| truth * p).collect();
/// let fit = umeyama_rigid(&src, &dst).unwrap();
/// approx::assert_relative_eq!(fit.pose, truth, epsilon = 1e-12);
/// assert!(fit.rms < 1e-12);
/// ```
pub fn umeyama_rigid(src: &[Point2<f64>], dst: &[Point2<f64>]) -> Result<UmeyamaFit> {
    fit(src, dst, false)
}

/// The scale, rotation and translation minimising Σ‖dst − (s·R·src + t)‖² (Umeyama's
/// eq. 40–42, in the 2-D closed form: `θ = atan2(Σ x′×y′, Σ x′·y′)`,
/// `s = √((Σ x′·y′)² + (Σ x′×y′)²) / Σ‖x′‖²` for centred points).
///
/// # Errors
/// As [`umeyama_rigid`]; a target whose points all coincide is degenerate (`s` would be 0).
///
/// # Complexity
/// O(n).
pub fn umeyama_similarity(src: &[Point2<f64>], dst: &[Point2<f64>]) -> Result<UmeyamaFit> {
    fit(src, dst, true)
}

fn fit(src: &[Point2<f64>], dst: &[Point2<f64>], with_scale: bool) -> Result<UmeyamaFit> {
    if src.len() != dst.len() {
        return Err(SimilarityError::LengthMismatch {
            what: "correspondences (source vs target)",
            left: src.len(),
            right: dst.len(),
        });
    }
    if src.len() < 2 {
        return Err(SimilarityError::TooFew {
            what: "point pairs",
            found: src.len(),
            needed: 2,
        });
    }
    for (what, set) in [("source", src), ("target", dst)] {
        if let Some(index) = set
            .iter()
            .position(|p| !(p.x.is_finite() && p.y.is_finite()))
        {
            return Err(SimilarityError::NonFinitePoint { what, index });
        }
    }
    let n = src.len() as f64;
    let mean = |s: &[Point2<f64>]| s.iter().fold(Vector2::zeros(), |a, p| a + p.coords) / n;
    let (mx, my) = (mean(src), mean(dst));
    let (mut sxx, mut syy, mut dot, mut cross) = (0.0, 0.0, 0.0, 0.0);
    for (p, q) in src.iter().zip(dst) {
        let (x, y) = (p.coords - mx, q.coords - my);
        sxx += x.norm_squared();
        syy += y.norm_squared();
        dot += x.dot(&y);
        cross += x.perp(&y);
    }
    let spread = mx.norm().max(my.norm()).max(1.0);
    let tiny = (1e-12 * spread).powi(2) * n;
    if sxx <= tiny {
        return Err(SimilarityError::Degenerate {
            reason: "all source points coincide",
        });
    }
    if syy <= tiny {
        return Err(SimilarityError::Degenerate {
            reason: "all target points coincide",
        });
    }
    let strength = dot.hypot(cross);
    if strength <= 1e-12 * (sxx * syy).sqrt() {
        return Err(SimilarityError::Degenerate {
            reason: "the cross-covariance vanishes: no rotation is preferred",
        });
    }
    let angle = cross.atan2(dot);
    let scale = if with_scale { strength / sxx } else { 1.0 };
    let rotation = nalgebra::UnitComplex::new(angle);
    let t = my - rotation * mx * scale;
    let pose = Pose2::from_parts(t.into(), rotation);
    let result = UmeyamaFit {
        pose,
        scale,
        rms: 0.0,
    };
    let sse: f64 = src
        .iter()
        .zip(dst)
        .map(|(p, q)| (result.transform(p) - q).norm_squared())
        .sum();
    Ok(UmeyamaFit {
        rms: (sse / n).sqrt(),
        ..result
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use nalgebra::{Isometry2, Matrix2};
    use rand::{RngExt, SeedableRng, rngs::StdRng};
    use rand_distr::{Distribution, Normal};

    /// Umeyama's general algorithm with an SVD (eq. 39–42), as a reference.
    fn reference(src: &[Point2<f64>], dst: &[Point2<f64>]) -> (Matrix2<f64>, Vector2<f64>, f64) {
        let n = src.len() as f64;
        let mx = src.iter().fold(Vector2::zeros(), |a, p| a + p.coords) / n;
        let my = dst.iter().fold(Vector2::zeros(), |a, p| a + p.coords) / n;
        let mut sigma = Matrix2::zeros();
        let mut var = 0.0;
        for (p, q) in src.iter().zip(dst) {
            sigma += (q.coords - my) * (p.coords - mx).transpose() / n;
            var += (p.coords - mx).norm_squared() / n;
        }
        let svd = sigma.svd(true, true);
        let (u, vt) = (svd.u.unwrap(), svd.v_t.unwrap());
        let mut s = Matrix2::identity();
        if u.determinant() * vt.determinant() < 0.0 {
            s[(1, 1)] = -1.0;
        }
        let r = u * s * vt;
        let c = (Matrix2::from_diagonal(&svd.singular_values) * s).trace() / var;
        (r, my - c * r * mx, c)
    }

    fn fixture(seed: u64, n: usize, noise: f64) -> (Vec<Point2<f64>>, Vec<Point2<f64>>) {
        let mut rng = StdRng::seed_from_u64(seed);
        let truth = Similarity2::new(Vector2::new(3.5, -1.25), 2.2, 1.7);
        let normal = Normal::new(0.0, noise.max(1e-300)).unwrap();
        let src: Vec<_> = (0..n)
            .map(|_| Point2::new(rng.random_range(-5.0..5.0), rng.random_range(-2.0..8.0)))
            .collect();
        let dst = src
            .iter()
            .map(|p| {
                let q = truth * p;
                if noise > 0.0 {
                    q + Vector2::new(normal.sample(&mut rng), normal.sample(&mut rng))
                } else {
                    q
                }
            })
            .collect();
        (src, dst)
    }

    #[test]
    fn recovers_a_known_similarity_exactly_without_noise() {
        let (src, dst) = fixture(7, 30, 0.0);
        let fit = umeyama_similarity(&src, &dst).unwrap();
        assert_relative_eq!(fit.scale, 1.7, epsilon = 1e-9);
        assert_relative_eq!(fit.pose.rotation.angle(), 2.2, epsilon = 1e-9);
        assert_relative_eq!(
            fit.pose.translation.vector,
            Vector2::new(3.5, -1.25),
            epsilon = 1e-9
        );
        assert!(fit.rms < 1e-9);
    }

    #[test]
    fn noisy_fit_equals_the_svd_form_and_is_near_the_truth() {
        let (src, dst) = fixture(8, 200, 0.05);
        let fit = umeyama_similarity(&src, &dst).unwrap();
        let (r, t, c) = reference(&src, &dst);
        assert_relative_eq!(
            fit.pose.rotation.to_rotation_matrix().into_inner(),
            r,
            epsilon = 1e-9
        );
        assert_relative_eq!(fit.pose.translation.vector, t, epsilon = 1e-9);
        assert_relative_eq!(fit.scale, c, epsilon = 1e-9);
        assert_relative_eq!(fit.scale, 1.7, epsilon = 0.01);
        assert_relative_eq!(fit.pose.rotation.angle(), 2.2, epsilon = 0.01);
        assert_relative_eq!(fit.rms, 0.05 * 2f64.sqrt(), epsilon = 0.01);
        // Rigid: the least-squares rotation is the same; the translation absorbs no scale.
        let rigid = umeyama_rigid(&src, &dst).unwrap();
        assert_eq!(rigid.scale, 1.0);
        assert_relative_eq!(
            rigid.pose.rotation.angle(),
            fit.pose.rotation.angle(),
            epsilon = 1e-12
        );
    }

    #[test]
    fn two_points_and_collinear_points_are_enough() {
        let truth = Isometry2::new(Vector2::new(-1.0, 0.5), -2.9);
        let src = [
            Point2::new(0.0, 0.0),
            Point2::new(1.0, 1.0),
            Point2::new(3.0, 3.0),
        ];
        let dst: Vec<_> = src.iter().map(|p| truth * p).collect();
        assert_relative_eq!(
            umeyama_rigid(&src[..2], &dst[..2]).unwrap().pose,
            truth,
            epsilon = 1e-12
        );
        assert_relative_eq!(
            umeyama_rigid(&src, &dst).unwrap().pose,
            truth,
            epsilon = 1e-12
        );
    }

    #[test]
    fn degenerate_input_is_a_typed_error() {
        let p = Point2::new(1.0, 2.0);
        let q = Point2::new(3.0, -1.0);
        assert!(matches!(
            umeyama_rigid(&[p], &[q]),
            Err(SimilarityError::TooFew { found: 1, .. })
        ));
        assert!(matches!(
            umeyama_rigid(&[p, q], &[q]),
            Err(SimilarityError::LengthMismatch { .. })
        ));
        assert!(matches!(
            umeyama_rigid(&[p, p, p], &[p, q, q]),
            Err(SimilarityError::Degenerate {
                reason: "all source points coincide"
            })
        ));
        assert!(matches!(
            umeyama_similarity(&[p, q], &[q, q]),
            Err(SimilarityError::Degenerate { .. })
        ));
        let nan = Point2::new(f64::NAN, 0.0);
        assert!(matches!(
            umeyama_rigid(&[p, q], &[q, nan]),
            Err(SimilarityError::NonFinitePoint {
                what: "target",
                index: 1
            })
        ));
        // Orthogonal arrangement: the cross-covariance is zero, every rotation fits equally.
        let src = [
            Point2::new(1.0, 0.0),
            Point2::new(-1.0, 0.0),
            Point2::new(0.0, 1.0),
            Point2::new(0.0, -1.0),
        ];
        let dst = [
            Point2::new(1.0, 0.0),
            Point2::new(-1.0, 0.0),
            Point2::new(0.0, -1.0),
            Point2::new(0.0, 1.0),
        ];
        assert!(matches!(
            umeyama_rigid(&src, &dst),
            Err(SimilarityError::Degenerate { .. })
        ));
    }
}
