//! Bad input gives typed errors that name what was wrong; nothing panics.

use haunts_occupancy::{Cell, Grid, GridGeometry, OccupancyError};
use haunts_planning::{
    AStar, ActivityAwareAStar, ActivityAwareParams, ActivityCostAStar, ActivityCostParams, Costmap,
    DensityLayer, DensityLayerParams, Dijkstra, InflationLayer, InflationParams, LETHAL_OBSTACLE,
    Layer, NO_INFORMATION, Planner, PlanningError, SearchParams, StraightLine, UnknownPolicy,
    max_activity_cell,
};
use nalgebra::Point2;

fn geometry(w: usize, h: usize) -> GridGeometry {
    GridGeometry::new(0.1, Point2::origin(), w, h).unwrap()
}

fn invalid<T: std::fmt::Debug>(result: Result<T, PlanningError>) -> &'static str {
    match result {
        Err(PlanningError::InvalidParameter(haunts_core::InvalidParameter { name, .. })) => name,
        other => panic!("expected an invalid parameter, got {other:?}"),
    }
}

#[test]
fn nan_and_out_of_range_parameters_are_named() {
    let bad_search = SearchParams::default().with_cost_weight(f64::NAN);
    assert_eq!(invalid(AStar::new(bad_search)), "cost_weight");
    assert_eq!(invalid(Dijkstra::new(bad_search)), "cost_weight");
    assert_eq!(invalid(StraightLine::new(bad_search)), "cost_weight");
    let quiet = Grid::filled(geometry(3, 3), 0.0);
    assert_eq!(
        invalid(ActivityAwareAStar::new(
            quiet.clone(),
            ActivityAwareParams::default().with_threshold(f64::NAN)
        )),
        "threshold"
    );
    assert_eq!(
        invalid(ActivityAwareAStar::new(
            quiet.clone(),
            ActivityAwareParams::default().with_search(bad_search)
        )),
        "cost_weight"
    );
    assert_eq!(
        invalid(ActivityCostAStar::new(
            quiet.clone(),
            ActivityCostParams::default().with_activity_weight(f64::NAN)
        )),
        "activity_weight"
    );
    assert_eq!(
        invalid(ActivityCostAStar::new(
            quiet.clone(),
            ActivityCostParams::default().with_activity_weight(-0.5)
        )),
        "activity_weight"
    );
    assert_eq!(
        invalid(AStar::new(
            SearchParams::default().with_unknown(UnknownPolicy::Allow(NO_INFORMATION))
        )),
        "unknown cost"
    );
    assert_eq!(
        invalid(DensityLayer::new(
            quiet.clone(),
            DensityLayerParams::default().with_weight(f64::NAN)
        )),
        "weight"
    );
    assert_eq!(
        invalid(InflationLayer::new(
            InflationParams::default().with_cost_scaling_factor(f64::NAN)
        )),
        "cost_scaling_factor"
    );
    let message = AStar::new(bad_search).unwrap_err().to_string();
    assert!(
        message.contains("cost_weight") && message.contains("NaN"),
        "{message}"
    );
}

#[test]
fn non_finite_activity_is_rejected_where_it_is() {
    let mut activity = Grid::filled(geometry(4, 3), 1.0);
    activity[Cell::new(2, 1)] = f64::NAN;
    for result in [
        ActivityAwareAStar::new(activity.clone(), ActivityAwareParams::default()).map(|_| ()),
        ActivityCostAStar::new(activity.clone(), ActivityCostParams::default()).map(|_| ()),
    ] {
        assert!(matches!(
            result,
            Err(PlanningError::NonFiniteActivity {
                cell: Cell { col: 2, row: 1 },
                value,
            }) if value.is_nan()
        ));
    }
    // Metrics need finite activity on the path's cells only.
    let costmap = Costmap::filled(geometry(4, 3), 0);
    let path = AStar::default()
        .plan(&costmap, Cell::new(0, 0), Cell::new(3, 0))
        .unwrap();
    assert!(path.metrics(&activity).is_ok());
    let through = AStar::default()
        .plan(&costmap, Cell::new(0, 1), Cell::new(3, 1))
        .unwrap();
    assert!(matches!(
        through.metrics(&activity),
        Err(PlanningError::NonFiniteActivity { .. })
    ));
}

#[test]
fn rasters_on_other_grids_are_rejected() {
    let costmap = Costmap::filled(geometry(4, 3), 0);
    let other = Grid::filled(geometry(3, 4), 1.0);
    let (s, t) = (Cell::new(0, 0), Cell::new(3, 2));
    for planner in [
        Box::new(ActivityAwareAStar::new(other.clone(), ActivityAwareParams::default()).unwrap())
            as Box<dyn Planner>,
        Box::new(ActivityCostAStar::new(other.clone(), ActivityCostParams::default()).unwrap()),
    ] {
        assert!(matches!(
            planner.plan(&costmap, s, t),
            Err(PlanningError::GeometryMismatch {
                what: "activity raster",
                ..
            })
        ));
    }
    assert!(matches!(
        max_activity_cell(&other, &costmap),
        Err(PlanningError::GeometryMismatch { .. })
    ));
    let path = AStar::default().plan(&costmap, s, t).unwrap();
    assert!(matches!(
        path.metrics(&other),
        Err(PlanningError::GeometryMismatch { .. })
    ));
}

#[test]
fn no_cell_of_maximum_activity_is_an_error() {
    let g = geometry(2, 1);
    let costmap = Costmap::new(Grid::from_vec(g, vec![LETHAL_OBSTACLE, 0]).unwrap());
    let activity = Grid::from_vec(g, vec![5.0, f64::NAN]).unwrap();
    assert!(matches!(
        max_activity_cell(&activity, &costmap),
        Err(PlanningError::NoActivity)
    ));
}

#[test]
fn a_map_too_large_for_the_distance_transform_is_an_occupancy_error() {
    // 70 000 × 1 cells: squared distances would overflow the EDT's u32.
    let g = GridGeometry::new(0.05, Point2::origin(), 70_000, 1).unwrap();
    let mut costmap = Costmap::filled(g, 0);
    costmap.grid_mut().data_mut()[0] = LETHAL_OBSTACLE;
    let result = InflationLayer::new(InflationParams::default())
        .unwrap()
        .apply(&mut costmap);
    assert!(matches!(
        result,
        Err(PlanningError::Occupancy(OccupancyError::BadGridSize { .. }))
    ));
}
