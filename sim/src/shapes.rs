//! Analytic 2-D shapes the laser sees: exact ray intersection, angular extent and
//! rasterisation onto grid cells.

use nalgebra::{Point2, Rotation2, Vector2};

/// A solid 2-D shape of the simulated world.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Shape {
    /// A disc (a table, chair or human leg).
    Circle {
        /// Centre, metres.
        center: Point2<f64>,
        /// Radius, metres.
        radius: f64,
    },
    /// An oriented rectangle (a wall, sofa or cabinet).
    Rect {
        /// Centre, metres.
        center: Point2<f64>,
        /// Half extents along the rectangle's own axes, metres.
        half: Vector2<f64>,
        /// Rotation of the rectangle's x axis from the world x axis, radians.
        angle: f64,
    },
    /// A segment of zero thickness (a thin wall or glass pane edge).
    Segment {
        /// One end.
        a: Point2<f64>,
        /// The other end.
        b: Point2<f64>,
    },
}

#[cfg(test)]
fn cross(a: Vector2<f64>, b: Vector2<f64>) -> f64 {
    a.x * b.y - a.y * b.x
}

/// `angle` wrapped into `(-π, π]`.
pub(crate) fn wrap_angle(angle: f64) -> f64 {
    let w = angle.rem_euclid(std::f64::consts::TAU);
    if w > std::f64::consts::PI {
        w - std::f64::consts::TAU
    } else {
        w
    }
}

impl Shape {
    /// An axis-aligned rectangle from its lower-left and upper-right corners.
    pub fn aabb(min: Point2<f64>, max: Point2<f64>) -> Self {
        Self::Rect {
            center: nalgebra::center(&min, &max),
            half: (max - min).abs() / 2.0,
            angle: 0.0,
        }
    }

    /// Whether every number is finite and every size non-negative (circles: radius > 0).
    pub(crate) fn is_valid(&self) -> bool {
        match *self {
            Self::Circle { center, radius } => {
                center.iter().all(|v| v.is_finite()) && radius.is_finite() && radius > 0.0
            }
            Self::Rect {
                center,
                half,
                angle,
            } => {
                center.iter().all(|v| v.is_finite())
                    && half.iter().all(|v| v.is_finite() && *v >= 0.0)
                    && angle.is_finite()
            }
            Self::Segment { a, b } => a.iter().chain(b.iter()).all(|v| v.is_finite()),
        }
    }

    /// Distance along the ray `origin + t·dir` (`dir` a unit vector) to where it first enters
    /// the shape, for `t > 0`. A ray that starts inside a shape does not see it (`None`):
    /// a laser inside an obstacle has no meaningful reading of it. The plain reference the
    /// caster is tested against.
    ///
    /// Complexity: O(1).
    #[cfg(test)]
    pub(crate) fn ray_distance(&self, origin: Point2<f64>, dir: Vector2<f64>) -> Option<f64> {
        match *self {
            Self::Circle { center, radius } => {
                let m = origin - center;
                let c = m.norm_squared() - radius * radius;
                if c <= 0.0 {
                    return None;
                }
                ray_circle(m.dot(&dir), c)
            }
            Self::Rect {
                center,
                half,
                angle,
            } => {
                let (s, c) = angle.sin_cos();
                let m = origin - center;
                // Into the rectangle's frame (rotate by -angle).
                let o = [c * m.x + s * m.y, -s * m.x + c * m.y];
                let d = [c * dir.x + s * dir.y, -s * dir.x + c * dir.y];
                let h = [half.x, half.y];
                let (mut t0, mut t1) = (f64::NEG_INFINITY, f64::INFINITY);
                for k in 0..2 {
                    if d[k] == 0.0 {
                        if o[k].abs() > h[k] {
                            return None;
                        }
                    } else {
                        let inv = 1.0 / d[k];
                        let (a, b) = ((-h[k] - o[k]) * inv, (h[k] - o[k]) * inv);
                        let (a, b) = if a < b { (a, b) } else { (b, a) };
                        t0 = t0.max(a);
                        t1 = t1.min(b);
                    }
                }
                (t0 > 0.0 && t0 <= t1).then_some(t0)
            }
            Self::Segment { a, b } => {
                let e = b - a;
                let denom = cross(dir, e);
                if denom == 0.0 {
                    return None;
                }
                let w = a - origin;
                let t = cross(w, e) / denom;
                let u = cross(w, dir) / denom;
                (t > 0.0 && (0.0..=1.0).contains(&u)).then_some(t)
            }
        }
    }

    fn corners(&self) -> [Point2<f64>; 4] {
        match *self {
            Self::Circle { center, .. } => [center; 4],
            Self::Rect {
                center,
                half,
                angle,
            } => {
                let r = Rotation2::new(angle);
                [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
                    .map(|(sx, sy)| center + r * Vector2::new(sx * half.x, sy * half.y))
            }
            Self::Segment { a, b } => [a, b, b, a],
        }
    }

    /// Whether the shape overlaps the axis-aligned square of centre `c` and half side `h`
    /// (exact, by separating axes).
    pub(crate) fn overlaps_square(&self, c: Point2<f64>, h: f64) -> bool {
        match *self {
            Self::Circle { center, radius } => {
                let q = Point2::new(
                    center.x.clamp(c.x - h, c.x + h),
                    center.y.clamp(c.y - h, c.y + h),
                );
                (q - center).norm_squared() <= radius * radius
            }
            Self::Rect { .. } | Self::Segment { .. } => {
                let corners = self.corners();
                let sq = [
                    Point2::new(c.x - h, c.y - h),
                    Point2::new(c.x + h, c.y - h),
                    Point2::new(c.x + h, c.y + h),
                    Point2::new(c.x - h, c.y + h),
                ];
                let mut axes = vec![Vector2::x(), Vector2::y()];
                for i in 0..2 {
                    let e = corners[i + 1] - corners[i];
                    if e.norm() > 0.0 {
                        axes.push(Vector2::new(-e.y, e.x));
                    }
                }
                axes.iter().all(|ax| {
                    let proj = |pts: &[Point2<f64>; 4]| {
                        pts.iter()
                            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
                                let v = p.coords.dot(ax);
                                (lo.min(v), hi.max(v))
                            })
                    };
                    let (a0, a1) = proj(&corners);
                    let (b0, b1) = proj(&sq);
                    a0 <= b1 && b0 <= a1
                })
            }
        }
    }

    /// The axis-aligned bounding box `(min, max)`.
    pub fn bounds(&self) -> (Point2<f64>, Point2<f64>) {
        match *self {
            Self::Circle { center, radius } => (
                center - Vector2::repeat(radius),
                center + Vector2::repeat(radius),
            ),
            _ => {
                let c = self.corners();
                let lo = c
                    .iter()
                    .fold(Point2::new(f64::INFINITY, f64::INFINITY), |m, p| {
                        Point2::new(m.x.min(p.x), m.y.min(p.y))
                    });
                let hi = c
                    .iter()
                    .fold(Point2::new(f64::NEG_INFINITY, f64::NEG_INFINITY), |m, p| {
                        Point2::new(m.x.max(p.x), m.y.max(p.y))
                    });
                (lo, hi)
            }
        }
    }
}

/// The distance along a unit ray to a circle it starts outside of, from `b = m·d` and
/// `c = |m|² − r²` (`m` = origin − centre, `d` the direction): the nearer root of
/// `t² + 2bt + c = 0`, or `None` when the ray points away or misses.
#[inline]
pub(crate) fn ray_circle(b: f64, c: f64) -> Option<f64> {
    if b > 0.0 {
        return None;
    }
    let disc = b * b - c;
    if disc < 0.0 {
        return None;
    }
    let t = -b - disc.sqrt();
    (t > 0.0).then_some(t)
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn circle_rect_segment_hits() {
        let o = Point2::origin();
        let d = Vector2::x();
        let c = Shape::Circle {
            center: Point2::new(3.0, 0.0),
            radius: 0.5,
        };
        assert_relative_eq!(c.ray_distance(o, d).unwrap(), 2.5, epsilon = 1e-12);
        assert!(c.ray_distance(o, -d).is_none());
        let r = Shape::aabb(Point2::new(2.0, -1.0), Point2::new(4.0, 1.0));
        assert_relative_eq!(r.ray_distance(o, d).unwrap(), 2.0, epsilon = 1e-12);
        assert!(r.ray_distance(Point2::new(3.0, 0.0), d).is_none());
        let s = Shape::Segment {
            a: Point2::new(1.0, -1.0),
            b: Point2::new(1.0, 1.0),
        };
        assert_relative_eq!(s.ray_distance(o, d).unwrap(), 1.0, epsilon = 1e-12);
        assert!(s.ray_distance(o, Vector2::y()).is_none());
    }

    #[test]
    fn rotated_rect_distance_and_overlap() {
        let r = Shape::Rect {
            center: Point2::new(5.0, 0.0),
            half: Vector2::new(1.0, 0.1),
            angle: std::f64::consts::FRAC_PI_2,
        };
        // Rotated a quarter turn: 0.2 m thick along x.
        assert_relative_eq!(
            r.ray_distance(Point2::origin(), Vector2::x()).unwrap(),
            4.9,
            epsilon = 1e-12
        );
        assert!(r.overlaps_square(Point2::new(4.95, 0.95), 0.025));
        assert!(!r.overlaps_square(Point2::new(5.2, 0.0), 0.05));
    }
}
