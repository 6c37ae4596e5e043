//! A layout of the library served to a planner, as seed 000 serves its affordance map: the
//! layout's composite as the static map, its affordance map as a layer of the global costmap
//! whose cost rises with the density of people ("paths over areas more used by people have a
//! greater cost", seed 000 §V), and plans with and without that layer.

use haunts_affordance::activity_at::ActivityRaster;
use haunts_affordance::layout::Layout;
use haunts_affordance::{AffordanceError, DensityMap};
use haunts_occupancy::{Grid, OccupancyGrid};
use haunts_planning::{
    AStar, Combine, Costmap, DensityLayer, InflationLayer, InflationParams, LayeredCostmap,
    PathMetrics, Planner, SearchParams, StaticLayer,
};
use nalgebra::Point2;

use super::{PipelineError, Result};

/// How a layout is served.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub struct ServeParams {
    /// The composite's static map keeps cells occupied on at least this fraction of the
    /// layout's days (default 0.5, as the library classifies days).
    pub static_fraction: f64,
    /// Inflation around the static map's obstacles (default: the planning crate's).
    pub inflation: InflationParams,
    /// The affordance layer's cost at the density scale (default 200 of the 252 non-lethal
    /// levels), added to the cost below and saturated short of an obstacle: a busy cell is
    /// expensive but never a wall.
    pub weight: f64,
    /// The density at which the layer's cost reaches `weight`: `None` (the default) takes
    /// the layout's 99th percentile of known cells, so that a few extreme cells do not
    /// flatten the layer; cells above it cost `weight` too.
    pub scale: Option<f64>,
}

impl Default for ServeParams {
    fn default() -> Self {
        Self {
            static_fraction: 0.5,
            inflation: InflationParams::default(),
            weight: 200.0,
            scale: None,
        }
    }
}

impl ServeParams {
    /// Sets the static map's fraction of days.
    pub fn with_static_fraction(mut self, fraction: f64) -> Self {
        self.static_fraction = fraction;
        self
    }

    /// Sets the affordance layer's weight and scale (`None`: the 99th percentile).
    pub fn with_layer(mut self, weight: f64, scale: Option<f64>) -> Self {
        self.weight = weight;
        self.scale = scale;
        self
    }
}

/// A layout as a planner sees it.
#[derive(Debug, Clone)]
pub struct ServedLayout {
    /// The composite's static map (ROS map values: 100, 0, −1).
    pub map: OccupancyGrid,
    /// The costmap of the static map and its inflation.
    pub without_layer: Costmap,
    /// The same with the affordance layer on top.
    pub with_layer: Costmap,
    /// The layout's affordance density (NaN where too few visits).
    pub density: Grid<f64>,
    /// The density at which the layer reaches its weight.
    pub scale: f64,
}

#[cfg(feature = "figures")]
impl ServedLayout {
    /// The figure of the layout's affordance map over its composite's walls, coloured with
    /// turbo up to the density's 99th percentile (see [`percentile`]), titled `title`.
    pub fn figure(&self, title: impl Into<String>) -> crate::figure::MapFigure<'_> {
        let top = percentile(&self.density, 0.99).unwrap_or(1.0);
        crate::figure::MapFigure::new(title)
            .walls(&self.map)
            .scalar(
                &self.density,
                "people per laser visit",
                haunts_occupancy::picture::ColorMap::Turbo,
            )
            .range(0.0, top)
    }
}

/// Saves a served layout's maps as `haunts maps` writes them, into `dir`:
/// `layout_ID_composite.{yaml,pgm}` (trinary) and `layout_ID_costmap.{yaml,pgm}` (raw: the
/// costmap with the affordance layer in Nav2's translation to occupancy values). Returns the
/// two YAML paths.
///
/// # Errors
/// The files cannot be written.
pub fn save_layout_maps(
    dir: &std::path::Path,
    id: usize,
    served: &ServedLayout,
) -> Result<(std::path::PathBuf, std::path::PathBuf)> {
    use haunts_occupancy::{MapMode, MapSaveOptions, save_map};
    let composite = dir.join(format!("layout_{id}_composite.yaml"));
    let costmap = dir.join(format!("layout_{id}_costmap.yaml"));
    save_map(&composite, &served.map, &MapSaveOptions::default())?;
    let mut raw = MapSaveOptions::default();
    raw.mode = MapMode::Raw;
    save_map(&costmap, &served.with_layer.to_occupancy_grid(), &raw)?;
    Ok((composite, costmap))
}

/// Serves `layout`: static map, costmaps without and with its affordance layer.
///
/// # Errors
/// [`PipelineError::InvalidParameter`] for a weight outside `[0, 252]` or a scale that is
/// not finite and positive; [`PipelineError::EmptyDay`] when the layout's density knows no
/// cell (no scale can be taken); the crates' errors.
pub fn serve_layout(layout: &Layout, params: &ServeParams) -> Result<ServedLayout> {
    let density = layout.affordance().density_grid();
    serve_density(layout, density, None, params)
}

/// Serves `layout` with its activity at time `t` (UNIX seconds) in place of its affordance:
/// `activity` is the layout's time-independent map modulated by the daily rhythm
/// ([`ActivityAt`](haunts_affordance::ActivityAt), rasterised on the layout's cells by
/// [`ActivityAt::on_grid`](haunts_affordance::ActivityAt::on_grid)). Without a
/// [`ServeParams::scale`] the layer's scale is the 99th percentile of the *time-independent*
/// map, so that the layers of two times cost the same for the same activity and a busier
/// hour is dearer.
///
/// # Errors
/// As [`serve_layout`]; `GeometryMismatch` when `activity` is not on the layout's cells.
pub fn serve_layout_at<M: DensityMap>(
    layout: &Layout,
    activity: &ActivityRaster<'_, M>,
    t: f64,
    params: &ServeParams,
) -> Result<ServedLayout> {
    let geometry = *layout.composite().geometry();
    if !activity.geometry().same_cells(&geometry, 1e-9) {
        return Err(AffordanceError::GeometryMismatch {
            what: "activity raster",
            expected: Box::new(geometry),
            found: Box::new(*activity.geometry()),
        }
        .into());
    }
    serve_density(layout, activity.at(t), Some(&activity.base()), params)
}

/// The layout's static map and costmaps, with `density` as the layer, scaled by
/// `params.scale` or else the 99th percentile of `scale_of` (`density` itself by default).
fn serve_density(
    layout: &Layout,
    density: Grid<f64>,
    scale_of: Option<&Grid<f64>>,
    params: &ServeParams,
) -> Result<ServedLayout> {
    if !(0.0..=252.0).contains(&params.weight) {
        return Err(PipelineError::InvalidParameter(
            haunts_core::InvalidParameter {
                name: "serve.weight",
                value: params.weight,
                rule: "must be in [0, 252]",
            },
        ));
    }
    let map = layout.composite().static_map(params.static_fraction)?;
    let scale = match params.scale {
        Some(s) => {
            haunts_core::positive("serve.scale", s)?;
            s
        }
        None => percentile(scale_of.unwrap_or(&density), 0.99).ok_or(PipelineError::EmptyDay {
            what: "affordance cell with enough visits",
        })?,
    };
    let geometry = *map.geometry();
    let base = LayeredCostmap::new(geometry)
        .with_layer(StaticLayer::new(&map, false))
        .with_layer(InflationLayer::new(params.inflation)?);
    let without_layer = base.build()?;
    // Scaled so that `scale` costs `weight`; a cell above the scale costs no more.
    let scaled = density.map(|&d| (d / scale).min(1.0));
    let layer = DensityLayer::new(
        scaled,
        haunts_planning::DensityLayerParams::default()
            .with_weight(params.weight)
            .with_combine(Combine::Additive),
    )?;
    let with_layer = base.with_layer(layer).build()?;
    Ok(ServedLayout {
        map,
        without_layer,
        with_layer,
        density,
        scale,
    })
}

/// One trip planned at one time of day ([`plan_at_times`]).
#[derive(Debug, Clone)]
pub struct TimedPlan {
    /// The time, UNIX seconds.
    pub time: f64,
    /// The layout served with its activity at that time.
    pub served: ServedLayout,
    /// The plans without and with the activity layer, measured against the activity at
    /// that time.
    pub plans: PlanComparison,
}

/// The same trip `from` → `to` planned on `layout` served with its activity at each of
/// `times` ([`serve_layout_at`], [`compare_plans`]).
///
/// # Errors
/// As [`serve_layout_at`] and [`compare_plans`].
pub fn plan_at_times<M: DensityMap>(
    layout: &Layout,
    activity: &ActivityRaster<'_, M>,
    times: &[f64],
    from: Point2<f64>,
    to: Point2<f64>,
    params: &ServeParams,
    search: SearchParams,
) -> Result<Vec<TimedPlan>> {
    times
        .iter()
        .map(|&time| {
            let served = serve_layout_at(layout, activity, time, params)?;
            let plans = compare_plans(&served, from, to, search)?;
            Ok(TimedPlan {
                time,
                served,
                plans,
            })
        })
        .collect()
}

/// The mean and the largest of `density` over the cells of `path` (unknown cells and
/// points off the grid count as 0), `(0, 0)` for an empty path: a path planned at one time
/// measured against the activity of another.
pub fn activity_along(path: &[Point2<f64>], density: &Grid<f64>) -> (f64, f64) {
    let values: Vec<f64> = path
        .iter()
        .map(|p| {
            density
                .at_world(*p)
                .copied()
                .filter(|d| d.is_finite())
                .unwrap_or(0.0)
        })
        .collect();
    let max = values.iter().copied().fold(0.0, f64::max);
    let mean = values.iter().sum::<f64>() / values.len().max(1) as f64;
    (mean, max)
}

/// One trip planned on a served layout without and with its affordance layer.
#[derive(Debug, Clone, PartialEq)]
pub struct PlanComparison {
    /// A* on the costmap without the layer: length, and the density along the path.
    pub without_layer: PathMetrics,
    /// A* on the costmap with the layer.
    pub with_layer: PathMetrics,
    /// The path without the layer, cell centres from start to goal.
    pub without_path: Vec<Point2<f64>>,
    /// The path with the layer.
    pub with_path: Vec<Point2<f64>>,
}

/// Plans `from` → `to` with A* (`search`) on both costmaps of `served` and measures each path
/// against the layout's density (NaN cells count as 0: no one was seen there).
///
/// # Errors
/// The planner's errors: an endpoint outside the map or inside an obstacle, no path.
pub fn compare_plans(
    served: &ServedLayout,
    from: Point2<f64>,
    to: Point2<f64>,
    search: SearchParams,
) -> Result<PlanComparison> {
    let planner = AStar::new(search)?;
    let density = served.density.map(|d| if d.is_finite() { *d } else { 0.0 });
    let plan = |costmap: &Costmap| -> Result<(PathMetrics, Vec<Point2<f64>>)> {
        let path = planner.plan_world(costmap, from, to)?;
        Ok((path.metrics(&density)?, path.points()))
    };
    let (without_layer, without_path) = plan(&served.without_layer)?;
    let (with_layer, with_path) = plan(&served.with_layer)?;
    Ok(PlanComparison {
        without_layer,
        with_layer,
        without_path,
        with_path,
    })
}

/// The `q`-quantile of the finite values of `grid` (a density's known cells), `None` if there
/// are none or it is not positive: a colour or cost scale that a few extreme cells do not
/// flatten.
pub fn percentile(grid: &Grid<f64>, q: f64) -> Option<f64> {
    let mut v: Vec<f64> = grid
        .data()
        .iter()
        .copied()
        .filter(|v| v.is_finite())
        .collect();
    v.sort_by(f64::total_cmp);
    let i = ((v.len() as f64 - 1.0) * q).round();
    v.get(i.max(0.0) as usize).copied().filter(|p| *p > 0.0)
}
