//! The one rule for rows of coordinates far from the rest: every reader of positions
//! (detections, trajectories, CARMEN poses, odometry) applies [`BoundsRule`] before a grid is
//! sized on its rows, so that one glitch (a detection at x = 10⁷ m, a pose at 10⁵ m) is
//! skipped and counted instead of asking for a grid over the cell budget and failing the job.
//!
//! # The rule
//!
//! The *bulk* of the rows is the box between the `quantile` and `1 − quantile` order
//! statistics of x and of y (0.1 % and 99.9 % by default), trimming at least one row on each
//! side once there are `min_rows` (20) finite rows; fewer rows are too few to tell a glitch
//! from a sparse site, and their box is their bounding box. The box is grown on every side by
//! `margin + growth · D`, where `D` is the larger side of the bulk box (by default
//! 10 m + the box's own larger side, so the kept area is at least three times the bulk's width
//! across): a row outside the grown box is *far*. A row whose coordinates are NaN or infinite
//! is *non-finite*. Both kinds are skipped and counted; the job fails only when no usable row
//! remains ([`OccupancyError::NoUsableRows`]).
//!
//! [`BoundsRule::within`] replaces the bulk by a box the caller gives (a known site, a
//! library's grid): rows outside it are far.
//!
//! Why this reading: a site is buildings, and the sensor sees tens of metres; a real row
//! beyond the bulk lies within a building's width of it, while a glitch (a unit error, an
//! uninitialised pose) lies orders of magnitude away. Growing by the bulk's own size keeps a
//! sparse corridor that only 0.1 % of the rows reach, and the fixed margin keeps real rows of
//! a bulk that is a single spot. The kept rows keep their order, so the result of a job on good
//! rows plus far rows is the result on the good rows alone.
//!
//! ```
//! use haunts_occupancy::bounds::BoundsRule;
//! use nalgebra::Point2;
//! let mut rows: Vec<Point2<f64>> = (0..3000)
//!     .map(|i| Point2::new(f64::from(i % 60) * 0.5, f64::from(i / 60) * 0.4))
//!     .collect();
//! rows.push(Point2::new(1.0e7, 3.0)); // one glitch
//! rows.push(Point2::new(f64::NAN, 1.0));
//! let kept = BoundsRule::default().split("detections", rows, |p| *p)?;
//! assert_eq!(kept.rows.len(), 3000);
//! assert_eq!((kept.skipped.counts.far, kept.skipped.counts.non_finite), (1, 1));
//! assert_eq!(kept.skipped.counts.json(), r#"{"far":1,"non_finite":1}"#);
//! assert_eq!(kept.skipped.first_far[0].index, 3000);
//! # Ok::<(), haunts_occupancy::OccupancyError>(())
//! ```

use nalgebra::Point2;

use crate::{OccupancyError, Result};

/// How many skipped rows a [`SkipReport`] names ([`SkipReport::first_far`],
/// [`SkipReport::first_non_finite`]).
pub const KEEP_NAMED: usize = 5;

/// Where rows may lie (see the [module docs](self)).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct BoundsRule {
    /// Share of the rows trimmed on each side of each axis to find the bulk (0.001).
    pub quantile: f64,
    /// Fewest finite rows for which the bulk is trimmed at all (20).
    pub min_rows: usize,
    /// Fixed growth of the bulk box on every side, metres (10).
    pub margin: f64,
    /// Growth of the bulk box on every side per metre of its larger side (1).
    pub growth: f64,
    /// A box given by the caller, `(lower-left, upper-right)`, instead of the bulk.
    pub given: Option<(Point2<f64>, Point2<f64>)>,
}

impl Default for BoundsRule {
    fn default() -> Self {
        Self {
            quantile: 0.001,
            min_rows: 20,
            margin: 10.0,
            growth: 1.0,
            given: None,
        }
    }
}

/// Rows skipped by a [`BoundsRule`], by reason.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct RowCounts {
    /// Rows outside the kept box.
    pub far: usize,
    /// Rows with a NaN or infinite coordinate.
    pub non_finite: usize,
}

impl RowCounts {
    /// The counts as the JSON object every command prints: `{"far":n,"non_finite":n}`.
    pub fn json(&self) -> String {
        format!(
            "{{\"far\":{},\"non_finite\":{}}}",
            self.far, self.non_finite
        )
    }

    /// Rows skipped in all.
    pub fn total(&self) -> usize {
        self.far + self.non_finite
    }
}

impl std::ops::AddAssign for RowCounts {
    fn add_assign(&mut self, other: Self) {
        self.far += other.far;
        self.non_finite += other.non_finite;
    }
}

/// A row skipped as far: its index among the rows given and where it lay.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FarRow {
    /// 0-based index among the rows given to [`BoundsRule::split`].
    pub index: usize,
    /// Its position.
    pub position: Point2<f64>,
}

/// What a [`BoundsRule`] skipped: the counts, the first rows of each kind, and the box the
/// rest were kept in (the default: nothing skipped, an empty box at the origin).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SkipReport {
    /// How many rows were skipped, by reason.
    pub counts: RowCounts,
    /// The first far rows (up to [`KEEP_NAMED`]).
    pub first_far: Vec<FarRow>,
    /// The indices of the first non-finite rows (up to [`KEEP_NAMED`]).
    pub first_non_finite: Vec<usize>,
    /// The box rows were kept in, `(lower-left, upper-right)`.
    pub bounds: (Point2<f64>, Point2<f64>),
}

/// The rows a [`BoundsRule`] kept, in their order, and what it skipped.
#[derive(Debug, Clone, PartialEq)]
pub struct Kept<T> {
    /// The kept rows, in the order given.
    pub rows: Vec<T>,
    /// What was skipped.
    pub skipped: SkipReport,
}

impl<T> Kept<T> {
    /// The same report around other rows (the kept rows regrouped, say).
    pub fn with_rows<U>(self, rows: Vec<U>) -> Kept<U> {
        Kept {
            rows,
            skipped: self.skipped,
        }
    }
}

impl SkipReport {
    /// One line per named skipped row, for standard error, each opening with `row(index)`
    /// (a line number, say, or `"detection 17"`): `"…: (x, y) m lies outside the kept box
    /// … : skipped as far"`, `"…: a coordinate is not finite: skipped"`, and a last line
    /// counting the rows skipped but not named.
    pub fn describe(&self, row: impl Fn(usize) -> String) -> Vec<String> {
        let (lo, hi) = self.bounds;
        let far = self.first_far.iter().map(|r| {
            format!(
                "{}: ({:e}, {:e}) m lies outside the kept box ({:.1}, {:.1}) to ({:.1}, {:.1}) \
                 m: skipped as far",
                row(r.index),
                r.position.x,
                r.position.y,
                lo.x,
                lo.y,
                hi.x,
                hi.y
            )
        });
        let bad = self
            .first_non_finite
            .iter()
            .map(|&i| format!("{}: a coordinate is not finite: skipped", row(i)));
        let mut lines: Vec<String> = far.chain(bad).collect();
        let named = self.first_far.len() + self.first_non_finite.len();
        if self.counts.total() > named {
            lines.push(format!(
                "and {} more skipped rows",
                self.counts.total() - named
            ));
        }
        lines
    }
}

impl BoundsRule {
    /// The rule with a box the caller gives instead of the bulk.
    pub fn within(lower_left: Point2<f64>, upper_right: Point2<f64>) -> Self {
        Self {
            given: Some((lower_left, upper_right)),
            ..Self::default()
        }
    }

    /// Checks the parameters.
    ///
    /// # Errors
    /// [`OccupancyError::InvalidParameter`] for a quantile outside `[0, 0.5)`, a negative or
    /// non-finite margin or growth, or a given box that is not finite or not ordered.
    pub fn check(&self) -> Result<()> {
        if !(0.0..0.5).contains(&self.quantile) {
            return Err(haunts_core::InvalidParameter {
                name: "quantile",
                value: self.quantile,
                rule: "must be in [0, 0.5)",
            }
            .into());
        }
        haunts_core::non_negative("margin", self.margin)?;
        haunts_core::non_negative("growth", self.growth)?;
        if let Some((lo, hi)) = self.given {
            let finite = lo.iter().chain(hi.iter()).all(|v| v.is_finite());
            if !finite || lo.x > hi.x || lo.y > hi.y {
                return Err(haunts_core::InvalidParameter {
                    name: "given",
                    value: if finite { hi.x.min(hi.y) } else { f64::NAN },
                    rule: "a finite box with lower-left below upper-right",
                }
                .into());
            }
        }
        Ok(())
    }

    /// The box rows at `positions` would be kept in, `(lower-left, upper-right)`; `None` when
    /// no position is finite (and no box is given). Non-finite positions are ignored.
    ///
    /// # Complexity
    /// `O(n)` (selection, not sorting) for `n` positions.
    pub fn kept_box(
        &self,
        positions: impl IntoIterator<Item = Point2<f64>>,
    ) -> Option<(Point2<f64>, Point2<f64>)> {
        if let Some(given) = self.given {
            return Some(given);
        }
        let (mut xs, mut ys): (Vec<f64>, Vec<f64>) = positions
            .into_iter()
            .filter(|p| p.x.is_finite() && p.y.is_finite())
            .map(|p| (p.x, p.y))
            .unzip();
        let n = xs.len();
        if n == 0 {
            return None;
        }
        let trim = if n >= self.min_rows.max(3) {
            // Truncation is the rank of the quantile; at least one row on each side.
            ((self.quantile * n as f64).floor() as usize).clamp(1, (n - 1) / 2)
        } else {
            0
        };
        let (x0, x1) = order_statistics(&mut xs, trim);
        let (y0, y1) = order_statistics(&mut ys, trim);
        let grow = self.margin + self.growth * (x1 - x0).max(y1 - y0);
        Some((
            Point2::new(x0 - grow, y0 - grow),
            Point2::new(x1 + grow, y1 + grow),
        ))
    }

    /// Splits `rows` into those kept and those skipped as far or non-finite, by the position
    /// `position` gives each; the kept rows keep their order. `what` names the rows in the
    /// error.
    ///
    /// # Errors
    /// [`OccupancyError::InvalidParameter`] for a rule [`check`](Self::check) refuses;
    /// [`OccupancyError::NoUsableRows`] when no row is kept.
    pub fn split<T>(
        &self,
        what: &'static str,
        rows: Vec<T>,
        position: impl Fn(&T) -> Point2<f64>,
    ) -> Result<Kept<T>> {
        self.check()?;
        let given = rows.len();
        let bounds = self.kept_box(rows.iter().map(&position));
        let mut kept = Vec::with_capacity(rows.len());
        let mut report = SkipReport {
            counts: RowCounts::default(),
            first_far: Vec::new(),
            first_non_finite: Vec::new(),
            bounds: bounds.unwrap_or((Point2::origin(), Point2::origin())),
        };
        for (index, row) in rows.into_iter().enumerate() {
            let p = position(&row);
            if !(p.x.is_finite() && p.y.is_finite()) {
                report.counts.non_finite += 1;
                if report.first_non_finite.len() < KEEP_NAMED {
                    report.first_non_finite.push(index);
                }
            } else if bounds.is_some_and(|(lo, hi)| {
                (lo.x..=hi.x).contains(&p.x) && (lo.y..=hi.y).contains(&p.y)
            }) {
                kept.push(row);
            } else {
                report.counts.far += 1;
                if report.first_far.len() < KEEP_NAMED {
                    report.first_far.push(FarRow { index, position: p });
                }
            }
        }
        if kept.is_empty() {
            return Err(OccupancyError::NoUsableRows {
                what,
                given,
                far: report.counts.far,
                non_finite: report.counts.non_finite,
            });
        }
        Ok(Kept {
            rows: kept,
            skipped: report,
        })
    }
}

/// The `trim`-th smallest and `trim`-th largest of `values` (0-based), reordering them.
fn order_statistics(values: &mut [f64], trim: usize) -> (f64, f64) {
    let n = values.len();
    let (_, lo, _) = values.select_nth_unstable_by(trim, f64::total_cmp);
    let lo = *lo;
    let (_, hi, _) = values.select_nth_unstable_by(n - 1 - trim, f64::total_cmp);
    (lo, *hi)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The plain reading of the rule: sort, index, grow.
    fn slow_box(rule: &BoundsRule, points: &[Point2<f64>]) -> (Point2<f64>, Point2<f64>) {
        let mut xs: Vec<f64> = points.iter().map(|p| p.x).collect();
        let mut ys: Vec<f64> = points.iter().map(|p| p.y).collect();
        xs.sort_by(f64::total_cmp);
        ys.sort_by(f64::total_cmp);
        let n = xs.len();
        let mut trim = 0;
        if n >= rule.min_rows {
            trim = ((rule.quantile * n as f64) as usize).max(1);
        }
        let (x0, x1, y0, y1) = (xs[trim], xs[n - 1 - trim], ys[trim], ys[n - 1 - trim]);
        let g = rule.margin + rule.growth * (x1 - x0).max(y1 - y0);
        (Point2::new(x0 - g, y0 - g), Point2::new(x1 + g, y1 + g))
    }

    fn grid_points(n: u32) -> Vec<Point2<f64>> {
        (0..n)
            .map(|i| {
                let i = f64::from(i);
                Point2::new((i * 7.31).rem_euclid(40.0), (i * 3.17).rem_euclid(25.0))
            })
            .collect()
    }

    #[test]
    fn the_box_is_the_plain_readings() {
        let rule = BoundsRule::default();
        for n in [1, 5, 19, 20, 21, 999, 1000, 3001] {
            let points = grid_points(n);
            assert_eq!(
                rule.kept_box(points.iter().copied()),
                Some(slow_box(&rule, &points))
            );
        }
    }

    #[test]
    fn far_rows_are_skipped_and_the_rest_keep_their_order() {
        let good = grid_points(3000);
        let mut rows = good.clone();
        rows.insert(1234, Point2::new(1.0e7, 1.0));
        rows.insert(10, Point2::new(-3.0, -1.0e5));
        rows.push(Point2::new(f64::INFINITY, 0.0));
        let kept = BoundsRule::default().split("rows", rows, |p| *p).unwrap();
        assert_eq!(kept.rows, good);
        assert_eq!(
            kept.skipped.counts,
            RowCounts {
                far: 2,
                non_finite: 1
            }
        );
        let far: Vec<usize> = kept.skipped.first_far.iter().map(|r| r.index).collect();
        assert_eq!(far, [10, 1235]);
        assert_eq!(kept.skipped.first_non_finite, [3002]);
        let lines = kept.skipped.describe(|i| format!("row {i}"));
        assert_eq!(lines.len(), 3);
        assert!(
            lines[0].starts_with("row 10: (-3e0, -1e5) m lies outside"),
            "{}",
            lines[0]
        );
    }

    #[test]
    fn a_sparse_edge_of_the_site_is_kept() {
        // 99 % in a 10 m room, 1 % along a corridor 60 m long: nothing is far.
        let mut rows: Vec<Point2<f64>> = (0..2970)
            .map(|i| Point2::new(f64::from(i % 100) * 0.1, f64::from(i / 100) * 0.33))
            .collect();
        rows.extend((0..30).map(|i| Point2::new(10.0 + 2.0 * f64::from(i), 5.0)));
        let kept = BoundsRule::default().split("rows", rows, |p| *p).unwrap();
        assert_eq!(kept.skipped.counts, RowCounts::default());
        // A few rows alone are never trimmed: three people 50 m apart are all kept.
        let few = vec![
            Point2::new(0.0, 0.0),
            Point2::new(50.0, 0.0),
            Point2::new(0.0, 50.0),
        ];
        let kept = BoundsRule::default().split("rows", few, |p| *p).unwrap();
        assert_eq!(kept.rows.len(), 3);
    }

    #[test]
    fn a_given_box_and_nothing_usable() {
        let rule = BoundsRule::within(Point2::new(0.0, 0.0), Point2::new(10.0, 10.0));
        let kept = rule
            .split(
                "rows",
                vec![Point2::new(5.0, 5.0), Point2::new(11.0, 5.0)],
                |p| *p,
            )
            .unwrap();
        assert_eq!(kept.rows.len(), 1);
        assert_eq!(kept.skipped.counts.far, 1);
        let err = rule
            .split(
                "poses",
                vec![Point2::new(f64::NAN, 0.0), Point2::new(20.0, 0.0)],
                |p| *p,
            )
            .unwrap_err();
        assert!(matches!(
            err,
            OccupancyError::NoUsableRows {
                what: "poses",
                given: 2,
                far: 1,
                non_finite: 1
            }
        ));
        let empty: Vec<Point2<f64>> = Vec::new();
        assert!(BoundsRule::default().split("rows", empty, |p| *p).is_err());
        let bad = BoundsRule {
            quantile: 0.5,
            ..BoundsRule::default()
        };
        assert!(
            bad.split("rows", vec![Point2::new(0.0, 0.0)], |p| *p)
                .is_err()
        );
        let bad = BoundsRule::within(Point2::new(1.0, 0.0), Point2::new(0.0, 1.0));
        assert!(bad.check().is_err());
    }
}
