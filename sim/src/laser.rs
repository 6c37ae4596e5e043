//! The simulated planar laser: exact ray casting against analytic shapes (nearest shapes
//! first, each only over the beams it can cover), then Gaussian range noise, dropouts and
//! max-range returns.
//!
//! Why analytic shapes rather than a raster: a beam's range is exact (no cell
//! quantisation, so leg circles of 6 cm are seen as circles), and the cost per scan is
//! O(shapes + beams · overlapping shapes) with an O(1) rejection of occluded shapes,
//! independent of the grid resolution.

use haunts_occupancy::{LaserScan, Pose2};
use nalgebra::{Point2, Vector2};
use rand::{RngExt, SeedableRng, rngs::Xoshiro256PlusPlus};
use rand_distr::StandardNormal;

use crate::error::{Result, SimError, invalid};
use crate::rng::{Stream, stream_seed};
use crate::shapes::{Shape, ray_circle};

/// Largest accepted number of beams per scan.
pub(crate) const MAX_BEAMS: usize = 100_000;

/// What a beam reports when nothing is within `range_max` (or on a spurious no-return).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum MaxRangeReturn {
    /// `+inf` (REP 117).
    Infinity,
    /// Exactly `range_max` (older drivers).
    RangeMax,
}

/// The laser's description and error model.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub struct LaserParams {
    /// Field of view, radians, centred on the robot's heading (`0 < fov ≤ 2π`).
    pub fov: f64,
    /// Angle between beams, radians.
    pub angular_resolution: f64,
    /// Shortest valid range, metres.
    pub range_min: f64,
    /// Longest range, metres.
    pub range_max: f64,
    /// Standard deviation of the Gaussian range noise, metres.
    pub noise_sd: f64,
    /// Probability that a beam returns NaN (no information).
    pub dropout: f64,
    /// Probability that a beam which hit something returns a max-range reading instead
    /// (dark or glossy surfaces).
    pub spurious_max_range: f64,
    /// What a max-range reading looks like.
    pub max_range_return: MaxRangeReturn,
    /// Scans per second.
    pub rate: f64,
}

impl Default for LaserParams {
    /// A Hokuyo UTM-30LX-like scanner decimated to 0.5°: 270°, 541 beams, 20 m, σ = 1 cm,
    /// 0.5 % dropouts, 0.2 % spurious max-range returns as `+inf`, 10 Hz.
    fn default() -> Self {
        Self {
            fov: 270f64.to_radians(),
            angular_resolution: 0.5f64.to_radians(),
            range_min: 0.05,
            range_max: 20.0,
            noise_sd: 0.01,
            dropout: 0.005,
            spurious_max_range: 0.002,
            max_range_return: MaxRangeReturn::Infinity,
            rate: 10.0,
        }
    }
}

impl LaserParams {
    /// The laser without noise, dropouts or spurious returns.
    pub fn noiseless(self) -> Self {
        Self {
            noise_sd: 0.0,
            dropout: 0.0,
            spurious_max_range: 0.0,
            ..self
        }
    }

    /// Number of beams: `fov / resolution + 1`, or `2π / resolution` for a full circle.
    pub fn beams(&self) -> usize {
        let n = self.fov / self.angular_resolution;
        if self.fov >= std::f64::consts::TAU - 1e-9 {
            (n.round() as usize).max(1)
        } else {
            ((n + 1e-9).floor() as usize).saturating_add(1)
        }
    }

    /// Angle of the first beam, radians (`-fov/2`).
    pub fn angle_min(&self) -> f64 {
        -self.fov / 2.0
    }

    /// The parameters if usable.
    ///
    /// # Errors
    /// [`SimError::InvalidParameter`] for a non-finite value, `fov` outside `(0, 2π]`, a
    /// resolution not in `(0, fov]`, `range_min < 0`, `range_max ≤ range_min`, a negative
    /// noise, a probability outside `[0, 1]` or a rate not in `(0, 1000]`;
    /// [`SimError::TooLarge`] for more than 100 000 beams.
    pub fn check(self) -> Result<Self> {
        let bad = |param, value, expected| Err(invalid(param, value, expected));
        if !(self.fov.is_finite() && self.fov > 0.0 && self.fov <= std::f64::consts::TAU + 1e-9) {
            return bad("laser.fov", self.fov, "in (0, 2π]");
        }
        if !(self.angular_resolution.is_finite()
            && self.angular_resolution > 0.0
            && self.angular_resolution <= self.fov)
        {
            return bad(
                "laser.angular_resolution",
                self.angular_resolution,
                "in (0, fov]",
            );
        }
        let beams = self.fov / self.angular_resolution;
        if beams > MAX_BEAMS as f64 {
            return Err(SimError::TooLarge {
                what: "beams per scan",
                count: beams,
                limit: MAX_BEAMS,
            });
        }
        if !(self.range_min.is_finite() && self.range_min >= 0.0) {
            return bad("laser.range_min", self.range_min, "finite and >= 0");
        }
        if !(self.range_max.is_finite() && self.range_max > self.range_min) {
            return bad("laser.range_max", self.range_max, "finite and > range_min");
        }
        if !(self.noise_sd.is_finite() && self.noise_sd >= 0.0) {
            return bad("laser.noise_sd", self.noise_sd, "finite and >= 0");
        }
        for (param, p) in [
            ("laser.dropout", self.dropout),
            ("laser.spurious_max_range", self.spurious_max_range),
        ] {
            if !(0.0..=1.0).contains(&p) {
                return bad(param, p, "in [0, 1]");
            }
        }
        if !(self.rate.is_finite() && self.rate > 0.0 && self.rate <= 1000.0) {
            return bad("laser.rate", self.rate, "in (0, 1000]");
        }
        Ok(self)
    }

    /// One scan at `stamp` from `pose`: exact ranges as [`crate::Simulator::exact_ranges`], then the
    /// error model with the laser stream of (`seed`, `day`, `index`). Also returns the exact
    /// ranges of the beams whose reading is a return (NaN for dropouts and max-range
    /// readings), which say what each returned beam hit.
    ///
    /// # Errors
    /// [`SimError::Occupancy`] if the scan description is rejected (not with checked
    /// parameters).
    pub(crate) fn scan(
        &self,
        caster: &Caster,
        pose: &Pose2,
        shapes: &[Shape],
        stamp: f64,
        stream: (u64, usize, usize),
    ) -> Result<(LaserScan, Vec<f64>)> {
        let (seed, day, index) = stream;
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(stream_seed(
            seed,
            day as u64,
            Stream::Laser,
            index as u64,
        ));
        let max_value = match self.max_range_return {
            MaxRangeReturn::Infinity => f64::INFINITY,
            MaxRangeReturn::RangeMax => self.range_max,
        };
        let mut exact_returns = caster.cast(pose, shapes);
        let ranges = exact_returns
            .iter_mut()
            .map(|exact_return| {
                let exact = *exact_return;
                *exact_return = f64::NAN;
                // Two uniforms from the two halves of one draw.
                let bits: u64 = rng.random();
                let scale = 1.0 / (1u64 << 32) as f64;
                let u_drop = (bits >> 32) as f64 * scale;
                let u_spur = (bits & 0xFFFF_FFFF) as f64 * scale;
                let noise: f64 = rng.sample(StandardNormal);
                if u_drop < self.dropout {
                    return f64::NAN;
                }
                if !exact.is_finite() || u_spur < self.spurious_max_range {
                    return max_value;
                }
                let r = exact + self.noise_sd * noise;
                if r >= self.range_max {
                    max_value
                } else {
                    *exact_return = exact;
                    r
                }
            })
            .collect();
        let scan = LaserScan::new(
            stamp,
            self.angle_min(),
            self.angular_resolution,
            self.range_min,
            self.range_max,
            ranges,
            Vec::new(),
        )?;
        Ok((scan, exact_returns))
    }
}

/// A shape prepared for one sensor position: what every beam's test needs, precomputed.
#[derive(Debug, Clone, Copy)]
enum Prim {
    /// `m` = sensor − centre, `c` = |m|² − r².
    Circle { m: Vector2<f64>, c: f64 },
    /// `w` = a − sensor, `e` = b − a, `we` = w × e.
    Segment {
        w: Vector2<f64>,
        e: Vector2<f64>,
        we: f64,
    },
}

impl Prim {
    /// Distance along the unit direction `dir` to the primitive, as
    /// [`Shape::ray_distance`].
    #[inline]
    fn hit(&self, dir: Vector2<f64>) -> Option<f64> {
        match *self {
            Self::Circle { m, c } => ray_circle(m.dot(&dir), c),
            Self::Segment { w, e, we } => {
                let denom = dir.x * e.y - dir.y * e.x;
                if denom == 0.0 {
                    return None;
                }
                let t = we / denom;
                let u = (w.x * dir.y - w.y * dir.x) / denom;
                (t > 0.0 && (0.0..=1.0).contains(&u)).then_some(t)
            }
        }
    }
}

/// Margin added to angular extents: well above the error of [`fast_atan2`].
const ATAN_MARGIN: f64 = 2e-3;

/// `atan2` to within 3e-4 rad (a 7th-order odd polynomial on [0, 1] and octant folding),
/// several times faster than libm's; only used to choose which beams to test.
fn fast_atan2(y: f64, x: f64) -> f64 {
    let (ax, ay) = (x.abs(), y.abs());
    let (lo, hi) = if ax < ay { (ax, ay) } else { (ay, ax) };
    if hi == 0.0 {
        return 0.0;
    }
    let a = lo / hi;
    let s = a * a;
    let mut r = ((-0.046_496_474_9 * s + 0.159_314_22) * s - 0.327_622_764) * s * a + a;
    if ay > ax {
        r = std::f64::consts::FRAC_PI_2 - r;
    }
    if x < 0.0 {
        r = std::f64::consts::PI - r;
    }
    if y < 0.0 { -r } else { r }
}

fn segment_distance(p: Point2<f64>, a: Point2<f64>, b: Point2<f64>) -> f64 {
    let e = b - a;
    let l2 = e.norm_squared();
    let f = if l2 > 0.0 {
        ((p - a).dot(&e) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (a + e * f - p).norm()
}

/// The ray caster of one laser: beam directions precomputed once, then per scan every
/// shape is reduced to primitives (circles, and the faces of rectangles that face the
/// sensor) sorted nearest first; each primitive is tested only on the beams of its angular
/// extent, and skipped on beams that already hit something nearer than it can be.
#[derive(Debug, Clone)]
pub(crate) struct Caster {
    local: Vec<Vector2<f64>>,
    angle_min: f64,
    inc: f64,
    range_max: f64,
}

impl Caster {
    pub(crate) fn new(params: &LaserParams) -> Self {
        let n = params.beams();
        let local = (0..n)
            .map(|i| {
                let a = params.angle_min() + i as f64 * params.angular_resolution;
                Vector2::new(a.cos(), a.sin())
            })
            .collect();
        Self {
            local,
            angle_min: params.angle_min(),
            inc: params.angular_resolution,
            range_max: params.range_max,
        }
    }

    fn prims(
        &self,
        o: Point2<f64>,
        shapes: &[Shape],
    ) -> Vec<(f64, Prim, Point2<f64>, Point2<f64>)> {
        let mut out = Vec::with_capacity(shapes.len() + 16);
        let segment = |out: &mut Vec<_>, a: Point2<f64>, b: Point2<f64>| {
            let bound = segment_distance(o, a, b);
            if bound < self.range_max {
                let (w, e) = (a - o, b - a);
                out.push((
                    bound,
                    Prim::Segment {
                        w,
                        e,
                        we: w.x * e.y - w.y * e.x,
                    },
                    a,
                    b,
                ));
            }
        };
        for s in shapes {
            match *s {
                Shape::Circle { center, radius } => {
                    let m = o - center;
                    let d = m.norm();
                    if d > radius && d - radius < self.range_max {
                        out.push((
                            d - radius,
                            Prim::Circle {
                                m,
                                c: m.norm_squared() - radius * radius,
                            },
                            center,
                            Point2::new(radius, 0.0),
                        ));
                    }
                }
                Shape::Segment { a, b } => segment(&mut out, a, b),
                Shape::Rect {
                    center,
                    half,
                    angle,
                } => {
                    let (sn, cs) = angle.sin_cos();
                    let ax = Vector2::new(cs, sn);
                    let ay = Vector2::new(-sn, cs);
                    let m = o - center;
                    let (lx, ly) = (m.dot(&ax), m.dot(&ay));
                    if lx.abs() <= half.x && ly.abs() <= half.y {
                        continue; // inside: not seen
                    }
                    let (hx, hy) = (ax * half.x, ay * half.y);
                    // The faces whose outside the sensor is on.
                    if lx > half.x {
                        segment(&mut out, center + hx - hy, center + hx + hy);
                    }
                    if lx < -half.x {
                        segment(&mut out, center - hx - hy, center - hx + hy);
                    }
                    if ly > half.y {
                        segment(&mut out, center - hx + hy, center + hx + hy);
                    }
                    if ly < -half.y {
                        segment(&mut out, center - hx - hy, center + hx - hy);
                    }
                }
            }
        }
        out
    }

    /// The unit direction of every beam in the sensor frame.
    pub(crate) fn directions(&self) -> &[Vector2<f64>] {
        &self.local
    }

    /// Angle of the first beam in the sensor frame, radians.
    pub(crate) fn angle_min(&self) -> f64 {
        self.angle_min
    }

    /// Angle between consecutive beams, radians.
    pub(crate) fn increment(&self) -> f64 {
        self.inc
    }

    pub(crate) fn cast(&self, pose: &Pose2, shapes: &[Shape]) -> Vec<f64> {
        let n = self.local.len();
        let mut ranges = vec![f64::INFINITY; n];
        let o = Point2::from(pose.translation.vector);
        let heading = pose.rotation.angle();
        let (sh, ch) = heading.sin_cos();
        let first = heading + self.angle_min;
        let inc = self.inc;
        let tau = std::f64::consts::TAU;
        let prims = self.prims(o, shapes);
        // Circles (legs: small, near, cheap) first in their given order, then the faces of
        // walls and solid furniture nearest first, so that beams already stopped nearer are
        // skipped with one comparison. The order changes only the speed, never the result.
        let mut order: Vec<(f64, u32)> = prims
            .iter()
            .enumerate()
            .map(|(k, p)| (p.0, k as u32))
            .collect();
        let (mut circles, mut faces): (Vec<_>, Vec<_>) = order
            .drain(..)
            .partition(|&(_, k)| matches!(prims[k as usize].1, Prim::Circle { .. }));
        faces.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        circles.extend(faces);
        order = circles;
        // Every beam's direction in the world frame, once per scan (not once per shape).
        let dirs: Vec<Vector2<f64>> = self
            .local
            .iter()
            .map(|l| Vector2::new(ch * l.x - sh * l.y, sh * l.x + ch * l.y))
            .collect();
        for &(bound, k) in &order {
            let (_, prim, a, b) = prims[k as usize];
            // Angular extent (centre, half width) seen from the sensor, widened by the
            // error of the fast arctangent: the exact test decides every beam in it.
            let (center, half) = match prim {
                Prim::Circle { m, c } => {
                    // tan(asin(r/d)) = r / √(d² − r²) bounds the half angle from above.
                    (fast_atan2(-m.y, -m.x), b.x / c.max(1e-300).sqrt())
                }
                Prim::Segment { .. } => {
                    let (va, vb) = (a - o, b - o);
                    let (aa, ab) = (fast_atan2(va.y, va.x), fast_atan2(vb.y, vb.x));
                    let d = crate::shapes::wrap_angle(ab - aa);
                    (aa + d / 2.0, d.abs() / 2.0)
                }
            };
            let half = half + ATAN_MARGIN;
            let lo = (center - half - first).rem_euclid(tau);
            let hi = lo + 2.0 * half;
            let eps = 1e-9;
            for shift in [0.0, tau] {
                let (x, y) = (lo - shift - eps, hi - shift + eps);
                if y < 0.0 {
                    continue;
                }
                let i0 = (x / inc).ceil().max(0.0) as usize;
                let i1 = ((y / inc).floor() as usize).min(n - 1);
                if i0 > i1 {
                    continue;
                }
                for (range, &dir) in ranges[i0..=i1].iter_mut().zip(&dirs[i0..=i1]) {
                    if *range <= bound {
                        continue;
                    }
                    if let Some(t) = prim.hit(dir) {
                        if t < *range {
                            *range = t;
                        }
                    }
                }
            }
        }
        for r in &mut ranges {
            if *r >= self.range_max {
                *r = f64::INFINITY;
            }
        }
        ranges
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use proptest::prelude::*;

    /// Reference: every beam against every shape.
    fn brute(l: &LaserParams, pose: &Pose2, shapes: &[Shape]) -> Vec<f64> {
        let o = Point2::from(pose.translation.vector);
        (0..l.beams())
            .map(|i| {
                let a = pose.rotation.angle() + l.angle_min() + i as f64 * l.angular_resolution;
                let d = Vector2::new(a.cos(), a.sin());
                let r = shapes
                    .iter()
                    .filter_map(|s| s.ray_distance(o, d))
                    .fold(f64::INFINITY, f64::min);
                if r >= l.range_max { f64::INFINITY } else { r }
            })
            .collect()
    }

    proptest! {
        #[test]
        fn culled_cast_equals_brute_force(
            x in -3.0f64..3.0, y in -3.0f64..3.0, h in -4.0f64..4.0,
            fov in 0.5f64..6.3,
            circles in proptest::collection::vec((-6.0f64..6.0, -6.0f64..6.0, 0.02f64..0.5), 0..12),
            rects in proptest::collection::vec((-6.0f64..6.0, -6.0f64..6.0, 0.05f64..2.0, 0.05f64..2.0, -3.0f64..3.0), 0..6),
        ) {
            let mut shapes: Vec<Shape> = circles.iter().map(|&(cx, cy, r)| Shape::Circle { center: Point2::new(cx, cy), radius: r }).collect();
            shapes.extend(rects.iter().map(|&(cx, cy, hx, hy, a)| Shape::Rect { center: Point2::new(cx, cy), half: Vector2::new(hx, hy), angle: a }));
            shapes.push(Shape::Segment { a: Point2::new(-7.0, 7.0), b: Point2::new(7.0, 7.5) });
            let l = LaserParams { fov: fov.min(std::f64::consts::TAU), range_max: 8.0, ..LaserParams::default() };
            let pose = Pose2::new(Vector2::new(x, y), h);
            let fast = Caster::new(&l).cast(&pose, &shapes);
            let slow = brute(&l, &pose, &shapes);
            for (a, b) in fast.iter().zip(&slow) {
                prop_assert!(a == b || (a - b).abs() < 1e-9, "{a} vs {b}");
            }
        }
    }

    #[test]
    fn fast_atan2_is_within_its_margin() {
        let worst = (0..100_000)
            .map(|i| {
                let a = -std::f64::consts::PI + i as f64 * std::f64::consts::TAU / 100_000.0;
                let r = 0.1 + (i % 17) as f64;
                let (y, x) = (r * a.sin(), r * a.cos());
                crate::shapes::wrap_angle(fast_atan2(y, x) - y.atan2(x)).abs()
            })
            .fold(0.0, f64::max);
        assert!(worst < ATAN_MARGIN / 5.0, "worst error {worst}");
    }

    #[test]
    fn wall_in_front_and_full_circle_beams() {
        let l = LaserParams {
            fov: std::f64::consts::TAU,
            angular_resolution: std::f64::consts::TAU / 360.0,
            ..LaserParams::default()
        };
        assert_eq!(l.beams(), 360);
        assert_eq!(LaserParams::default().beams(), 541);
        let wall = Shape::aabb(Point2::new(2.0, -10.0), Point2::new(2.1, 10.0));
        let r = Caster::new(&l).cast(&Pose2::identity(), &[wall]);
        // Beam 180 points along +x (angle_min = -π).
        assert_relative_eq!(r[180], 2.0, epsilon = 1e-12);
        assert!(r[0].is_infinite());
        let bad = LaserParams {
            angular_resolution: 0.0,
            ..LaserParams::default()
        };
        assert!(bad.check().is_err());
        let bad = LaserParams {
            dropout: 1.5,
            ..LaserParams::default()
        };
        assert!(bad.check().is_err());
    }
}
