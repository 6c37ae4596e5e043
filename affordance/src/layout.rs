//! The layout library (seed 000 Fig. 2): days grouped by furniture layout, each layout with
//! its geometric composite and its affordance composite.
//!
//! Every day brings its occupancy map (aligned to the library's reference geometry) and its
//! daily hits and visits ([`DailyDensity`]). [`LayoutLibrary::ingest`] compares the map with
//! each stored layout's composite map by seed 000 III-C's distance-field difference (the
//! similarity crate's [`directed_difference`] in both directions, combined and thresholded by
//! its [`ClusterParams`] and [`LayoutThreshold`](haunts_similarity::LayoutThreshold), the
//! measure its [`greedy_layouts`] clusters days with), then either joins the best matching
//! layout — adding the map to its [`GeometricComposite`] and the counts to its
//! [`CumulativeDensity`] (Σ hits / Σ visits) — or starts a new layout.
//!
//! A layout's *composite map*, the map days are compared with, is the structure occupied in at
//! least [`LayoutParams::composite_min_fraction`] of its days
//! ([`GeometricComposite::static_structure`]; default: half). Furniture that moves by less
//! than its own thickness between days survives the majority; thin structure that jitters
//! further thins out (lower the fraction to keep it, at the price of keeping clutter).
//!
//! The paper clusters all days at once (III-D); the library does it incrementally, as its
//! Fig. 2 draws it, so a day's layout depends only on the days before it.
//!
//! The library is saved to and loaded from one file, atomically; the format is described in
//! [`file`](mod@file).

pub mod file;
pub mod register;

use haunts_occupancy::GeometricComposite;
use haunts_occupancy::{CellState, Grid, GridGeometry, OccupancyGrid};
use haunts_similarity::{
    ClusterParams, DifferenceParams, PreparedMap, SimilarityError, SimilarityMatrix,
    directed_difference, greedy_layouts,
};

use crate::density::{CumulativeDensity, DailyDensity, check_geometry};
use crate::{AffordanceError, Result};

/// Parameters of the layout library.
///
/// With the `serde` feature the similarity parameters are written as serde's derive would
/// write them: `{"difference": {"cutoff": {"Metres": 0.5}}, "cluster": {"threshold":
/// {"SquareMetres": 3.25}, "symmetrisation": "Max"}, …}`.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub struct LayoutParams {
    /// The distance-field difference (its cutoff `ct`, default 0.5 m: seed 000's 10 cells).
    pub difference: DifferenceParams,
    /// When a day matches a layout (default: the seed's 1300 cells² at 0.05 m, as 3.25 m²,
    /// the larger of the two directions).
    pub cluster: ClusterParams,
    /// Fraction of a layout's days in which a cell must be occupied to belong to the layout's
    /// composite map (default 0.5), in `(0, 1]`.
    pub composite_min_fraction: f64,
    /// Fewest Σ visits for a known affordance density (default 1).
    pub min_visits: u32,
    /// Whether a day and a layout are compared only where both observed (default `true`):
    /// the layout's structure counts against the day only in cells the day observed (free or
    /// occupied), the day's only in cells some day of the layout observed. Seed 000 compares
    /// whole maps of days that each toured the whole building; a day recorded from another
    /// start pose and moved into the library's frame ([`LayoutLibrary::register`]) covers
    /// another box of the building, and a cell nobody looked at is no evidence that the
    /// furniture moved. On leg_tracker's `general_tracking_moving_1` moved onto itself the
    /// whole-map difference is 3.58 m², over the seed's 3.25 m² threshold: the same room
    /// would start a new layout. Libraries saved without it read as `true`.
    #[cfg_attr(feature = "serde", serde(default = "observed_only_default"))]
    pub observed_only: bool,
}

#[cfg(feature = "serde")]
fn observed_only_default() -> bool {
    true
}

impl Default for LayoutParams {
    fn default() -> Self {
        Self {
            difference: DifferenceParams::default(),
            cluster: ClusterParams::default(),
            composite_min_fraction: 0.5,
            min_visits: 1,
            observed_only: true,
        }
    }
}

impl LayoutParams {
    /// Sets the difference parameters.
    pub fn with_difference(mut self, difference: DifferenceParams) -> Self {
        self.difference = difference;
        self
    }
    /// Sets the matching threshold and symmetrisation.
    pub fn with_cluster(mut self, cluster: ClusterParams) -> Self {
        self.cluster = cluster;
        self
    }
    /// Sets the fraction of days that makes a cell part of a layout's composite map.
    pub fn with_composite_min_fraction(mut self, fraction: f64) -> Self {
        self.composite_min_fraction = fraction;
        self
    }
    /// Sets the fewest Σ visits for a known affordance density.
    pub fn with_min_visits(mut self, min_visits: u32) -> Self {
        self.min_visits = min_visits;
        self
    }
    /// Sets whether days and layouts are compared only where both observed.
    pub fn with_observed_only(mut self, observed_only: bool) -> Self {
        self.observed_only = observed_only;
        self
    }

    /// The parameters, after checking every rule.
    ///
    /// # Errors
    /// [`AffordanceError::Similarity`] for a bad cutoff or threshold;
    /// [`AffordanceError::InvalidParameter`] naming `composite_min_fraction` (must be in
    /// `(0, 1]`) or `min_visits` (must be ≥ 1).
    pub fn check(self) -> Result<Self> {
        self.difference.check()?;
        self.cluster.check()?;
        let f = self.composite_min_fraction;
        haunts_core::fraction("composite_min_fraction", f)?;
        haunts_core::at_least_one("min_visits", self.min_visits as usize)?;
        Ok(self)
    }
}

/// A layout of the library: its position in [`LayoutLibrary::layouts`] (layouts are never
/// removed, so ids are stable).
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct LayoutId(pub usize);

impl std::fmt::Display for LayoutId {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "layout {}", self.0)
    }
}

/// A day of the library, numbered 0, 1, … in order of ingestion.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct DayId(pub u64);

/// One day in a layout's history.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Debug, Clone, PartialEq)]
pub struct DayRecord {
    /// The day's number in the library.
    pub id: DayId,
    /// The label it was ingested with (unique in the library, e.g. `"2015-02-17"`).
    pub label: String,
    /// Its distance to the layout when it joined (units of the threshold, see
    /// [`LayoutDistance::distance`]); `None` for the day that started the layout.
    pub distance: Option<f64>,
}

/// A furniture layout: the days that showed it, their geometric composite and their
/// affordance composite.
///
/// With the `serde` feature it is saved as its id, its days, the geometric composite's
/// occupied and free counts (`{"composite": {"occupied": grid, "free": grid}}`) and its
/// affordance composite; loading checks that the counts lie on the affordance's cells and do
/// not exceed the days, that the affordance holds as many days, that day ids and labels are
/// unique and distances finite and ≥ 0, and replays the composite from its counts as
/// [`LayoutLibrary::from_bytes`] does.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(try_from = "LayoutFields"))]
pub struct Layout {
    id: LayoutId,
    composite: GeometricComposite,
    affordance: CumulativeDensity,
    days: Vec<DayRecord>,
}

impl Layout {
    /// The layout's id.
    pub fn id(&self) -> LayoutId {
        self.id
    }
    /// The geometric composite of its days (seed 000 III-A): per-cell occupied and free
    /// counts.
    pub fn composite(&self) -> &GeometricComposite {
        &self.composite
    }
    /// Its affordance map (seed 000 III-B): Σ hits / Σ visits over its days, a
    /// [`DensityMap`](crate::DensityMap).
    pub fn affordance(&self) -> &CumulativeDensity {
        &self.affordance
    }
    /// Its days, in order of ingestion.
    pub fn days(&self) -> &[DayRecord] {
        &self.days
    }
    /// The composite map days are compared with: cells occupied in at least
    /// `min_fraction` of the layout's days.
    ///
    /// # Errors
    /// [`AffordanceError::InvalidParameter`] unless `0 < min_fraction <= 1`.
    pub fn composite_mask(&self, min_fraction: f64) -> Result<Grid<bool>> {
        haunts_core::fraction("composite_min_fraction", min_fraction)?;
        Ok(self.composite.static_structure(min_fraction)?)
    }
}

/// How far a map lies from one stored layout.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LayoutDistance {
    /// The layout.
    pub layout: LayoutId,
    /// The two directed differences combined by the symmetrisation, in the threshold's units
    /// ([`ClusterParams::layout_distances`]); `None` when the layout's composite map has no
    /// occupied cell (its days disagree everywhere), which nothing can match.
    pub distance: Option<f64>,
    /// Whether the map counts as this layout (the distance is strictly below the threshold).
    pub matches: bool,
}

/// Which layout a map belongs to.
#[derive(Debug, Clone, PartialEq)]
pub struct Classification {
    /// The matching layout with the smallest distance (ties: the lowest id), or `None` when no
    /// layout matches and the map would start a new one.
    pub layout: Option<LayoutId>,
    /// The distance to every stored layout, in order of id.
    pub distances: Vec<LayoutDistance>,
}

impl Classification {
    /// The distance to the chosen layout, if any.
    pub fn distance(&self) -> Option<f64> {
        let chosen = self.layout?;
        self.distances
            .iter()
            .find(|d| d.layout == chosen)
            .and_then(|d| d.distance)
    }
}

/// What ingesting a day did.
#[derive(Debug, Clone, PartialEq)]
pub struct Ingested {
    /// The day's number.
    pub day: DayId,
    /// The layout it joined or started.
    pub layout: LayoutId,
    /// Whether it started a new layout.
    pub created: bool,
    /// How it compared with every layout stored before it.
    pub classification: Classification,
}

/// The layout library: every ingested day assigned to a layout, on one reference geometry.
///
/// ```
/// use haunts_affordance::density::DailyDensity;
/// use haunts_affordance::layout::{LayoutLibrary, LayoutParams};
/// use haunts_occupancy::{Cell, FREE, Grid, GridGeometry, OccupancyGrid, OCCUPIED};
/// use nalgebra::Point2;
/// let g = GridGeometry::new(0.05, Point2::origin(), 60, 60).unwrap();
/// // A day's map: the room seen free, a wall along one column.
/// let day_map = |wall_col: usize| {
///     let mut m = OccupancyGrid::from_grid(Grid::filled(g, FREE)).unwrap();
///     for row in 0..60 {
///         m.set(Cell::new(wall_col, row), OCCUPIED);
///     }
///     m
/// };
/// let counts = DailyDensity::new(Grid::filled(g, 1), Grid::filled(g, 2), 1).unwrap();
/// let mut library = LayoutLibrary::new(g, LayoutParams::default()).unwrap();
/// let a = library.ingest("monday", &day_map(10), &counts).unwrap();
/// let b = library.ingest("tuesday", &day_map(11), &counts).unwrap(); // moved 5 cm: same
/// let c = library.ingest("wednesday", &day_map(50), &counts).unwrap(); // moved 2 m: new
/// assert!(a.created && !b.created && c.created);
/// assert_eq!(b.layout, a.layout);
/// assert_eq!(library.layouts().len(), 2);
/// assert_eq!(library.classify(&day_map(49)).unwrap().layout, Some(c.layout));
/// ```
///
/// With the `serde` feature it is saved as its geometry, parameters, layouts (see [`Layout`])
/// and day count; loading checks what [`LayoutLibrary::from_bytes`] checks: valid parameters,
/// layouts numbered in order on the reference geometry with the library's `min_visits`, day
/// ids unique and below the day count, labels unique, every ingested day in exactly one
/// layout. The [file format](crate::layout::file) stays the compact, checksummed way to store
/// a library.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(try_from = "LayoutLibraryFields"))]
pub struct LayoutLibrary {
    geometry: GridGeometry,
    params: LayoutParams,
    layouts: Vec<Layout>,
    next_day: u64,
}

impl LayoutLibrary {
    /// An empty library on the reference `geometry`.
    ///
    /// # Errors
    /// As [`LayoutParams::check`].
    pub fn new(geometry: GridGeometry, params: LayoutParams) -> Result<Self> {
        Ok(Self {
            geometry,
            params: params.check()?,
            layouts: Vec::new(),
            next_day: 0,
        })
    }

    /// The reference geometry every day must lie on.
    pub fn geometry(&self) -> &GridGeometry {
        &self.geometry
    }
    /// The parameters.
    pub fn params(&self) -> &LayoutParams {
        &self.params
    }
    /// The layouts, in order of id.
    pub fn layouts(&self) -> &[Layout] {
        &self.layouts
    }
    /// The layout with id `id`.
    pub fn layout(&self, id: LayoutId) -> Option<&Layout> {
        self.layouts.get(id.0)
    }
    /// Number of days ingested.
    pub fn day_count(&self) -> u64 {
        self.next_day
    }
    /// The layout of the day ingested as `label`, with its record.
    pub fn find_day(&self, label: &str) -> Option<(LayoutId, &DayRecord)> {
        self.layouts
            .iter()
            .find_map(|l| l.days.iter().find(|d| d.label == label).map(|d| (l.id, d)))
    }

    /// Which layout `map` belongs to, without storing anything.
    ///
    /// # Errors
    /// [`AffordanceError::GeometryMismatch`] (`what` = `"day map"`) when the map does not lie
    /// on the reference geometry (resample it first with [`haunts_similarity::resample`]);
    /// [`AffordanceError::EmptyDayMap`] when it has no occupied cell to compare.
    ///
    /// # Complexity
    /// O(layouts · cells): one distance transform per layout and one for the map.
    pub fn classify(&self, map: &OccupancyGrid) -> Result<Classification> {
        let day = self.prepare_day(map)?;
        self.classify_prepared(&day)
    }

    /// Ingests one day: classifies its map, then joins the best matching layout or starts a
    /// new one, adding the map to the layout's geometric composite and the day's hits and
    /// visits to its affordance composite.
    ///
    /// # Errors
    /// [`AffordanceError::GeometryMismatch`] when the map (`"day map"`) or the counts
    /// (`"day hits"`, `"day visits"`) do not lie on the reference geometry;
    /// [`AffordanceError::EmptyDayMap`]; [`AffordanceError::DuplicateDay`] when a day with
    /// this label is already stored; [`AffordanceError::InvalidParameter`] for a label longer
    /// than `u32::MAX` bytes. On any error the library is unchanged.
    ///
    /// # Complexity
    /// As [`LayoutLibrary::classify`].
    pub fn ingest(
        &mut self,
        label: impl Into<String>,
        map: &OccupancyGrid,
        density: &DailyDensity,
    ) -> Result<Ingested> {
        let label = label.into();
        if u32::try_from(label.len()).is_err() {
            return Err(AffordanceError::InvalidParameter(
                haunts_core::InvalidParameter {
                    name: "label length",
                    value: label.len() as f64,
                    rule: "must fit in u32 bytes (the file format's limit)",
                },
            ));
        }
        check_geometry("day hits", &self.geometry, density.hits().geometry())?;
        check_geometry("day visits", &self.geometry, density.visits().geometry())?;
        if self.find_day(&label).is_some() {
            return Err(AffordanceError::DuplicateDay { label });
        }
        let day = self.prepare_day(map)?;
        let classification = self.classify_prepared(&day)?;
        let id = DayId(self.next_day);
        let record = DayRecord {
            id,
            label,
            distance: classification.distance(),
        };
        // Update copies, then commit: an error half-way leaves the library as it was.
        let chosen = classification.layout.and_then(|id| self.layouts.get(id.0));
        let (mut layout, created) = match chosen {
            Some(l) => (l.clone(), false),
            None => (
                Layout {
                    id: LayoutId(self.layouts.len()),
                    composite: GeometricComposite::new(self.geometry),
                    affordance: CumulativeDensity::new(self.geometry, self.params.min_visits)?,
                    days: Vec::new(),
                },
                true,
            ),
        };
        layout.composite.add(map)?;
        layout.affordance.add(density)?;
        layout.days.push(record);
        let layout_id = layout.id;
        if created {
            self.layouts.push(layout);
        } else if let Some(slot) = self.layouts.get_mut(layout_id.0) {
            *slot = layout;
        }
        self.next_day += 1;
        Ok(Ingested {
            day: id,
            layout: layout_id,
            created,
            classification,
        })
    }

    fn prepare_day(&self, map: &OccupancyGrid) -> Result<DayMap> {
        check_geometry("day map", &self.geometry, map.geometry())?;
        let prepared = PreparedMap::new(map).map_err(|e| match e {
            SimilarityError::EmptyMap { .. } => AffordanceError::EmptyDayMap,
            e => e.into(),
        })?;
        let t = map.thresholds();
        let observed = map.values().map(|&v| t.state(v) != CellState::Unknown);
        Ok(DayMap { prepared, observed })
    }

    fn classify_prepared(&self, day: &DayMap) -> Result<Classification> {
        let mut distances = Vec::with_capacity(self.layouts.len());
        let mut best: Option<(f64, LayoutId)> = None;
        for layout in &self.layouts {
            let d = self.distance(layout, day)?;
            if let (true, Some(v)) = (d.matches, d.distance) {
                if best.is_none_or(|(b, _)| v < b) {
                    best = Some((v, layout.id));
                }
            }
            distances.push(d);
        }
        Ok(Classification {
            layout: best.map(|(_, id)| id),
            distances,
        })
    }

    /// The distance between a layout's composite map and a day's map, and whether they match.
    fn distance(&self, layout: &Layout, day: &DayMap) -> Result<LayoutDistance> {
        let mask = layout.composite_mask(self.params.composite_min_fraction)?;
        let composite = match PreparedMap::from_mask(&mask) {
            Ok(p) => p,
            Err(SimilarityError::EmptyMap { .. }) => {
                return Ok(LayoutDistance {
                    layout: layout.id,
                    distance: None,
                    matches: false,
                });
            }
            Err(e) => return Err(e.into()),
        };
        let (composite, day) = if self.params.observed_only {
            let seen = layout.composite.observed_frequency().map(|f| f.is_finite());
            (
                composite.within(&day.observed)?,
                day.prepared.within(&seen)?,
            )
        } else {
            (composite, day.prepared.clone())
        };
        let difference = &self.params.difference;
        // Entry (x, y) of a similarity matrix is cmapXmapY: y's occupied cells in x's field.
        let layout_to_day = directed_difference(&composite, &day, difference)?;
        let day_to_layout = directed_difference(&day, &composite, difference)?;
        // The pair as a 2 × 2 similarity matrix, so that the threshold's units, scaling and
        // strictness are exactly those of the similarity crate's clustering.
        let pair = SimilarityMatrix::from_values(
            vec![0.0, layout_to_day, day_to_layout, 0.0],
            vec![composite.occupied_count(), day.occupied_count()],
            self.geometry.resolution(),
        )?;
        let distance = self.params.cluster.layout_distances(&pair)[1];
        let matches = greedy_layouts(&pair, &self.params.cluster)?.clusters == 1;
        Ok(LayoutDistance {
            layout: layout.id,
            distance: Some(distance),
            matches,
        })
    }
}

/// A day's map ready for comparison, and the cells it observed (free or occupied).
struct DayMap {
    prepared: PreparedMap,
    observed: Grid<bool>,
}

/// A layout as written: its geometric composite as counts.
#[cfg(feature = "serde")]
#[derive(serde::Serialize)]
struct LayoutRef<'a> {
    id: LayoutId,
    days: &'a [DayRecord],
    composite: CompositeCounts<&'a Grid<u32>>,
    affordance: &'a CumulativeDensity,
}

/// A geometric composite's per-cell counts over its maps (the layout's days).
#[cfg(feature = "serde")]
#[derive(serde::Serialize, serde::Deserialize)]
struct CompositeCounts<G> {
    occupied: G,
    free: G,
}

#[cfg(feature = "serde")]
impl serde::Serialize for Layout {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        LayoutRef {
            id: self.id,
            days: &self.days,
            composite: CompositeCounts {
                occupied: self.composite.occupied_counts(),
                free: self.composite.free_counts(),
            },
            affordance: &self.affordance,
        }
        .serialize(s)
    }
}

/// The fields of a [`Layout`] as deserialised, before they are checked and the composite is
/// replayed.
#[cfg(feature = "serde")]
#[derive(serde::Deserialize)]
struct LayoutFields {
    id: LayoutId,
    days: Vec<DayRecord>,
    composite: CompositeCounts<Grid<u32>>,
    affordance: CumulativeDensity,
}

#[cfg(feature = "serde")]
fn invalid(model: &'static str, problem: String) -> AffordanceError {
    AffordanceError::InvalidModel { model, problem }
}

#[cfg(feature = "serde")]
impl TryFrom<LayoutFields> for Layout {
    type Error = AffordanceError;
    fn try_from(f: LayoutFields) -> Result<Self> {
        let bad = |problem: String| invalid("layout", format!("{}: {problem}", f.id));
        let Ok(maps) = u32::try_from(f.days.len()) else {
            return Err(bad(format!("{} days (at most u32::MAX)", f.days.len())));
        };
        if maps == 0 {
            return Err(bad(
                "no day (a layout starts with the day that created it)".into()
            ));
        }
        let mut ids = std::collections::HashSet::new();
        let mut labels = std::collections::HashSet::new();
        for day in &f.days {
            if !ids.insert(day.id) {
                return Err(bad(format!("day id {} repeated", day.id.0)));
            }
            if !labels.insert(day.label.as_str()) {
                return Err(bad(format!("day label `{}` repeated", day.label)));
            }
            if let Some(d) = day.distance {
                if !(d.is_finite() && d >= 0.0) {
                    return Err(bad(format!(
                        "day `{}` has distance {d} (must be finite and >= 0)",
                        day.label
                    )));
                }
            }
        }
        if f.affordance.days() != maps {
            return Err(bad(format!(
                "the affordance composite holds {} days, the layout {maps}",
                f.affordance.days()
            )));
        }
        let geometry = *f.affordance.geometry();
        check_geometry(
            "composite occupied counts",
            &geometry,
            f.composite.occupied.geometry(),
        )?;
        check_geometry(
            "composite free counts",
            &geometry,
            f.composite.free.geometry(),
        )?;
        let Some(composite) = file::composite_from_counts(
            geometry,
            f.composite.occupied.data(),
            f.composite.free.data(),
            maps,
        ) else {
            return Err(bad(format!(
                "a cell's occupied + free counts exceed its {maps} days"
            )));
        };
        Ok(Self {
            id: f.id,
            composite,
            affordance: f.affordance,
            days: f.days,
        })
    }
}

/// The fields of a [`LayoutLibrary`] as deserialised (each layout already checked on its
/// own), before the library's rules are checked.
#[cfg(feature = "serde")]
#[derive(serde::Deserialize)]
struct LayoutLibraryFields {
    geometry: GridGeometry,
    params: LayoutParams,
    layouts: Vec<Layout>,
    next_day: u64,
}

#[cfg(feature = "serde")]
impl TryFrom<LayoutLibraryFields> for LayoutLibrary {
    type Error = AffordanceError;
    fn try_from(f: LayoutLibraryFields) -> Result<Self> {
        let bad = |problem: String| invalid("layout library", problem);
        let params = f.params.check()?;
        let mut ids = std::collections::HashSet::new();
        let mut labels = std::collections::HashSet::new();
        for (index, layout) in f.layouts.iter().enumerate() {
            if layout.id != LayoutId(index) {
                return Err(bad(format!("{} stored at position {index}", layout.id)));
            }
            check_geometry("layout", &f.geometry, layout.affordance.geometry())?;
            if layout.affordance.min_visits() != params.min_visits {
                return Err(bad(format!(
                    "{} has min_visits {}, the library {}",
                    layout.id,
                    layout.affordance.min_visits(),
                    params.min_visits
                )));
            }
            for day in &layout.days {
                if day.id.0 >= f.next_day || !ids.insert(day.id) {
                    return Err(bad(format!(
                        "day id {} repeated or not below the day count {}",
                        day.id.0, f.next_day
                    )));
                }
                if !labels.insert(day.label.as_str()) {
                    return Err(bad(format!("day label `{}` repeated", day.label)));
                }
                if u32::try_from(day.label.len()).is_err() {
                    return Err(bad(format!(
                        "a label of {} bytes (at most u32::MAX)",
                        day.label.len()
                    )));
                }
            }
        }
        if ids.len() as u64 != f.next_day {
            return Err(bad(format!(
                "the layouts hold {} of the {} ingested days",
                ids.len(),
                f.next_day
            )));
        }
        Ok(Self {
            geometry: f.geometry,
            params,
            layouts: f.layouts,
            next_day: f.next_day,
        })
    }
}
