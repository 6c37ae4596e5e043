//! Plans that keep out of people's way (issue 53): a flow map as a planner's directional
//! cost, and plain against flow-aware A* on trips across the busiest place, scored on a flow
//! map of other observations (the `flow_map` example's `plans`); and a flow field as arrows
//! (`flow_arrows`, `flow_arrows_at`) in the colours of their headings (`heading_rgb`), as
//! `haunts maps --days` and the main job draw and publish it.
//!
//! ```
//! use haunts::affordance::flow::{FlowMap, FlowObservation, FlowParams};
//! use haunts::nalgebra::Point2;
//! use haunts::occupancy::GridGeometry;
//! use haunts::pipeline::flow::{FlowPlanParams, flow_plans};
//! use haunts::planning::Costmap;
//!
//! // A corridor 30 × 4 m: people walk east over y < 2 and west over y > 2, a crowd of
//! // them westwards around x = 15.
//! let seen: Vec<FlowObservation> = (0..6000)
//!     .map(|i| {
//!         let (x, y) = if i % 2 == 0 {
//!             ((i % 300) as f64 * 0.1, (i / 7 % 20) as f64 * 0.2 + 0.1)
//!         } else {
//!             (14.0 + (i % 20) as f64 * 0.1, 2.1 + (i / 7 % 10) as f64 * 0.2)
//!         };
//!         let heading = if y < 2.0 { 0.0 } else { std::f64::consts::PI };
//!         FlowObservation::new(i as f64, Point2::new(x, y), heading, 1.2)
//!     })
//!     .collect();
//! let grid = GridGeometry::new(1.0, Point2::origin(), 30, 4)?;
//! let flow = FlowMap::fit(&seen, grid, &FlowParams::default())?;
//! let costmap = Costmap::filled(GridGeometry::new(0.25, Point2::origin(), 120, 16)?, 0);
//! let params = FlowPlanParams::default().with_crossings(4, 10.0);
//! let plans = flow_plans(&costmap, &flow, &flow, 4.0, &params)?;
//! // The one trip along the corridor, eastwards from the crowd's lane: it changes lanes.
//! assert_eq!(plans.trips, 1);
//! assert_eq!(plans.plain.against_flow_share, 1.0);
//! assert!(plans.flow_aware.against_flow_share < 0.5 * plans.plain.against_flow_share);
//! assert!(plans.length_ratio() < 1.2);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use haunts_affordance::flow::FlowMap;
use haunts_occupancy::{Grid, GridGeometry};
use haunts_planning::{
    AStar, Costmap, DirectionalCost, FlowCostAStar, FlowCostParams, Path, Planner,
    against_flow_share, crossings, max_activity_cell,
};
use nalgebra::Point2;

use super::{PipelineError, Result};

/// The flow map's opposing traffic on `geometry`'s cells as a planner's directional cost:
/// [`FlowMap::against`] at each cell's centre for each move's heading, over
/// [`FlowMap::max_traffic`], so in `[0, 1]` (1: head-on against the busiest cell's people).
///
/// # Errors
/// [`PipelineError::NoTraffic`] for a map without traffic; the planning crate's errors.
pub fn directional_cost(map: &FlowMap, geometry: GridGeometry) -> Result<DirectionalCost> {
    let max = map.max_traffic();
    // max_traffic is a fold from 0 over finite counts: never NaN.
    if max <= 0.0 {
        return Err(PipelineError::NoTraffic);
    }
    Ok(DirectionalCost::from_fn(geometry, |c, heading| {
        map.against(geometry.cell_center(c), heading) / max
    })?)
}

/// Parameters of [`flow_plans`].
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub struct FlowPlanParams {
    /// Trips across the busiest cell, one per direction over half a turn (12).
    pub crossings: usize,
    /// How far either side of it each trip starts and ends, metres (5).
    pub radius: f64,
}

impl Default for FlowPlanParams {
    fn default() -> Self {
        Self {
            crossings: 12,
            radius: 5.0,
        }
    }
}

impl FlowPlanParams {
    /// Sets the number of trips and their radius.
    pub fn with_crossings(mut self, crossings: usize, radius: f64) -> Self {
        (self.crossings, self.radius) = (crossings, radius);
        self
    }
}

/// A planner's figures, as means over the trips with a path.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct PlanFigures {
    /// Length, metres.
    pub length: f64,
    /// The share of the length moving at more than 90° from the dominant flow of the cells
    /// entered, on the map the plans are scored on ([`against_flow_share`]).
    pub against_flow_share: f64,
    /// The same on the map the plans were made on (lenient: the planner saw it).
    pub against_flow_share_planned: f64,
    /// The scoring map's traffic ([`FlowMap::traffic_at`]) along the path, mean over its cells.
    pub activity_mean: f64,
}

impl PlanFigures {
    fn add(&mut self, o: &Self) {
        self.length += o.length;
        self.against_flow_share += o.against_flow_share;
        self.against_flow_share_planned += o.against_flow_share_planned;
        self.activity_mean += o.activity_mean;
    }
    fn mean(mut self, n: usize) -> Self {
        let n = n.max(1) as f64;
        self.length /= n;
        self.against_flow_share /= n;
        self.against_flow_share_planned /= n;
        self.activity_mean /= n;
        self
    }
}

/// What [`flow_plans`] found.
#[derive(Debug, Clone, PartialEq)]
pub struct FlowPlans {
    /// Trips planned by both planners.
    pub trips: usize,
    /// Trips without a path.
    pub no_path: usize,
    /// The busiest free cell's centre (most traffic on the planning map).
    pub busiest: Point2<f64>,
    /// Plain A*'s figures (means over the trips).
    pub plain: PlanFigures,
    /// The flow-aware A*'s.
    pub flow_aware: PlanFigures,
}

impl FlowPlans {
    /// Mean length, flow-aware over plain (NaN without trips).
    pub fn length_ratio(&self) -> f64 {
        self.flow_aware.length / self.plain.length
    }
    /// Mean against-flow share, flow-aware over plain (NaN when plain A* never went against).
    pub fn against_ratio(&self) -> f64 {
        self.flow_aware.against_flow_share / self.plain.against_flow_share
    }
}

/// Plain A* against the flow-aware A* (`FlowCostAStar`, flow weight `weight`, no activity
/// term) on trips across the cell of most traffic of `plan_map` ([`crossings`]), the
/// flow-aware one paying [`directional_cost`] of `plan_map`; each plan scored on `score_map`
/// (a flow map of other observations: those held out) and, leniently, on `plan_map`.
///
/// # Errors
/// As [`directional_cost`]; the planning crate's errors for bad parameters; a path's
/// metrics' errors.
pub fn flow_plans(
    costmap: &Costmap,
    plan_map: &FlowMap,
    score_map: &FlowMap,
    weight: f64,
    params: &FlowPlanParams,
) -> Result<FlowPlans> {
    let geometry = *costmap.geometry();
    let centre = |c| geometry.cell_center(c);
    let aware = FlowCostAStar::new(
        directional_cost(plan_map, geometry)?,
        FlowCostParams::default()
            .with_flow_weight(weight)
            .with_activity_weight(0.0),
    )?;
    let traffic = |map: &FlowMap| Grid::from_fn(geometry, |c| map.traffic_at(centre(c)));
    let (plan_traffic, score_traffic) = (traffic(plan_map), traffic(score_map));
    let busiest = max_activity_cell(&plan_traffic, costmap)?;
    let figures = |path: &Path| -> Result<PlanFigures> {
        Ok(PlanFigures {
            length: path.length(),
            against_flow_share: against_flow_share(path, |c| score_map.dominant(centre(c))),
            against_flow_share_planned: against_flow_share(path, |c| plan_map.dominant(centre(c))),
            activity_mean: path.metrics(&score_traffic)?.activity_mean,
        })
    };
    let (mut plain, mut flow_aware) = (PlanFigures::default(), PlanFigures::default());
    let (mut trips, mut no_path) = (0, 0);
    for (s, g) in crossings(costmap, busiest, params.radius, params.crossings)? {
        let (Ok(p), Ok(a)) = (
            AStar::default().plan(costmap, s, g),
            aware.plan(costmap, s, g),
        ) else {
            no_path += 1;
            continue;
        };
        plain.add(&figures(&p)?);
        flow_aware.add(&figures(&a)?);
        trips += 1;
    }
    Ok(FlowPlans {
        trips,
        no_path,
        busiest: centre(busiest),
        plain: plain.mean(trips),
        flow_aware: flow_aware.mean(trips),
    })
}

/// The flow weight [`choose_flow_weight`] picks among, by default.
pub const FLOW_WEIGHTS: [f64; 6] = [0.5, 1.0, 2.0, 4.0, 8.0, 16.0];

/// The most a flow-aware plan may be longer than the plain one, on average, for
/// [`choose_flow_weight`] to pick its weight: 10 % (issue 53's bound).
pub const MAX_LENGTH_RATIO: f64 = 1.10;

/// One weight tried by [`choose_flow_weight`]: the weight and its trips' figures.
#[derive(Debug, Clone, PartialEq)]
pub struct WeightTried {
    /// The flow weight.
    pub weight: f64,
    /// Its plans.
    pub plans: FlowPlans,
}

/// The flow weight of `weights` whose plans (made on `plan_map`, scored on `score_map`, two
/// maps of *training* observations: an earlier part and a later one) go least against the
/// flow while at most [`MAX_LENGTH_RATIO`] times as long as plain A*'s on average; the
/// smallest weight when none is short enough. Returns it with every weight's plans.
///
/// # Errors
/// As [`flow_plans`].
pub fn choose_flow_weight(
    costmap: &Costmap,
    plan_map: &FlowMap,
    score_map: &FlowMap,
    weights: &[f64],
    params: &FlowPlanParams,
) -> Result<(f64, Vec<WeightTried>)> {
    let mut tried = Vec::with_capacity(weights.len());
    let mut best: Option<(f64, f64)> = None;
    for &weight in weights {
        let plans = flow_plans(costmap, plan_map, score_map, weight, params)?;
        let against = plans.flow_aware.against_flow_share;
        if plans.length_ratio() <= MAX_LENGTH_RATIO && best.is_none_or(|(_, a)| against < a) {
            best = Some((weight, against));
        }
        tried.push(WeightTried { weight, plans });
    }
    let fallback = weights.iter().copied().fold(f64::INFINITY, f64::min);
    Ok((best.map_or(fallback, |(w, _)| w), tried))
}

/// The colour of `heading` (radians) on a colour wheel, red, green, blue in `[0, 1]`: hue =
/// heading (east red, a third of a turn on green, two thirds blue), full saturation, lightness
/// 0.42 (the figures' arrows and the MCAP's flow markers alike).
pub fn heading_rgb(heading: f64) -> [f64; 3] {
    let hue = heading.rem_euclid(std::f64::consts::TAU) / std::f64::consts::TAU * 6.0;
    let (l, s) = (0.42, 1.0);
    let chroma = (1.0 - (2.0 * l - 1.0_f64).abs()) * s;
    let x = chroma * (1.0 - (hue.rem_euclid(2.0) - 1.0).abs());
    let (r, g, b) = match hue as u32 {
        0 => (chroma, x, 0.0),
        1 => (x, chroma, 0.0),
        2 => (0.0, chroma, x),
        3 => (0.0, x, chroma),
        4 => (x, 0.0, chroma),
        _ => (chroma, 0.0, x),
    };
    let m = l - chroma / 2.0;
    [r + m, g + m, b + m]
}

/// The arrows of a flow field: for every cell of `map` standing on its own observations with
/// at least `min_share` of the busiest cell's traffic, `(tail, head)` through its centre along
/// its dominant direction ([`FlowMap::dominant`]), 0.8 of a cell long.
pub fn flow_arrows(map: &FlowMap, min_share: f64) -> Vec<(Point2<f64>, Point2<f64>)> {
    let g = map.geometry();
    let floor = min_share * map.max_traffic();
    (0..g.len())
        .filter_map(|i| g.cell_at(i))
        .filter_map(|c| {
            let p = g.cell_center(c);
            let own = matches!(
                map.source_at(p),
                Some((haunts_affordance::flow::CellSource::Own, _))
            );
            if !own || map.traffic_at(p) < floor || floor <= 0.0 {
                return None;
            }
            let heading = map.dominant(p)?;
            let half = nalgebra::Vector2::new(heading.cos(), heading.sin()) * 0.4 * g.resolution();
            Some((p - half, p + half))
        })
        .collect()
}

/// [`flow_arrows`] at time `t` of a
/// [`TimedFlowMap`](haunts_affordance::flow::TimedFlowMap): the same cells (its static
/// map's), each arrow along the direction bin most likely at `t` (the first of equals).
pub fn flow_arrows_at(
    map: &haunts_affordance::flow::TimedFlowMap,
    t: f64,
    min_share: f64,
) -> Vec<(Point2<f64>, Point2<f64>)> {
    let bins = map.base().params().bins;
    flow_arrows(map.base(), min_share)
        .into_iter()
        .map(|(tail, head)| {
            let p = Point2::from((tail.coords + head.coords) / 2.0);
            let heading = (0..bins)
                .map(|b| b as f64 * std::f64::consts::TAU / bins as f64)
                .fold((0.0, f64::NEG_INFINITY), |best, h| {
                    let d = map.density(p, h, t);
                    if d > best.1 { (h, d) } else { best }
                })
                .0;
            let half =
                nalgebra::Vector2::new(heading.cos(), heading.sin()) * (head - tail).norm() / 2.0;
            (p - half, p + half)
        })
        .collect()
}
