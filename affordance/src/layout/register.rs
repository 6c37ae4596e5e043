//! Bringing a day recorded from another start pose into the library's frame: the day's map
//! registered onto the layouts' composite maps (global registration, then ICP refinement),
//! judged, and the day's counts resampled onto the library's cells.
//!
//! A robot's odometry starts wherever it was switched on, so two days of one room lie in
//! two frames. [`LayoutLibrary::register`] finds the transform of a day's frame into the
//! library's with the similarity crate's [`register_maps`](haunts_similarity::register_maps) (Harris corners, ring
//! descriptors, RANSAC + Umeyama, map-to-map ICP: seed 002's session registration) against
//! the composite map of every layout, keeps the layout it fits best, and accepts it only when
//! enough of the day's structure lies on the library's ([`RegisterParams`]). A day that
//! does not fit is refused ([`AffordanceError::NotRegistered`] saying why), never moved by a
//! wrong transform.

use haunts_occupancy::{Grid, GridGeometry, OccupancyGrid, Pose2};
use haunts_similarity::{
    GlobalParams, Length, SimilarityError, fit_at, register_maps_onto_each, resample_grid,
    resample_posed,
};

use super::{LayoutId, LayoutLibrary};
use crate::density::DailyDensity;
use crate::{AffordanceError, Result};

/// When a registration of a day onto the library is trusted.
///
/// The defaults were chosen on simulated office days from random start poses (`haunts-sim`
/// seed 0, 0.1 m cells; the facade's `tests/align_days.rs` keeps the measurement), not on the
/// real checks: registered correctly, days of every layout had 88–98 % inliers and residuals
/// of 0.052–0.057 m; placed 2, 3 or 5 cells or 2° or 5° off the truth, each had a residual
/// of 0.10–0.17 m or under 34 % inliers and is refused. The rules are a last check on what
/// the registration's ICP found, not a proof: with days whose frames were turned by quarter
/// turns, a pose 3 or 5 cells off along one wall direction kept 50–70 % of its cells within
/// two cells at 0.07–0.09 m and would have passed (BENCHMARKS.md).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub struct RegisterParams {
    /// The global registration (its own `min_overlap` refuses first; default
    /// [`GlobalParams::default`]).
    pub global: GlobalParams,
    /// Fewest share of the day's occupied cells within two cells of the layout's composite
    /// structure after alignment (default 0.5, the registration's own overlap rule). Furniture
    /// that moved since the layout's days and clutter seen only that day lower it.
    pub min_inliers: f64,
    /// Largest root mean square distance of those cells to the composite's nearest occupied
    /// cell (default one cell: walls registered onto walls lie within a cell; a transform
    /// that only grazes the structure spreads its inliers over the two-cell band, an RMS of
    /// about 1.2 cells).
    pub max_residual: Length,
}

impl Default for RegisterParams {
    fn default() -> Self {
        Self {
            global: GlobalParams::default(),
            min_inliers: 0.5,
            max_residual: Length::Cells(1.0),
        }
    }
}

impl RegisterParams {
    /// Sets the fewest inlier share.
    pub fn with_min_inliers(mut self, min_inliers: f64) -> Self {
        self.min_inliers = min_inliers;
        self
    }
    /// Sets the largest residual.
    pub fn with_max_residual(mut self, max_residual: Length) -> Self {
        self.max_residual = max_residual;
        self
    }
    /// Sets the global registration's parameters.
    pub fn with_global(mut self, global: GlobalParams) -> Self {
        self.global = global;
        self
    }

    /// The parameters after checking each rule.
    ///
    /// # Errors
    /// [`AffordanceError::InvalidParameter`] for an inlier share outside `[0, 1]` or a
    /// residual that is not finite and positive; the global registration's own errors.
    pub fn check(self) -> Result<Self> {
        haunts_core::fraction("min_inliers", self.min_inliers)?;
        let r = match self.max_residual {
            Length::Cells(v) | Length::Metres(v) => v,
        };
        haunts_core::positive("max_residual", r)?;
        self.global.check()?;
        Ok(self)
    }
}

/// The transform that brings a day's frame into the library's, with its evidence.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Registration {
    /// The day frame's pose in the library frame: x, metres.
    pub x: f64,
    /// y, metres.
    pub y: f64,
    /// Heading, radians in (−π, π].
    pub yaw: f64,
    /// Share of the day's occupied cells within two cells of the layout's composite
    /// structure under the transform.
    pub inliers: f64,
    /// Root mean square distance of those cells to the composite's nearest occupied cell,
    /// metres.
    pub residual: f64,
    /// The layout whose composite map the day was registered onto.
    pub layout: LayoutId,
    /// Whether the transform was given (a user's `--pose`) rather than found; a given one is
    /// measured but not judged.
    pub forced: bool,
}

impl Registration {
    /// The transform as a pose: day frame → library frame.
    pub fn pose(&self) -> Pose2 {
        Pose2::new(nalgebra::Vector2::new(self.x, self.y), self.yaw)
    }
}

/// Why a day was not registered onto the library.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum Refusal {
    /// The library has no layout with a composite structure to register onto.
    NoLayout,
    /// No transform passed the global registration (e.g. another building): its best
    /// hypothesis had `keypoint_inliers` consistent keypoint matches and put `overlap` of the
    /// day's structure on a layout's.
    NoReliableMatch {
        /// Keypoint matches consistent with the best hypothesis.
        keypoint_inliers: usize,
        /// Share of the day's occupied cells on the layout's structure under it.
        overlap: f64,
    },
    /// The best transform put too little of the day on the library.
    FewInliers {
        /// The best transform's inlier share.
        inliers: f64,
        /// The least accepted.
        min: f64,
    },
    /// The best transform's inliers lie too far from the library's structure.
    LargeResidual {
        /// Its residual, metres.
        residual: f64,
        /// The largest accepted, metres.
        max: f64,
    },
}

impl std::fmt::Display for Refusal {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match *self {
            Self::NoLayout => write!(f, "the library has no layout to register onto"),
            Self::NoReliableMatch {
                keypoint_inliers,
                overlap,
            } => write!(
                f,
                "no reliable match (best: {keypoint_inliers} consistent keypoint matches, \
                 {:.1} % of the day's structure on a layout's): another place?",
                100.0 * overlap
            ),
            Self::FewInliers { inliers, min } => write!(
                f,
                "only {:.1} % of the day's structure lies on the library's (at least {:.1} % \
                 needed)",
                100.0 * inliers,
                100.0 * min
            ),
            Self::LargeResidual { residual, max } => write!(
                f,
                "the day's structure lies {residual:.3} m from the library's (RMS; at most \
                 {max:.3} m accepted)"
            ),
        }
    }
}

impl LayoutLibrary {
    /// Registers a day's `map`, in its own frame (any geometry at the library's resolution),
    /// onto the library: onto the composite map of each layout in turn, keeping the
    /// transform with the largest inlier share (ties: the smaller residual, then the lower
    /// layout id), accepted only under `params`' rules.
    ///
    /// # Errors
    /// [`AffordanceError::NotRegistered`] with the [`Refusal`]: no layout, no reliable match
    /// (another place), too few inliers or too large a residual — the day must then not be
    /// merged; [`AffordanceError::EmptyDayMap`]; a resolution other than the library's
    /// ([`SimilarityError::ResolutionMismatch`]); bad parameters.
    ///
    /// # Complexity
    /// O(layouts · (cells + keypoints² + RANSAC iterations · matches)): one global
    /// registration per layout, the day's keypoints computed once.
    pub fn register(&self, map: &OccupancyGrid, params: &RegisterParams) -> Result<Registration> {
        let params = params.check()?;
        let targets = self.registration_targets()?;
        let maps: Vec<&OccupancyGrid> = targets.iter().map(|(_, map)| map).collect();
        let found = match register_maps_onto_each(&maps, map, &params.global) {
            Ok(found) => found,
            Err(SimilarityError::EmptyMap { index: 1 }) => {
                return Err(AffordanceError::EmptyDayMap);
            }
            Err(e) => return Err(e.into()),
        };
        let mut best: Option<Registration> = None;
        let mut refused = Refusal::NoLayout;
        for ((layout, _), found) in targets.iter().zip(found) {
            match found {
                Ok(m) => {
                    let (x, y) = (m.pose.translation.x, m.pose.translation.y);
                    let r = Registration {
                        x,
                        y,
                        yaw: m.pose.rotation.angle(),
                        inliers: m.overlap,
                        residual: m.residual,
                        layout: *layout,
                        forced: false,
                    };
                    let better = best.is_none_or(|b| {
                        r.inliers > b.inliers || (r.inliers == b.inliers && r.residual < b.residual)
                    });
                    if better {
                        best = Some(r);
                    }
                }
                Err(SimilarityError::NoReliableMatch { inliers, overlap }) => {
                    let worse = match refused {
                        Refusal::NoReliableMatch { overlap: o, .. } => overlap <= o,
                        _ => false,
                    };
                    if !worse {
                        refused = Refusal::NoReliableMatch {
                            keypoint_inliers: inliers,
                            overlap,
                        };
                    }
                }
                Err(e) => return Err(e.into()),
            }
        }
        let Some(best) = best else {
            return Err(AffordanceError::NotRegistered { refusal: refused });
        };
        let max =
            params.max_residual.cells(self.geometry.resolution()) * self.geometry.resolution();
        if best.inliers < params.min_inliers {
            return Err(AffordanceError::NotRegistered {
                refusal: Refusal::FewInliers {
                    inliers: best.inliers,
                    min: params.min_inliers,
                },
            });
        }
        if best.residual > max {
            return Err(AffordanceError::NotRegistered {
                refusal: Refusal::LargeResidual {
                    residual: best.residual,
                    max,
                },
            });
        }
        Ok(best)
    }

    /// How a day's `map` lies on the library when its frame is at `pose` in the library's
    /// (a transform given by the user): the layout it fits best and the inlier share and
    /// residual there, marked `forced`. Nothing is judged.
    ///
    /// # Errors
    /// [`AffordanceError::NotRegistered`] ([`Refusal::NoLayout`]) for a library without
    /// layouts; [`AffordanceError::EmptyDayMap`]; a resolution other than the library's.
    pub fn measure(&self, map: &OccupancyGrid, pose: &Pose2) -> Result<Registration> {
        let mut best: Option<Registration> = None;
        for (layout, target) in &self.registration_targets()? {
            let fit = fit_at(target, map, pose).map_err(|e| match e {
                SimilarityError::EmptyMap { index: 1 } => AffordanceError::EmptyDayMap,
                e => e.into(),
            })?;
            let r = Registration {
                x: pose.translation.x,
                y: pose.translation.y,
                yaw: pose.rotation.angle(),
                inliers: fit.overlap,
                residual: fit.residual,
                layout: *layout,
                forced: true,
            };
            if best.is_none_or(|b| r.inliers > b.inliers) {
                best = Some(r);
            }
        }
        best.ok_or(AffordanceError::NotRegistered {
            refusal: Refusal::NoLayout,
        })
    }

    /// The composite map of every layout that has structure, as registration targets.
    fn registration_targets(&self) -> Result<Vec<(LayoutId, OccupancyGrid)>> {
        let mut targets = Vec::new();
        for layout in &self.layouts {
            let map = layout
                .composite
                .static_map(self.params.composite_min_fraction)?;
            if map.values().data().contains(&100) {
                targets.push((layout.id, map));
            }
        }
        Ok(targets)
    }
}

/// A day's map and counts, in a frame at `pose` in the library's, resampled onto the
/// library's `geometry` by nearest neighbour (the similarity crate's [`resample_posed`] and
/// [`resample_grid`]): what [`LayoutLibrary::ingest`] then takes. Cells of the library the day
/// did not reach are unknown with no counts; the day's cells outside the library are left
/// out ([`MovedDay::outside`] counts its occupied ones).
///
/// # Errors
/// A resolution other than the library's; the density's own checks.
pub fn move_day(
    map: &OccupancyGrid,
    density: &DailyDensity,
    pose: &Pose2,
    geometry: &GridGeometry,
) -> Result<MovedDay> {
    let moved_map = resample_posed(map, geometry, pose)?;
    let counts = |g: &Grid<u32>| resample_grid(g, geometry, pose, 0);
    let moved_density = DailyDensity::new(
        counts(density.hits())?,
        counts(density.visits())?,
        density.min_visits(),
    )?;
    let outside = map
        .values()
        .cells()
        .filter(|(c, v)| {
            **v == 100
                && geometry
                    .world_to_cell(pose * map.geometry().cell_center(*c))
                    .is_none()
        })
        .count();
    Ok(MovedDay {
        map: moved_map,
        density: moved_density,
        outside,
    })
}

/// A day moved onto the library's cells by [`move_day`].
#[derive(Debug, Clone, PartialEq)]
pub struct MovedDay {
    /// The day's occupancy grid on the library's geometry.
    pub map: OccupancyGrid,
    /// Its hits and visits on the library's geometry.
    pub density: DailyDensity,
    /// The day's occupied cells that fell outside the library's geometry.
    pub outside: usize,
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::LayoutParams;
    use haunts_occupancy::{Cell, OCCUPIED};
    use nalgebra::{Point2, Vector2};

    /// The test-support floor plan drawn into `geometry` with its frame at `pose`.
    fn room(pose: &Pose2, geometry: GridGeometry) -> OccupancyGrid {
        let mut m = OccupancyGrid::unknown(geometry);
        for [x, y] in haunts_test_support::plan::wall_points() {
            if let Some(c) = geometry.world_to_cell(pose * Point2::new(x, y)) {
                m.set(c, OCCUPIED);
            }
        }
        m
    }

    fn library() -> LayoutLibrary {
        let g = GridGeometry::new(0.1, Point2::new(-1.0, -1.0), 140, 100).unwrap();
        let mut lib = LayoutLibrary::new(g, LayoutParams::default()).unwrap();
        let map = room(&Pose2::identity(), g);
        let zeros = Grid::filled(g, 0u32);
        let density = DailyDensity::new(zeros.clone(), zeros, 1).unwrap();
        lib.ingest("day 0", &map, &density).unwrap();
        lib
    }

    #[test]
    fn a_day_from_another_start_pose_is_registered_and_moved_onto_the_library() {
        let lib = library();
        // The day's frame lies at `truth` in the library's: the room seen from there.
        let truth = Pose2::new(Vector2::new(2.0, -1.5), 2.0);
        let g = GridGeometry::new(0.1, Point2::new(-14.0, -14.0), 280, 280).unwrap();
        let day = room(&truth.inverse(), g);
        let r = lib.register(&day, &RegisterParams::default()).unwrap();
        let err_t = (r.pose().translation.vector - truth.translation.vector).norm();
        let err_r = r.pose().rotation.angle_to(&truth.rotation).abs();
        assert!(err_t < 0.2 && err_r < 1f64.to_radians(), "{r:?}");
        assert!(r.inliers > 0.9 && r.residual < 0.1 && !r.forced, "{r:?}");
        // Moved onto the library's cells, the day classifies into the library's one layout.
        let mut hits = Grid::filled(g, 0u32);
        let cell = g
            .world_to_cell(truth.inverse() * Point2::new(6.0, 6.5))
            .unwrap();
        hits[cell] = 3;
        let visits = Grid::filled(g, 5u32);
        let density = DailyDensity::new(hits, visits, 1).unwrap();
        let moved = move_day(&day, &density, &r.pose(), lib.geometry()).unwrap();
        assert_eq!(moved.map.geometry(), lib.geometry());
        let at = lib.geometry().world_to_cell(Point2::new(6.0, 6.5)).unwrap();
        let near: u32 = (-1..=1)
            .flat_map(|dc| (-1..=1).map(move |dr| (dc, dr)))
            .filter_map(|(dc, dr)| {
                lib.geometry()
                    .checked_cell(at.col as i64 + dc, at.row as i64 + dr)
            })
            .map(|c| moved.density.hits()[c])
            .sum();
        assert!(near >= 3, "the hits moved with their cell: {near}");
        assert_eq!(moved.outside, 0);
        let c = lib.classify(&moved.map).unwrap();
        assert_eq!(c.layout, Some(LayoutId(0)), "{c:?}");
        // Measured at the truth, forced: the same evidence, nothing judged.
        let m = lib.measure(&day, &truth).unwrap();
        assert!(m.forced && m.inliers > 0.9, "{m:?}");
    }

    #[test]
    fn another_place_is_refused_not_moved() {
        let lib = library();
        // A plain corridor with doors.
        let g = GridGeometry::new(0.1, Point2::origin(), 200, 100).unwrap();
        let mut other = OccupancyGrid::unknown(g);
        for col in 0..200 {
            for row in [20, 60] {
                if col % 50 > 10 {
                    other.set(Cell::new(col, row), OCCUPIED);
                }
            }
        }
        let r = lib.register(&other, &RegisterParams::default());
        assert!(
            matches!(
                r,
                Err(AffordanceError::NotRegistered {
                    refusal: Refusal::NoReliableMatch { .. }
                })
            ),
            "{r:?}"
        );
        // A forced pose is measured, and says how little lies on the library.
        let m = lib.measure(&other, &Pose2::identity()).unwrap();
        assert!(m.inliers < 0.5, "{m:?}");
        // An empty library has nothing to register onto; an empty day nothing to register.
        let empty = LayoutLibrary::new(*lib.geometry(), LayoutParams::default()).unwrap();
        assert!(matches!(
            empty.register(&other, &RegisterParams::default()),
            Err(AffordanceError::NotRegistered {
                refusal: Refusal::NoLayout
            })
        ));
        assert!(matches!(
            lib.register(&OccupancyGrid::unknown(g), &RegisterParams::default()),
            Err(AffordanceError::EmptyDayMap)
        ));
        // Strict rules refuse a good match, with the figure that failed.
        let strict = RegisterParams::default().with_max_residual(Length::Metres(1e-6));
        let day = room(&Pose2::new(Vector2::new(0.3, 0.2), 0.1), g);
        let r = lib.register(&day, &strict);
        assert!(
            matches!(
                r,
                Err(AffordanceError::NotRegistered {
                    refusal: Refusal::LargeResidual { .. }
                })
            ),
            "{r:?}"
        );
        assert!(
            RegisterParams::default()
                .with_min_inliers(1.5)
                .check()
                .is_err()
        );
    }
}
