//! Objects that come back patrol after patrol: table and chair legs, posts.
//!
//! The online [`StaticMap`](crate::detect::static_map::StaticMap) tells a post from a
//! person by seconds of stillness, which also turns a person who stands at a table for
//! minutes into furniture. A robot that patrols the same route several times a day (seed
//! 000 Fig. 7) has a stronger clue once the day is over: furniture is still there at the
//! next patrol, hours later, while the people have left. [`RecurringObjects`] is that clue.
//! From a day's scans and sensor poses, split into **sessions** wherever the stamps jump
//! by more than [`RecurringParams::session_gap`], it marks the cells (of side
//! [`RecurringParams::resolution`], in the world frame) where the detector's leg candidates
//! ([`Detector::candidates`]) fell in at least [`RecurringParams::min_scans`] scans of a
//! session, in at least [`RecurringParams::min_sessions`] sessions and at least
//! [`RecurringParams::min_session_fraction`] of the day's sessions. A day of one session
//! marks nothing: it cannot tell a long stay from furniture.
//!
//! It is a batch tool (the day's scans are all needed first), used by
//! [`OnlineTracker::with_recurring`](crate::track::online::OnlineTracker::with_recurring)
//! to drop the candidates on recurring objects before pairing and tracking.

use std::borrow::Borrow;
use std::collections::HashMap;

use haunts_occupancy::{LaserScan, Pose2};
use nalgebra::Point2;

use crate::detect::{Detector, rule};
use crate::{Result, TrackingError};

/// Parameters of [`RecurringObjects`].
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub struct RecurringParams {
    /// Stamps further apart than this start a new session, seconds.
    pub session_gap: f64,
    /// Side of a cell, metres.
    pub resolution: f64,
    /// Scans of one session in which a cell must hold a candidate for the session to count,
    /// so that a few stray candidates mark nothing.
    pub min_scans: usize,
    /// Sessions that must count for a cell (at least 2: one session cannot tell).
    pub min_sessions: usize,
    /// ... and at least this fraction of the day's sessions, in `[0, 1]`.
    pub min_session_fraction: f64,
    /// A point is on a recurring object when a marked cell's centre lies within this
    /// distance, metres (localisation error and a leg's estimated centre wander by a few
    /// centimetres).
    pub query_radius: f64,
}

impl Default for RecurringParams {
    /// Sessions separated by 10 minutes; 10 cm cells; a cell counts in a session with
    /// candidates in 5 scans, and recurs in at least 2 sessions and 80 % of them (4 of
    /// the pipeline's 5 daily patrols: a busy desk may hold someone at 3 patrols, a table
    /// leg is there at all of them but may be hidden behind a person at one); points
    /// within 3 cm of a marked cell (a person may stand a hand's width from a chair leg).
    fn default() -> Self {
        Self {
            session_gap: 600.0,
            resolution: 0.1,
            min_scans: 5,
            min_sessions: 2,
            min_session_fraction: 0.8,
            query_radius: 0.03,
        }
    }
}

impl RecurringParams {
    /// The parameters, if every rule holds.
    ///
    /// # Errors
    /// [`TrackingError::InvalidParameter`] naming the first parameter that breaks its rule:
    /// `session_gap` and `resolution` finite and > 0, `min_scans` ≥ 1, `min_sessions` ≥ 2,
    /// `min_session_fraction` in `[0, 1]`, `query_radius` finite and ≥ 0.
    pub fn check(self) -> Result<Self> {
        for (name, v) in [
            ("session_gap", self.session_gap),
            ("resolution", self.resolution),
        ] {
            haunts_core::positive(name, v)?;
        }
        rule(
            self.min_scans >= 1,
            "min_scans",
            self.min_scans as f64,
            ">= 1",
        )?;
        rule(
            self.min_sessions >= 2,
            "min_sessions",
            self.min_sessions as f64,
            ">= 2",
        )?;
        let f = self.min_session_fraction;
        rule(
            (0.0..=1.0).contains(&f),
            "min_session_fraction",
            f,
            "in [0, 1]",
        )?;
        let q = self.query_radius;
        rule(
            q.is_finite() && q >= 0.0,
            "query_radius",
            q,
            "finite and >= 0",
        )?;
        Ok(self)
    }
}

/// The cells of a day where leg candidates recur across sessions (see the
/// [module docs](self)).
///
/// # Example
/// ```
/// use haunts_occupancy::{LaserScan, Pose2};
/// use haunts_tracking::detect::{LegDetector, LegDetectorParams};
/// use haunts_tracking::detect::recurring::{RecurringObjects, RecurringParams};
/// use nalgebra::Point2;
///
/// // A post 2 m ahead (a few beams at 2 m in front of a far wall), seen in two patrols an
/// // hour apart.
/// let ranges: Vec<f64> = (0..181).map(|i| if (88..=92).contains(&i) { 2.0 } else { 8.0 }).collect();
/// let scan = |t: f64| LaserScan::new(t, -0.9, 0.01, 0.05, 20.0, ranges.clone(), vec![]);
/// let scans = [scan(0.0)?, scan(0.1)?, scan(0.2)?, scan(3600.0)?, scan(3600.1)?, scan(3600.2)?];
/// let poses = vec![Pose2::identity(); scans.len()];
/// let mut params = RecurringParams::default();
/// params.min_scans = 3;
/// let detector = LegDetector::new(LegDetectorParams::default())?;
/// let recurring = RecurringObjects::build(&detector, scans.iter().zip(&poses), params)?;
/// assert_eq!(recurring.sessions(), 2);
/// assert!(recurring.contains(&Point2::new(2.04, 0.0)));
/// assert!(!recurring.contains(&Point2::new(1.0, 1.0)));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(try_from = "RecurringObjectsFields"))]
pub struct RecurringObjects {
    params: RecurringParams,
    sessions: usize,
    /// Marked cells, sorted.
    cells: Vec<(i64, i64)>,
}

impl RecurringObjects {
    /// Marks the recurring cells of the scans (in time order) and the sensor poses they were
    /// taken from (world frame). Scans with a non-finite pose are skipped.
    ///
    /// # Errors
    /// As [`RecurringParams::check`]; [`TrackingError::TimeWentBackwards`] if a stamp is
    /// earlier than the one before; the detector's errors.
    pub fn build<S, P>(
        detector: &dyn Detector,
        scans: impl IntoIterator<Item = (S, P)>,
        params: RecurringParams,
    ) -> Result<Self>
    where
        S: Borrow<LaserScan>,
        P: Borrow<Pose2>,
    {
        let params = params.check()?;
        // Per cell: (session of the last count, scans in that session, sessions that counted).
        let mut counts: HashMap<(i64, i64), (usize, usize, usize)> = HashMap::new();
        let (mut session, mut last): (usize, Option<f64>) = (0, None);
        for (scan, pose) in scans {
            let (scan, pose) = (scan.borrow(), pose.borrow());
            if let Some(t) = last {
                if scan.stamp < t {
                    return Err(TrackingError::TimeWentBackwards {
                        previous: t,
                        time: scan.stamp,
                    });
                }
                if scan.stamp - t > params.session_gap {
                    session += 1;
                }
            }
            last = Some(scan.stamp);
            if !haunts_occupancy::pose_is_finite(pose) {
                continue;
            }
            let mut seen: Vec<(i64, i64)> = detector
                .candidates(scan)?
                .iter()
                .map(|p| cell_of(&(pose * p), params.resolution))
                .collect();
            seen.sort_unstable();
            seen.dedup();
            for cell in seen {
                let entry = counts.entry(cell).or_insert((session, 0, 0));
                if entry.0 != session {
                    *entry = (session, 0, entry.2);
                }
                entry.1 += 1;
                if entry.1 == params.min_scans {
                    entry.2 += 1;
                }
            }
        }
        let sessions = if last.is_some() { session + 1 } else { 0 };
        let needed = params
            .min_sessions
            .max((params.min_session_fraction * sessions as f64 - 1e-9).ceil() as usize);
        let mut cells: Vec<(i64, i64)> = counts
            .into_iter()
            .filter(|(_, (_, _, n))| *n >= needed)
            .map(|(cell, _)| cell)
            .collect();
        cells.sort_unstable();
        Ok(Self {
            params,
            sessions,
            cells,
        })
    }

    /// Sessions found in the scans.
    pub fn sessions(&self) -> usize {
        self.sessions
    }

    /// Number of marked cells.
    pub fn len(&self) -> usize {
        self.cells.len()
    }

    /// Whether nothing recurs.
    pub fn is_empty(&self) -> bool {
        self.cells.is_empty()
    }

    /// Centres of the marked cells, world frame.
    pub fn centres(&self) -> impl Iterator<Item = Point2<f64>> + '_ {
        let r = self.params.resolution;
        self.cells
            .iter()
            .map(move |&(i, j)| Point2::new((i as f64 + 0.5) * r, (j as f64 + 0.5) * r))
    }

    /// Whether `p` (world frame) lies within [`RecurringParams::query_radius`] of a marked
    /// cell (never for a non-finite `p`).
    ///
    /// # Complexity
    /// `O(log n + k)` for `n` marked cells, `k` of them in the columns within the query
    /// radius of `p`'s: the marked cells are searched, not the cells around `p`, so a far
    /// point or a radius of many cells (both valid: finite) costs at most `O(n)`, and the
    /// cell bounds, computed in `f64` and saturated to `i64`, never overflow.
    pub fn contains(&self, p: &Point2<f64>) -> bool {
        let (r, q) = (self.params.resolution, self.params.query_radius);
        if !(p.x.is_finite() && p.y.is_finite()) {
            return false;
        }
        let reach = (q / r).ceil();
        // The cell indices within `reach` of p's along one axis (saturating casts).
        let band = |v: f64| {
            let c = (v / r).floor();
            ((c - reach) as i64, (c + reach) as i64)
        };
        let ((i0, i1), (j0, j1)) = (band(p.x), band(p.y));
        let gap = |v: f64, k: i64| (v - (k as f64 + 0.5) * r).abs() - 0.5 * r;
        // The cells are sorted by column, then row: those of columns i0..=i1 start at the
        // first one not below (i0, j0).
        let first = self.cells.partition_point(|&c| c < (i0, j0));
        self.cells[first..]
            .iter()
            .take_while(|&&(i, _)| i <= i1)
            .any(|&(i, j)| {
                let (dx, dy) = (gap(p.x, i).max(0.0), gap(p.y, j).max(0.0));
                // `hypot`: squares of far distances would overflow to infinity.
                (j0..=j1).contains(&j) && dx.hypot(dy) <= q
            })
    }

    /// The parameters.
    pub fn params(&self) -> &RecurringParams {
        &self.params
    }
}

/// The cell holding `p` (floor of `p / resolution` per axis; saturating far away).
fn cell_of(p: &Point2<f64>, resolution: f64) -> (i64, i64) {
    (
        (p.x / resolution).floor() as i64,
        (p.y / resolution).floor() as i64,
    )
}

/// The fields of a [`RecurringObjects`] as deserialised, before they are checked.
#[cfg(feature = "serde")]
#[derive(serde::Deserialize)]
struct RecurringObjectsFields {
    params: RecurringParams,
    sessions: usize,
    cells: Vec<(i64, i64)>,
}

#[cfg(feature = "serde")]
impl TryFrom<RecurringObjectsFields> for RecurringObjects {
    type Error = TrackingError;
    /// The parameters must pass [`RecurringParams::check`]; the cells are sorted and
    /// deduplicated (a serialised map already is), as [`RecurringObjects::contains`] needs.
    fn try_from(f: RecurringObjectsFields) -> Result<Self> {
        let mut cells = f.cells;
        cells.sort_unstable();
        cells.dedup();
        Ok(Self {
            params: f.params.check()?,
            sessions: f.sessions,
            cells,
        })
    }
}
