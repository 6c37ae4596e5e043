//! The hypertime projection (seed 001 eq. 1): a detection `(x, y, t)` becomes
//! `(x, y, cos 2πt/T₁, sin 2πt/T₁, …)`, one circle per period.

use nalgebra::Point2;

use crate::{AffordanceError, Result};

/// One day in seconds: the default (and the seed's only) period.
pub const DAY: f64 = 86_400.0;

/// A person seen at a place at a time: `time` in UNIX seconds, `position` in metres.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TimedPoint {
    /// UNIX time, seconds.
    pub time: f64,
    /// World position, metres.
    pub position: Point2<f64>,
}

impl TimedPoint {
    /// A detection at `(x, y)` metres and `time` seconds.
    pub fn new(time: f64, x: f64, y: f64) -> Self {
        Self {
            time,
            position: Point2::new(x, y),
        }
    }

    /// Whether the time and both coordinates are finite.
    pub fn is_finite(&self) -> bool {
        self.time.is_finite() && self.position.x.is_finite() && self.position.y.is_finite()
    }
}

/// The map from `(x, y, t)` to the hypertime space `(x, y, cos ω₁t, sin ω₁t, …)`,
/// `ωₖ = 2π/Tₖ`, of dimension `2 + 2·periods`. With no period it is the plain plane (the
/// time-independent baseline).
///
/// The phase is computed as `(t mod T)/T` before the trigonometric functions, so UNIX times
/// (~1.5·10⁹ s) lose no precision.
///
/// ```
/// use haunts_affordance::hypertime::{Projection, TimedPoint, DAY};
/// let p = Projection::new(vec![DAY])?;
/// let mut out = [0.0; 4];
/// p.project_into(&TimedPoint::new(6.0 * 3600.0, 1.0, 2.0), &mut out);
/// approx::assert_abs_diff_eq!(&out[..], &[1.0, 2.0, 0.0, 1.0][..], epsilon = 1e-12);
/// # Ok::<(), haunts_affordance::AffordanceError>(())
/// ```
///
/// With the `serde` feature it is written as `{"periods": [...]}`; loading checks the periods
/// as [`Projection::new`] does.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(try_from = "ProjectionFields"))]
pub struct Projection {
    periods: Vec<f64>,
}

impl Projection {
    /// The projection for `periods` (seconds, each finite, > 0 and distinct; may be empty).
    ///
    /// # Errors
    /// [`AffordanceError::InvalidParameter`] (`periods`) naming the first bad or repeated
    /// period.
    pub fn new(periods: Vec<f64>) -> Result<Self> {
        for (i, &p) in periods.iter().enumerate() {
            if !(p.is_finite() && p > 0.0) {
                return Err(AffordanceError::InvalidParameter(
                    haunts_core::InvalidParameter {
                        name: "periods",
                        value: p,
                        rule: "every period must be finite and > 0 s",
                    },
                ));
            }
            if periods[..i].contains(&p) {
                return Err(AffordanceError::InvalidParameter(
                    haunts_core::InvalidParameter {
                        name: "periods",
                        value: p,
                        rule: "periods must be distinct",
                    },
                ));
            }
        }
        Ok(Self { periods })
    }

    /// The periods, seconds, in the order of their dimension pairs.
    pub fn periods(&self) -> &[f64] {
        &self.periods
    }

    /// The dimension of the hypertime space, `2 + 2·periods`.
    pub fn dim(&self) -> usize {
        2 + 2 * self.periods.len()
    }

    /// Writes the time dimensions of `time`, `(cos ω₁t, sin ω₁t, …)`, into `out`
    /// (`2·periods` values).
    ///
    /// # Panics
    /// If `out` is shorter than `2·periods` (a programming error).
    pub(crate) fn time_features(&self, time: f64, out: &mut [f64]) {
        for (pair, &period) in out.chunks_exact_mut(2).zip(&self.periods) {
            let phase = std::f64::consts::TAU * (time.rem_euclid(period) / period);
            let (s, c) = phase.sin_cos();
            pair[0] = c;
            pair[1] = s;
        }
    }

    /// Writes the hypertime coordinates of `point` into `out` (`dim()` values).
    ///
    /// # Panics
    /// If `out` is shorter than [`dim`](Self::dim) (a programming error).
    pub fn project_into(&self, point: &TimedPoint, out: &mut [f64]) {
        out[0] = point.position.x;
        out[1] = point.position.y;
        self.time_features(point.time, &mut out[2..self.dim()]);
    }

    /// The hypertime coordinates of the finite points, flat and row-major (`dim()` values per
    /// row), with how many non-finite points were skipped.
    pub(crate) fn project(&self, points: &[TimedPoint]) -> Projected {
        let dim = self.dim();
        let mut rows = Vec::with_capacity(points.len() * dim);
        let mut times = Vec::with_capacity(points.len());
        let mut row = vec![0.0; dim];
        for p in points.iter().filter(|p| p.is_finite()) {
            self.project_into(p, &mut row);
            rows.extend_from_slice(&row);
            times.push(p.time);
        }
        Projected {
            dim,
            skipped: points.len() - times.len(),
            rows,
            times,
        }
    }
}

/// The fields of a [`Projection`] as deserialised, before [`Projection::new`] checks them.
#[cfg(feature = "serde")]
#[derive(serde::Deserialize)]
struct ProjectionFields {
    periods: Vec<f64>,
}

#[cfg(feature = "serde")]
impl TryFrom<ProjectionFields> for Projection {
    type Error = AffordanceError;
    fn try_from(f: ProjectionFields) -> Result<Self> {
        Self::new(f.periods)
    }
}

/// Points in hypertime coordinates (see [`Projection::project`]).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Projected {
    /// Values per row.
    pub(crate) dim: usize,
    /// The rows, flat and row-major.
    pub(crate) rows: Vec<f64>,
    /// The time of each row, seconds.
    pub(crate) times: Vec<f64>,
    /// Input points skipped because a coordinate or the time was not finite.
    pub(crate) skipped: usize,
}

impl Projected {
    /// Number of rows.
    pub(crate) fn len(&self) -> usize {
        self.times.len()
    }

    /// Whether there is no row.
    pub(crate) fn is_empty(&self) -> bool {
        self.times.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn project_skips_points_with_a_non_finite_time_or_coordinate() {
        let p = Projection::new(vec![DAY, 3600.0]).unwrap();
        let projected = p.project(&[
            TimedPoint::new(0.0, 0.0, 0.0),
            TimedPoint::new(f64::NAN, 0.0, 0.0),
            TimedPoint::new(1.0, f64::INFINITY, 0.0),
        ]);
        assert_eq!((projected.len(), projected.skipped), (1, 2));
        assert_eq!(projected.rows.len(), projected.dim);
        let mut tau = [0.0; 4];
        p.time_features(0.0, &mut tau);
        assert_eq!(tau, [1.0, 0.0, 1.0, 0.0]);
    }
}
