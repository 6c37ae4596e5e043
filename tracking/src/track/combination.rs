//! The Gaussian combination of seed 000 (section IV-A-2): recent detections kept as Gaussians,
//! weighted by a forgetting factor that falls linearly with their age.
//!
//! The combination is what the particle-filter tracker weighs its particles with, and what
//! decides when a new person is born; it can be evaluated at any point and any time.

use nalgebra::{Matrix2, Point2};

use crate::detect::{Detection, rule};
use crate::{Result, TrackingError};

/// Parameters of the particle tracker's Gaussian combination of detections (seed 000 IV-A-2):
/// each detection's weight falls linearly to 0 over `horizon` seconds.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub struct CombinationParams {
    /// Age at which a detection's forgetting factor reaches zero, seconds: the factor of a
    /// detection of age `a` is `1 − a / horizon`.
    pub horizon: f64,
    /// Detections whose forgetting factor has fallen below this are removed, in `(0, 1]`.
    pub min_factor: f64,
}

impl Default for CombinationParams {
    /// A 0.4 s memory (three scans at 7.5 Hz), forgetting below 0.05: at walking speed
    /// (1.3 m/s) a person's trail in the combination stays about half a metre long.
    fn default() -> Self {
        Self {
            horizon: 0.4,
            min_factor: 0.05,
        }
    }
}

impl CombinationParams {
    /// Sets [`CombinationParams::horizon`].
    pub fn with_horizon(mut self, v: f64) -> Self {
        self.horizon = v;
        self
    }
    /// Sets [`CombinationParams::min_factor`].
    pub fn with_min_factor(mut self, v: f64) -> Self {
        self.min_factor = v;
        self
    }

    /// The parameters, if `horizon` is finite and > 0 and `min_factor` in `(0, 1]`.
    ///
    /// # Errors
    /// [`TrackingError::InvalidParameter`] naming the parameter.
    pub fn check(self) -> Result<Self> {
        haunts_core::positive("horizon", self.horizon)?;
        rule(
            self.min_factor > 0.0 && self.min_factor <= 1.0,
            "min_factor",
            self.min_factor,
            "must be in (0, 1]",
        )?;
        Ok(self)
    }

    /// The forgetting factor of a detection `age` seconds old: `1 − age / horizon`, clamped
    /// to `[0, 1]`.
    pub fn factor(&self, age: f64) -> f64 {
        (1.0 - age / self.horizon).clamp(0.0, 1.0)
    }
}

/// One Gaussian of the combination.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Component {
    time: f64,
    mean: Point2<f64>,
    /// Entries of the inverse covariance: `[[a, b], [b, c]]`.
    inv: [f64; 3],
    /// `1 / (2π √det Σ)`, the peak of the normalised density.
    norm: f64,
    /// The detection's confidence.
    weight: f64,
    /// [`REACH`] standard deviations along the widest axis, metres.
    reach: f64,
}

/// Beyond this many standard deviations a Gaussian is left out of a [`Snapshot`]: it would
/// add less than `exp(−12.5) ≈ 3.7·10⁻⁶` of its weight.
const REACH: f64 = 5.0;

/// Detections kept as Gaussians and combined with a linear forgetting factor (seed 000,
/// IV-A-2):
///
/// `g(x, t) = Σₖ cₖ · f(t − tₖ) · exp(−½ (x − μₖ)ᵀ Σₖ⁻¹ (x − μₖ))`,
///
/// where `μₖ, Σₖ, cₖ` are the position, covariance and confidence of the detection made at
/// `tₖ`, and `f(a) = 1 − a / horizon` the forgetting factor. Each Gaussian is scaled to peak
/// at its weight, so `g` reads as "how many fresh detections support this point" and its
/// thresholds do not depend on the covariances; [`GaussianCombination::density`] gives the
/// normalised mixture instead. Detections whose factor falls below `min_factor` are removed.
///
/// Covariances must be symmetric positive definite: a singular one is rejected with a typed
/// error (never regularised silently).
///
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct GaussianCombination {
    params: CombinationParams,
    components: Vec<Component>,
    latest: Option<f64>,
}

impl GaussianCombination {
    /// An empty combination.
    ///
    /// # Errors
    /// As [`CombinationParams::check`].
    pub(crate) fn new(params: CombinationParams) -> Result<Self> {
        Ok(Self {
            params: params.check()?,
            components: Vec::new(),
            latest: None,
        })
    }

    /// Number of Gaussians kept.
    #[cfg(test)]
    pub(crate) fn len(&self) -> usize {
        self.components.len()
    }

    /// Whether no Gaussian is kept.
    #[cfg(test)]
    pub(crate) fn is_empty(&self) -> bool {
        self.components.is_empty()
    }

    /// The latest time given to [`GaussianCombination::add`] or
    /// [`GaussianCombination::forget`].
    #[cfg(test)]
    pub(crate) fn latest(&self) -> Option<f64> {
        self.latest
    }

    fn check_time(&self, time: f64) -> Result<()> {
        if !time.is_finite() {
            return Err(TrackingError::NonFiniteTime { time });
        }
        match self.latest {
            Some(previous) if time < previous => {
                Err(TrackingError::TimeWentBackwards { previous, time })
            }
            _ => Ok(()),
        }
    }

    /// Adds the detections made at `time`, all or none.
    ///
    /// # Errors
    /// [`TrackingError::NonFiniteTime`], [`TrackingError::TimeWentBackwards`] (earlier than
    /// the latest time seen), or the first bad detection's
    /// [`TrackingError::InvalidDetection`] / [`TrackingError::SingularCovariance`]; the
    /// combination is then unchanged.
    pub(crate) fn add(&mut self, time: f64, detections: &[Detection]) -> Result<()> {
        self.check_time(time)?;
        let mut new = Vec::with_capacity(detections.len());
        for (index, d) in detections.iter().enumerate() {
            let c = d.checked_covariance(index)?;
            new.push(component(time, d, &c));
        }
        self.components.extend(new);
        self.latest = Some(time);
        Ok(())
    }

    /// Removes the Gaussians whose forgetting factor at `now` is below `min_factor`, and
    /// returns how many were removed.
    ///
    /// # Errors
    /// [`TrackingError::NonFiniteTime`] or [`TrackingError::TimeWentBackwards`]; nothing is
    /// removed then.
    pub(crate) fn forget(&mut self, now: f64) -> Result<usize> {
        self.check_time(now)?;
        let before = self.components.len();
        let params = self.params;
        self.components
            .retain(|c| params.factor(now - c.time) >= params.min_factor);
        self.latest = Some(now);
        Ok(before - self.components.len())
    }

    /// Removes every Gaussian (the time order is kept).
    pub(crate) fn clear(&mut self) {
        self.components.clear();
    }

    /// `g(point, now)`: the combination with Gaussians scaled to peak at their weights.
    /// Gaussians newer than `now` count with factor 1.
    pub(crate) fn value(&self, now: f64, point: &Point2<f64>) -> f64 {
        self.components
            .iter()
            .map(|c| c.weight * self.params.factor(now - c.time) * kernel(c, point))
            .sum()
    }

    /// The normalised mixture at `point`: as [`GaussianCombination::value`] with each Gaussian
    /// a probability density (integral = weight × factor), per m².
    #[cfg(test)]
    pub(crate) fn density(&self, now: f64, point: &Point2<f64>) -> f64 {
        self.components
            .iter()
            .map(|c| c.weight * self.params.factor(now - c.time) * c.norm * kernel(c, point))
            .sum()
    }

    /// The combination frozen at `now` for the points within `radius` metres of `centre`
    /// (the whole plane for an infinite radius): the fast way to evaluate
    /// [`GaussianCombination::value`] at many points of one region, such as the particles
    /// of one person. Gaussians whose [`REACH`]-σ ellipse misses the disc are left out, so
    /// inside the disc the snapshot is below the full value by less than
    /// `3.7·10⁻⁶` times the total weight.
    pub(crate) fn snapshot(&self, now: f64, centre: &Point2<f64>, radius: f64) -> Snapshot {
        let terms = self
            .components
            .iter()
            .filter(|c| (c.mean - centre).norm() <= radius + c.reach)
            .filter_map(|c| {
                let scale = c.weight * self.params.factor(now - c.time);
                (scale > 0.0).then_some(Term {
                    mean: c.mean,
                    inv: c.inv,
                    scale,
                })
            })
            .collect();
        Snapshot { terms }
    }
}

fn component(time: f64, d: &Detection, c: &Matrix2<f64>) -> Component {
    let det = c[(0, 0)] * c[(1, 1)] - c[(0, 1)] * c[(1, 0)];
    Component {
        time,
        mean: d.position,
        inv: [c[(1, 1)] / det, -c[(0, 1)] / det, c[(0, 0)] / det],
        norm: 1.0 / (2.0 * std::f64::consts::PI * det.sqrt()),
        weight: d.confidence,
        reach: REACH * largest_eigenvalue(c).sqrt(),
    }
}

/// The larger eigenvalue of a symmetric 2 × 2 matrix.
fn largest_eigenvalue(c: &Matrix2<f64>) -> f64 {
    let half_trace = 0.5 * (c[(0, 0)] + c[(1, 1)]);
    let d = 0.5 * (c[(0, 0)] - c[(1, 1)]);
    half_trace + (d * d + c[(0, 1)] * c[(0, 1)]).sqrt()
}

fn kernel(c: &Component, point: &Point2<f64>) -> f64 {
    gauss(&c.mean, &c.inv, point)
}

#[inline]
fn gauss(mean: &Point2<f64>, inv: &[f64; 3], point: &Point2<f64>) -> f64 {
    let (dx, dy) = (point.x - mean.x, point.y - mean.y);
    let m = inv[0] * dx * dx + 2.0 * inv[1] * dx * dy + inv[2] * dy * dy;
    (-0.5 * m).exp()
}

/// One Gaussian of a [`Snapshot`], its weight and forgetting factor folded into `scale`.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Term {
    mean: Point2<f64>,
    inv: [f64; 3],
    scale: f64,
}

/// A [`GaussianCombination`] frozen at one time (see [`GaussianCombination::snapshot`]).
#[derive(Debug, Clone, Default, PartialEq)]
pub(crate) struct Snapshot {
    terms: Vec<Term>,
}

impl Snapshot {
    /// The combination's value at `point` (as [`GaussianCombination::value`]).
    pub(crate) fn value(&self, point: &Point2<f64>) -> f64 {
        self.terms
            .iter()
            .map(|t| t.scale * gauss(&t.mean, &t.inv, point))
            .sum()
    }

    /// Number of Gaussians kept.
    #[cfg(test)]
    pub(crate) fn len(&self) -> usize {
        self.terms.len()
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn one_detection_fades_linearly_and_is_forgotten_after_the_horizon() {
        let params = CombinationParams::default().with_horizon(1.0);
        let mut g = GaussianCombination::new(params).unwrap();
        g.add(10.0, &[det(1.0, 2.0, 0.1)]).unwrap();
        // Fresh, at the mean: the full weight; half a second later: half of it.
        assert_relative_eq!(g.value(10.0, &Point2::new(1.0, 2.0)), 1.0);
        assert_relative_eq!(g.value(10.5, &Point2::new(1.0, 2.0)), 0.5);
        // One standard deviation away: exp(-1/2).
        assert_relative_eq!(
            g.value(10.0, &Point2::new(1.1, 2.0)),
            (-0.5f64).exp(),
            epsilon = 1e-12
        );
        // After the horizon the detection is forgotten.
        assert_eq!(g.forget(11.0).unwrap(), 1);
        assert!(g.is_empty());
    }

    fn det(x: f64, y: f64, std: f64) -> Detection {
        Detection::isotropic(Point2::new(x, y), std)
    }

    #[test]
    fn parameters_are_checked() {
        let d = CombinationParams::default();
        for (params, name) in [
            (d.with_horizon(0.0), "horizon"),
            (d.with_horizon(f64::INFINITY), "horizon"),
            (d.with_min_factor(0.0), "min_factor"),
            (d.with_min_factor(1.5), "min_factor"),
        ] {
            assert!(matches!(
                GaussianCombination::new(params),
                Err(TrackingError::InvalidParameter(haunts_core::InvalidParameter { name: n, .. })) if n == name
            ));
        }
    }

    #[test]
    fn forgetting_is_linear_and_drops_old_gaussians() {
        let params = CombinationParams::default()
            .with_horizon(2.0)
            .with_min_factor(0.3);
        let mut g = GaussianCombination::new(params).unwrap();
        g.add(0.0, &[det(0.0, 0.0, 0.2)]).unwrap();
        g.add(1.0, &[det(0.0, 0.0, 0.2)]).unwrap();
        let origin = Point2::origin();
        // At t = 1: factors 0.5 and 1.
        assert_relative_eq!(g.value(1.0, &origin), 1.5, epsilon = 1e-12);
        // At t = 1.5: factors 0.25 (< 0.3, removed by forget) and 0.75.
        assert_relative_eq!(g.value(1.5, &origin), 1.0, epsilon = 1e-12);
        assert_eq!(g.forget(1.5).unwrap(), 1);
        assert_relative_eq!(g.value(1.5, &origin), 0.75, epsilon = 1e-12);
    }

    #[test]
    fn density_integrates_to_the_weight() {
        let mut g = GaussianCombination::new(CombinationParams::default()).unwrap();
        let d = Detection {
            position: Point2::new(1.0, -1.0),
            covariance: Matrix2::new(0.04, 0.01, 0.01, 0.02),
            confidence: 0.5,
        };
        g.add(3.0, &[d]).unwrap();
        let h = 0.01;
        let mut sum = 0.0;
        for i in -100..=100 {
            for j in -100..=100 {
                let p = Point2::new(1.0 + i as f64 * h, -1.0 + j as f64 * h);
                sum += g.density(3.0, &p) * h * h;
            }
        }
        assert_relative_eq!(sum, 0.5, epsilon = 1e-3);
    }

    #[test]
    fn a_snapshot_matches_the_full_sum_near_its_centre() {
        let mut g = GaussianCombination::new(CombinationParams::default()).unwrap();
        g.add(0.0, &[det(0.0, 0.0, 0.1), det(5.0, 0.0, 0.1)])
            .unwrap();
        g.add(0.1, &[det(0.1, 0.05, 0.15)]).unwrap();
        let snap = g.snapshot(0.2, &Point2::origin(), 1.0);
        assert_eq!(snap.len(), 2);
        let p = Point2::new(0.05, 0.02);
        assert_relative_eq!(snap.value(&p), g.value(0.2, &p), epsilon = 1e-12);
    }

    #[test]
    fn singular_covariances_and_time_reversal_leave_it_unchanged() {
        let mut g = GaussianCombination::new(CombinationParams::default()).unwrap();
        g.add(1.0, &[det(0.0, 0.0, 0.1)]).unwrap();
        let flat = Detection {
            covariance: Matrix2::new(0.01, 0.0, 0.0, 0.0),
            ..det(1.0, 1.0, 0.1)
        };
        assert!(matches!(
            g.add(2.0, &[det(0.0, 0.0, 0.1), flat]),
            Err(TrackingError::SingularCovariance { index: 1 })
        ));
        assert!(matches!(
            g.add(0.5, &[det(0.0, 0.0, 0.1)]),
            Err(TrackingError::TimeWentBackwards { .. })
        ));
        assert!(matches!(
            g.forget(f64::NAN),
            Err(TrackingError::NonFiniteTime { .. })
        ));
        assert_eq!(g.len(), 1);
        assert_eq!(g.latest(), Some(1.0));
    }
}
