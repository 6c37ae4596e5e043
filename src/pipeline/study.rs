//! The daily loop evaluated on simulated days: the main job's stages as library calls, each
//! scored against the simulator's truth (which only this module and [`super::score`] read).
//!
//! 1. [`simulate_days`]: days simulated and processed ([`DayProcessor`]), in parallel; for
//!    days from random start poses, [`simulate_days_on_own_grids`] and then [`align_days`]
//!    (each day registered onto the layouts of the days before it);
//! 2. [`layouts`]: the days, in order, feed the layout library (seed 000 Fig. 2); the paper's
//!    greedy clustering and complete linkage run on the similarity matrix of all days; each
//!    is scored against the true layouts;
//! 3. [`own_tables`]: whether each layout's affordance map concentrates at its own tables
//!    and sofas rather than at another layout's;
//! 4. [`hypertime`]: seed 001's model over the tracked positions of the training days, scored
//!    on held-out days against the same clustering without time, over all days and per
//!    layout of the library;
//! 5. [`ta_map`]: seed 002's TA map and its confidence map;
//! 6. [`plans`]: plain and activity-aware A* on a layout's composite map, and the layout's
//!    affordance map served as a costmap layer ([`super::serve`]);
//! 7. [`plans_at_times`]: the same trip at several times of day, the layout's affordance
//!    modulated by its daily rhythm ([`ActivityAt`]).
//!
//! The stages' results together are a [`Study`]: its [`Summary`] (the main job's figures,
//! serialisable as its JSON line) and, with the `figures` feature, its figures, `index.html`
//! and MCAP ([`Study::write`]).

use std::ops::Range;

use haunts_affordance::activity_at::{ActivityAt, ActivityAtParams, RateCheck};
use haunts_affordance::hypertime::{GridLogLikelihood, grid_log_likelihood};
use haunts_affordance::layout::Layout;
use haunts_affordance::ta::{ConfidenceMap, TaMap, TaParams};
use haunts_affordance::{HypertimeModel, HypertimeParams, LayoutLibrary, LayoutParams, TimedPoint};
use haunts_occupancy::recording::Recording;
use haunts_occupancy::{Grid, GridGeometry, OccupancyGrid, Pose2};
use haunts_planning::{
    AStar, ActivityAwareAStar, ActivityAwareParams, InflationLayer, InflationParams,
    LayeredCostmap, PathMetrics, Planner, SearchParams, StaticLayer,
};
use haunts_sim::Simulator;
use haunts_similarity::{
    Agreement, ClusterParams, agreement, complete_linkage_layouts, greedy_layouts,
    similarity_matrix,
};
use haunts_tracking::track::dummy::{DummyFilterParams, filter_dummies};
use nalgebra::Point2;
#[cfg(feature = "rayon")]
use rayon::prelude::*;

use super::score::{self, SimulatedScore};
use super::serve::{self, PlanComparison, ServeParams, TimedPlan};
use super::{DayOutput, DayProcessor, PipelineParams, Result, density_near};

mod align;
mod summary;
#[cfg(feature = "figures")]
mod write;

pub use align::{
    AlignedDay, AlignmentErrors, AlignmentStudy, RefusedDay, align_days, reprocess_aligned,
};
pub use summary::Summary;

/// The main job's results, stage by stage: what each function of this module returned on
/// the same days (the busiest layout, [`LayoutStudy::most_frequent`], is the one `plans`
/// and `timed` planned on).
///
/// The main job in short (`examples/pipeline.rs` is the same with its parameters):
/// ```no_run
/// use haunts::affordance::{HypertimeParams, LayoutParams};
/// use haunts::pipeline::study::{self, Study};
/// use haunts::pipeline::{DayProcessor, PipelineParams};
/// use haunts::sim::{SimParams, Simulator};
/// use haunts::similarity::ClusterParams;
/// use nalgebra::Point2;
///
/// let sim = Simulator::new(SimParams::default())?;
/// let processor = DayProcessor::new(sim.geometry(), PipelineParams::default())?;
/// let geometry = *processor.geometry();
/// let days = study::simulate_days(&sim, &processor, 0..10, |_| {})?;
/// let layouts = study::layouts(&days, geometry, LayoutParams::default(), &ClusterParams::default())?;
/// let own_tables = study::own_tables(&layouts.library, &days);
/// let held_out = |d: &study::SimulatedDay| d.index % 5 == 4;
/// let hypertime = study::hypertime(
///     &days, &layouts.labels, &HypertimeParams::default(),
///     &geometry.with_resolution(0.25)?, 600.0, 40_000, held_out,
/// )?;
/// let ta = study::ta_map(&days, geometry, sim.params().laser.range_max)?;
/// let busiest = layouts.most_frequent().ok_or("no layout")?;
/// let (from, to) = (Point2::new(1.0, 4.8), Point2::new(14.2, 5.0));
/// let plans = study::plans(busiest, &ta.activity, from, to)?;
/// let timed = study::plans_at_times(
///     &days, &layouts.labels, held_out, busiest, &hypertime, &[8.0, 12.5], from, to,
/// )?;
/// let study = Study { days, layouts, own_tables, hypertime, ta, plans, timed, alignment: None };
/// let summary = study.write("out/study", "ten days", std::time::Instant::now())?;
/// println!("{}", serde_json::to_string(&summary)?);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Debug, Clone)]
pub struct Study {
    /// The days, processed and scored ([`simulate_days`]).
    pub days: Vec<SimulatedDay>,
    /// The layouts found in them ([`layouts`]).
    pub layouts: LayoutStudy,
    /// Each layout's affordance at its own tables and sofas ([`own_tables`]).
    pub own_tables: Vec<OwnTables>,
    /// Hypertime against its static baseline ([`hypertime`]).
    pub hypertime: HypertimeStudy,
    /// The TA map ([`ta_map`]).
    pub ta: TaStudy,
    /// Plans across the busiest layout ([`plans`]).
    pub plans: PlanStudy,
    /// The same trip at several times of day on it ([`plans_at_times`]).
    pub timed: TimedPlans,
    /// How days from random start poses were brought into one frame ([`align_days`]);
    /// `None` for days that all start at one pose.
    pub alignment: Option<AlignmentStudy>,
}

/// One simulated day, processed and scored.
#[derive(Debug, Clone)]
pub struct SimulatedDay {
    /// The day's index.
    pub index: usize,
    /// The true layout (for scoring only).
    pub layout: usize,
    /// What the daily loop made of the day's recording.
    pub output: DayOutput,
    /// Its score against the simulator's truth.
    pub score: SimulatedScore,
    /// The true tables and sofas (for scoring the affordance maps).
    pub tables_and_sofas: Vec<Point2<f64>>,
    /// The day's odometry frame in the office's (the truth of its registration; the
    /// identity unless the simulator starts days at random poses).
    pub start: Pose2,
}

/// Simulates the days `days` and processes each with `processor`, in parallel (with the
/// `rayon` feature): each task simulates one day, processes it and keeps only its output,
/// so memory holds one simulated day per thread and no thread waits for another's day;
/// `done(n)` is called as each day finishes with the number finished so far (from any
/// thread). The result is in day order, the same with any number of threads.
///
/// # Errors
/// The simulator's and the daily loop's errors.
pub fn simulate_days(
    sim: &Simulator,
    processor: &DayProcessor,
    days: Range<usize>,
    done: impl Fn(usize) + Sync,
) -> Result<Vec<SimulatedDay>> {
    simulate_with(sim, processor.params(), days, done, |recording| {
        processor.process(recording)
    })
}

/// [`simulate_days`] with each day processed on its own grid, as `haunts day` does a
/// recording: the box of its odometry grown by `margin` metres
/// ([`DayProcessor::geometry_for`]) at `params`' resolution. For days that start at random
/// poses ([`SimParams::random_start`](haunts_sim::SimParams::random_start)), whose frames
/// differ; [`align_days`] brings them into one.
///
/// # Errors
/// The simulator's and the daily loop's errors; a margin that is not finite and positive.
pub fn simulate_days_on_own_grids(
    sim: &Simulator,
    params: &PipelineParams,
    margin: f64,
    days: Range<usize>,
    done: impl Fn(usize) + Sync,
) -> Result<Vec<SimulatedDay>> {
    let params = (*params).check()?;
    simulate_with(sim, &params, days, done, |recording| {
        let geometry = DayProcessor::geometry_for(recording, params.resolution, margin)?;
        DayProcessor::new(geometry, params)?.process(recording)
    })
}

/// The days simulated and each processed by `process`, scored under `params`.
fn simulate_with(
    sim: &Simulator,
    params: &PipelineParams,
    days: Range<usize>,
    done: impl Fn(usize) + Sync,
    process: impl Fn(&Recording) -> Result<DayOutput> + Sync,
) -> Result<Vec<SimulatedDay>> {
    let finished = std::sync::atomic::AtomicUsize::new(0);
    let one = |index: usize| -> Result<SimulatedDay> {
        let day = sim.day(index)?;
        let output = process(&day.to_recording()?)?;
        let simulated = SimulatedDay {
            index: day.index,
            layout: day.layout,
            score: score::simulated(&output, &day, params)?,
            tables_and_sofas: score::tables_and_sofas(&day),
            start: day.odometry_frame,
            output,
        };
        done(finished.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1);
        Ok(simulated)
    };
    #[cfg(feature = "rayon")]
    let out = days.into_par_iter().map(one).collect();
    #[cfg(not(feature = "rayon"))]
    let out = days.map(one).collect();
    out
}

/// The layouts found in the days, three ways, scored against the true layouts.
#[derive(Debug, Clone)]
pub struct LayoutStudy {
    /// The layout library the days fed, in order (ours: online).
    pub library: LayoutLibrary,
    /// The library's layout of each day.
    pub labels: Vec<usize>,
    /// The true layout of each day.
    pub truth: Vec<usize>,
    /// The library against the truth.
    pub ours: Agreement,
    /// Seed 000's greedy threshold clustering of the similarity matrix against the truth.
    pub paper: Agreement,
    /// Complete linkage of the same matrix against the truth.
    pub linkage: Agreement,
}

impl LayoutStudy {
    /// The number of distinct true layouts.
    pub(crate) fn true_layouts(&self) -> usize {
        let mut t = self.truth.clone();
        t.sort_unstable();
        t.dedup();
        t.len()
    }

    /// The library's layout with the most days (the lowest id among ties), if any.
    pub fn most_frequent(&self) -> Option<&Layout> {
        self.library
            .layouts()
            .iter()
            .max_by_key(|l| (l.days().len(), std::cmp::Reverse(l.id().0)))
    }
}

/// Feeds `days` in order into a layout library on `geometry` with `params`, and clusters
/// their maps with seed 000's greedy method and complete linkage (`cluster`).
///
/// # Errors
/// The library's and the clustering's errors.
pub fn layouts(
    days: &[SimulatedDay],
    geometry: GridGeometry,
    params: LayoutParams,
    cluster: &ClusterParams,
) -> Result<LayoutStudy> {
    let truth: Vec<usize> = days.iter().map(|d| d.layout).collect();
    let mut library = LayoutLibrary::new(geometry, params)?;
    let mut labels = Vec::with_capacity(days.len());
    for d in days {
        let label = format!("day {:02}", d.index);
        labels.push(
            library
                .ingest(label, &d.output.map, &d.output.density)?
                .layout
                .0,
        );
    }
    let maps: Vec<OccupancyGrid> = days.iter().map(|d| d.output.map.clone()).collect();
    let matrix = similarity_matrix(&maps, &params.difference)?;
    Ok(LayoutStudy {
        ours: agreement(&labels, &truth)?,
        paper: agreement(&greedy_layouts(&matrix, cluster)?.labels, &truth)?,
        linkage: agreement(&complete_linkage_layouts(&matrix, cluster)?.labels, &truth)?,
        library,
        labels,
        truth,
    })
}

/// One layout's affordance map at its own tables and sofas and at another layout's.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OwnTables {
    /// The library's layout.
    pub layout: usize,
    /// The true layout of its first day.
    pub true_layout: usize,
    /// Mean density near its own tables and sofas.
    pub own: f64,
    /// Mean density near the other true layouts' tables and sofas.
    pub other: f64,
}

/// For every layout of the library whose first day has tables and sofas (and some other true
/// layout too): its affordance map's mean density near them and near the other layouts'.
pub fn own_tables(library: &LayoutLibrary, days: &[SimulatedDay]) -> Vec<OwnTables> {
    let mut out = Vec::new();
    for layout in library.layouts() {
        let Some(first) = layout
            .days()
            .first()
            .and_then(|d| days.get(d.id.0 as usize))
        else {
            continue;
        };
        let others: Vec<Point2<f64>> = days
            .iter()
            .filter(|d| d.layout != first.layout)
            .flat_map(|d| d.tables_and_sofas.iter().copied())
            .collect();
        if others.is_empty() || first.tables_and_sofas.is_empty() {
            continue;
        }
        let affordance = layout.affordance().density_grid();
        out.push(OwnTables {
            layout: layout.id().0,
            true_layout: first.layout,
            own: density_near(&affordance, &first.tables_and_sofas, &others),
            other: density_near(&affordance, &others, &first.tables_and_sofas),
        });
    }
    out
}

/// Hypertime and its static baseline on one set of training and test days.
#[derive(Debug, Clone)]
pub struct HypertimeScore {
    /// The hypertime model fitted on the training points.
    pub hypertime: HypertimeModel,
    /// The same clustering without time (when `hypertime` kept no period, the same model: its
    /// report then shows the periods `hypertime` tried).
    pub baseline: HypertimeModel,
    /// Hypertime's log-likelihood of the test points.
    pub hypertime_ll: GridLogLikelihood,
    /// The baseline's.
    pub static_ll: GridLogLikelihood,
    /// Training points (after thinning).
    pub train: usize,
}

/// Hypertime over all days, and per layout of the library.
#[derive(Debug, Clone)]
pub struct HypertimeStudy {
    /// The training points (every day not held out, thinned).
    pub train: Vec<TimedPoint>,
    /// The test points (the held-out days).
    pub test: Vec<TimedPoint>,
    /// Both models on all days.
    pub all: HypertimeScore,
    /// Per layout of the library with test days and at least 20 training points per
    /// cluster: `(layout, score)`.
    pub by_layout: Vec<(usize, HypertimeScore)>,
}

impl HypertimeStudy {
    /// The midnight (UTC) before the first training point, 0 without one: the origin of the
    /// hours of [`plans_at_times`].
    pub fn midnight(&self) -> f64 {
        self.train
            .first()
            .map_or(0.0, |p| p.time - p.time.rem_euclid(86_400.0))
    }
}

/// Fits hypertime and its static baseline on the tracked positions of the days that
/// `held_out` rejects (at most `max_points`, evenly strided: GK's cost is linear in them)
/// and scores both on the others, over `score_grid` at `time_step` seconds; then the same
/// per layout of the library (`labels`: each day's layout).
///
/// # Errors
/// The models' errors.
pub fn hypertime(
    days: &[SimulatedDay],
    labels: &[usize],
    params: &HypertimeParams,
    score_grid: &GridGeometry,
    time_step: f64,
    max_points: usize,
    held_out: impl Fn(&SimulatedDay) -> bool,
) -> Result<HypertimeStudy> {
    let thin = |points: Vec<TimedPoint>| {
        let stride = points.len().div_ceil(max_points.max(1)).max(1);
        points.into_iter().step_by(stride).collect::<Vec<_>>()
    };
    let points = |layout: Option<usize>, test: bool| {
        days.iter()
            .zip(labels)
            .filter(|(d, l)| layout.is_none_or(|id| **l == id) && held_out(d) == test)
            .flat_map(|(d, _)| d.output.tracked.iter().copied())
            .collect::<Vec<_>>()
    };
    // The models side by side (with the `rayon` feature): one fit's Gustafson–Kessel passes
    // split its points into blocks of 512 rows, too few in a layout's fits to keep every
    // thread busy between the iterations' joins; each fit is the same on any thread
    // (BENCHMARKS.md, issue 19).
    let fit = |train: &[TimedPoint], test: &[TimedPoint]| -> Result<HypertimeScore> {
        let hypertime = HypertimeModel::fit(train, params)?;
        let hypertime_ll = grid_log_likelihood(&hypertime, test, score_grid, time_step)?;
        // A model that kept no period ends with the baseline's own calibration and fit (the
        // selection refits without the rejected periods; affordance's test
        // `a_model_without_a_validated_period_is_its_baseline`): not fitted and scored twice.
        let (baseline, static_ll) =
            if hypertime.periods().is_empty() && params.cluster_search.is_none() {
                (hypertime.clone(), hypertime_ll)
            } else {
                let baseline = HypertimeModel::fit(train, &params.clone().without_time())?;
                let ll = grid_log_likelihood(&baseline, test, score_grid, time_step)?;
                (baseline, ll)
            };
        Ok(HypertimeScore {
            hypertime_ll,
            static_ll,
            hypertime,
            baseline,
            train: train.len(),
        })
    };
    let (train, test) = (thin(points(None, false)), points(None, true));
    let mut ids: Vec<usize> = labels.to_vec();
    ids.sort_unstable();
    ids.dedup();
    // Each layout with test days and enough training points.
    let layouts: Vec<(usize, Vec<TimedPoint>, Vec<TimedPoint>)> = ids
        .into_iter()
        .map(|id| (id, thin(points(Some(id), false)), points(Some(id), true)))
        .filter(|(_, train_l, test_l)| {
            !test_l.is_empty() && train_l.len() >= 20 * params.gk.clusters
        })
        .collect();
    let one = |(id, train_l, test_l): &(usize, Vec<TimedPoint>, Vec<TimedPoint>)| {
        fit(train_l, test_l).map(|score| (*id, score))
    };
    #[cfg(feature = "rayon")]
    let (all, by_layout) = rayon::join(
        || fit(&train, &test),
        || layouts.par_iter().map(one).collect::<Vec<_>>(),
    );
    #[cfg(not(feature = "rayon"))]
    let (all, by_layout) = (
        fit(&train, &test),
        layouts.iter().map(one).collect::<Vec<_>>(),
    );
    // The first error in the order of one fit after another: all days, then the layouts.
    let all = all?;
    let by_layout = by_layout.into_iter().collect::<Result<Vec<_>>>()?;
    Ok(HypertimeStudy {
        train,
        test,
        all,
        by_layout,
    })
}

/// Seed 002's TA map of the days and its confidence map.
#[derive(Debug, Clone)]
pub struct TaStudy {
    /// The activity (distinct targets per cell and session).
    pub activity: Grid<f64>,
    /// The confidence map from the robot's keyframes.
    pub confidence: Grid<f64>,
    /// Tracks that passed the dummy filter.
    pub kept: usize,
}

/// The TA map of the days' tracks that pass the dummy filter, each day a session (already in
/// the reference frame: scan matching from the dock), and its confidence map from the robot's
/// keyframes seen to `range` metres.
///
/// # Errors
/// The filter's and the maps' errors.
pub fn ta_map(days: &[SimulatedDay], geometry: GridGeometry, range: f64) -> Result<TaStudy> {
    let dummy = DummyFilterParams::default();
    let sessions: Vec<Vec<_>> = days
        .iter()
        .map(|d| Ok(filter_dummies(d.output.trajectories.clone(), &dummy)?.kept))
        .collect::<Result<_>>()?;
    let refs: Vec<&[_]> = sessions.iter().map(Vec::as_slice).collect();
    let robot: Vec<Point2<f64>> = days
        .iter()
        .flat_map(|d| d.output.keyframe_positions())
        .collect();
    let params = TaParams::default();
    let ta = TaMap::fit_sessions(&refs, geometry, &params)?;
    let confidence = ConfidenceMap::fit(&robot, geometry, range, &params.regression)?;
    Ok(TaStudy {
        activity: ta.raster().clone(),
        confidence: confidence.raster().clone(),
        kept: sessions.iter().map(Vec::len).sum(),
    })
}

/// A planned path and its metrics.
#[derive(Debug, Clone, PartialEq)]
pub struct Plan {
    /// Length and activity along the path.
    pub metrics: PathMetrics,
    /// Cell centres from start to goal.
    pub points: Vec<Point2<f64>>,
}

/// Plans across a layout, three ways.
#[derive(Debug, Clone, PartialEq)]
pub struct PlanStudy {
    /// The layout's composite map (cells occupied on at least half its days).
    pub map: OccupancyGrid,
    /// A* on the static and inflation layers, ignoring activity.
    pub plain: Plan,
    /// Seed 002's activity-aware A* with the TA map.
    pub aware: Plan,
    /// θ: the 75th percentile of the activity on free cells.
    pub threshold: f64,
    /// Seed 000's use: the layout's affordance map as a costmap layer, without and with it.
    pub layer: PlanComparison,
}

/// Plans `from` → `to` on `layout`'s composite map: plain A* and activity-aware A* with
/// `activity` (θ at the 75th percentile of the activity on free cells: seed 002's 5.5 counts
/// distinct targets per 3 m cell and session on busier data), and A* without and with the
/// layout's affordance layer.
///
/// # Errors
/// The planners' errors (an endpoint inside a wall, no path).
pub fn plans(
    layout: &Layout,
    activity: &Grid<f64>,
    from: Point2<f64>,
    to: Point2<f64>,
) -> Result<PlanStudy> {
    let map = layout.composite().static_map(0.5)?;
    let costmap = LayeredCostmap::new(*map.geometry())
        .with_layer(StaticLayer::new(&map, false))
        .with_layer(InflationLayer::new(InflationParams::default())?)
        .build()?;
    let plan = |path: haunts_planning::Path| -> Result<Plan> {
        Ok(Plan {
            metrics: path.metrics(activity)?,
            points: path.points(),
        })
    };
    let plain = plan(
        AStar::new(SearchParams::default().with_cost_weight(0.0))?
            .plan_world(&costmap, from, to)?,
    )?;
    let free = Grid::from_fn(*activity.geometry(), |c| match map.value(c) {
        Some(0) => activity.get(c).copied().unwrap_or(f64::NAN),
        _ => f64::NAN,
    });
    let threshold = serve::percentile(&free, 0.75).unwrap_or(f64::MIN_POSITIVE);
    let aware = plan(
        ActivityAwareAStar::new(
            activity.clone(),
            ActivityAwareParams::default().with_threshold(threshold),
        )?
        .plan_world(&costmap, from, to)?,
    )?;
    let served = serve::serve_layout(layout, &ServeParams::default())?;
    let layer = serve::compare_plans(&served, from, to, SearchParams::default())?;
    Ok(PlanStudy {
        map,
        plain,
        aware,
        threshold,
        layer,
    })
}

/// The same trip planned at several times of day ([`plans_at_times`]).
#[derive(Debug, Clone)]
pub struct TimedPlans {
    /// The plan at each time (UNIX seconds: the hours after [`HypertimeStudy::midnight`]).
    pub plans: Vec<TimedPlan>,
    /// The periods of the hypertime model that gave the rhythm's *where*.
    pub periods: Vec<f64>,
    /// The check of the rate's rhythm across held-out training days, made when that model
    /// kept no period ([`ActivityAt::rate_check`]); `None` otherwise.
    pub rate_check: Option<RateCheck>,
}

/// Plans `from` → `to` on `layout` at each of `hours` (hours after
/// [`HypertimeStudy::midnight`]) with its activity at that time as the costmap layer
/// ([`serve::plan_at_times`]): the layout's affordance modulated by the daily rhythm
/// ([`ActivityAt`], default parameters) of its hypertime model in `study` (the all-days
/// model if the layout has none) and of the tracked positions of its training days
/// (`held_out` rejects them). Without a validated rhythm every hour's map is the
/// affordance itself and the plans are the same.
///
/// # Errors
/// [`ActivityAt::new`]'s and [`serve::plan_at_times`]'s errors.
#[allow(clippy::too_many_arguments)]
pub fn plans_at_times(
    days: &[SimulatedDay],
    labels: &[usize],
    held_out: impl Fn(&SimulatedDay) -> bool,
    layout: &Layout,
    study: &HypertimeStudy,
    hours: &[f64],
    from: Point2<f64>,
    to: Point2<f64>,
) -> Result<TimedPlans> {
    let id = layout.id().0;
    let model = study
        .by_layout
        .iter()
        .find(|(l, _)| *l == id)
        .map_or(&study.all.hypertime, |(_, s)| &s.hypertime);
    let points: Vec<TimedPoint> = days
        .iter()
        .zip(labels)
        .filter(|(d, l)| **l == id && !held_out(d))
        .flat_map(|(d, _)| d.output.tracked.iter().copied())
        .collect();
    let activity = ActivityAt::new(
        layout.affordance().clone(),
        model.clone(),
        &points,
        &ActivityAtParams::default(),
    )?;
    let raster = activity.on_grid(layout.composite().geometry());
    let times: Vec<f64> = hours
        .iter()
        .map(|h| study.midnight() + h * 3600.0)
        .collect();
    let plans = serve::plan_at_times(
        layout,
        &raster,
        &times,
        from,
        to,
        &ServeParams::default(),
        SearchParams::default(),
    )?;
    Ok(TimedPlans {
        plans,
        periods: model.periods().to_vec(),
        rate_check: activity.rate_check().copied(),
    })
}
