//! With the `serde` feature, parameters, costmaps, paths and path metrics round-trip through
//! JSON, and deserialising a costmap or a path checks what the constructors and planners
//! guarantee.
#![cfg(feature = "serde")]
#![allow(clippy::unwrap_used)]

use haunts_occupancy::{Cell, Grid, GridGeometry, OccupancyGrid};
use haunts_planning::{
    AStar, ActivityAwareAStar, ActivityAwareParams, ActivityCostAStar, ActivityCostParams, Combine,
    Costmap, DensityLayer, DensityLayerParams, Dijkstra, InflationLayer, InflationParams,
    LayeredCostmap, Path, PathMetrics, Planner, SearchParams, StaticLayer, StraightLine,
    UnknownPolicy, crossings, max_activity_cell,
};
use nalgebra::Point2;

use haunts_test_support::json;
use json::{corrupt, rejection, round_trip};

/// A walled 4 m × 2 m room at 0.1 m, a costmap of it with inflation and people near its
/// middle, and the people's density.
fn scene() -> (Costmap, Grid<f64>) {
    let g = GridGeometry::new(0.1, Point2::new(-1.0, 0.5), 40, 20).unwrap();
    let wall = |c: Cell| c.col == 0 || c.row == 0 || c.col == 39 || c.row == 19;
    let map =
        OccupancyGrid::from_grid(Grid::from_fn(g, |c| if wall(c) { 100 } else { 0 })).unwrap();
    let people = Grid::from_fn(g, |c| {
        let p = g.cell_center(c);
        3.0 * (-((p.x - 1.0).powi(2) + (p.y - 1.5).powi(2)) / 0.3).exp()
    });
    let costmap = LayeredCostmap::new(g)
        .with_layer(StaticLayer::new(&map, true))
        .with_layer(InflationLayer::new(InflationParams::default()).unwrap())
        .with_layer(
            DensityLayer::new(
                people.clone(),
                DensityLayerParams::default().with_weight(60.0),
            )
            .unwrap(),
        )
        .build()
        .unwrap();
    (costmap, people)
}

#[test]
fn parameters_round_trip_through_json() {
    for policy in [UnknownPolicy::Forbid, UnknownPolicy::Allow(77)] {
        round_trip(&policy);
    }
    for combine in [Combine::Max, Combine::Overwrite, Combine::Additive] {
        round_trip(&combine);
    }
    let search = SearchParams::default()
        .with_cost_weight(0.75)
        .with_unknown(UnknownPolicy::Allow(120));
    assert_ne!(search, SearchParams::default());
    round_trip(&search);
    let inflation = InflationParams::default()
        .with_inscribed_radius(0.3)
        .with_inflation_radius(1.25)
        .with_cost_scaling_factor(4.5);
    assert_ne!(inflation, InflationParams::default());
    round_trip(&inflation);
    let density = DensityLayerParams::default()
        .with_weight(-150.0)
        .with_offset(200.0)
        .with_combine(Combine::Additive);
    assert_ne!(density, DensityLayerParams::default());
    round_trip(&density);
    let aware = ActivityAwareParams::default()
        .with_search(search)
        .with_threshold(3.25);
    assert_ne!(aware, ActivityAwareParams::default());
    round_trip(&aware);
    let cost = ActivityCostParams::default()
        .with_search(search)
        .with_activity_weight(0.125);
    assert_ne!(cost, ActivityCostParams::default());
    round_trip(&cost);
}

#[test]
fn costmaps_paths_and_metrics_round_trip_through_json() {
    let (costmap, people) = scene();
    assert!(costmap.data().iter().any(|&c| c > 0 && c < 253));
    let back = round_trip(&costmap);
    assert_eq!(back.geometry(), costmap.geometry());

    let planner = AStar::new(SearchParams::default().with_cost_weight(1.5)).unwrap();
    let path = planner
        .plan(&costmap, Cell::new(3, 3), Cell::new(36, 16))
        .unwrap();
    assert!(path.cells().len() > 30 && path.cost() > path.length());
    let back: Path = round_trip(&path);
    assert_eq!(back.length(), path.length());
    assert_eq!((back.start(), back.goal()), (path.start(), path.goal()));

    let metrics: PathMetrics = path.metrics(&people).unwrap();
    assert!(metrics.activity_max > 0.0 && metrics.activity_variance > 0.0);
    round_trip(&metrics);
    assert_eq!(back.metrics(&people).unwrap(), metrics);

    // A one-cell path (start = goal) is a path too.
    round_trip(
        &planner
            .plan(&costmap, Cell::new(5, 5), Cell::new(5, 5))
            .unwrap(),
    );
}

#[test]
fn an_invalid_costmap_is_rejected() {
    let geometry = r#"{"resolution":0.5,"origin":[0.0,0.0],"width":2,"height":2}"#;
    let ok: Costmap = serde_json::from_str(&format!(
        r#"{{"geometry":{geometry},"data":[0,254,255,3]}}"#
    ))
    .unwrap();
    assert_eq!(ok.cost(Cell::new(1, 0)), Some(254));
    let e = rejection::<Costmap>(&format!(r#"{{"geometry":{geometry},"data":[0,254,255]}}"#));
    assert!(e.contains("3 elements, expected 4"), "{e}");
    let e = rejection::<Costmap>(&format!(r#"{{"geometry":{geometry},"data":[0,1,2,256]}}"#));
    assert!(e.contains("256"), "{e}");
    let bad_geometry = geometry.replace("0.5", "0.0");
    let e = rejection::<Costmap>(&format!(
        r#"{{"geometry":{bad_geometry},"data":[0,0,0,0]}}"#
    ));
    assert!(e.contains("`resolution`"), "{e}");
}

#[test]
fn an_invalid_path_is_rejected() {
    let geometry = r#"{"resolution":0.5,"origin":[1.0,2.0],"width":4,"height":3}"#;
    let path = |cells: &str, cost: &str| {
        format!(r#"{{"geometry":{geometry},"cells":{cells},"cost":{cost}}}"#)
    };
    let ok: Path = serde_json::from_str(&path(
        r#"[{"col":0,"row":0},{"col":1,"row":1},{"col":2,"row":1}]"#,
        "1.5",
    ))
    .unwrap();
    assert_eq!(
        ok.cells(),
        &[Cell::new(0, 0), Cell::new(1, 1), Cell::new(2, 1)]
    );
    assert_eq!(ok.points()[2], Point2::new(2.25, 2.75));

    let e = rejection::<Path>(&path("[]", "0.0"));
    assert!(e.contains("`cells`") && e.contains("start cell"), "{e}");
    let e = rejection::<Path>(&path(r#"[{"col":3,"row":2},{"col":4,"row":2}]"#, "0.5"));
    assert!(e.contains("`cells` = 1") && e.contains("outside"), "{e}");
    let e = rejection::<Path>(&path(r#"[{"col":0,"row":0},{"col":2,"row":0}]"#, "1.0"));
    assert!(
        e.contains("`cells` = 1") && e.contains("8-neighbour"),
        "{e}"
    );
    let e = rejection::<Path>(&path(
        r#"[{"col":0,"row":0},{"col":1,"row":0},{"col":1,"row":0}]"#,
        "1.0",
    ));
    assert!(
        e.contains("`cells` = 2") && e.contains("8-neighbour"),
        "{e}"
    );
    let e = rejection::<Path>(&path(r#"[{"col":0,"row":0}]"#, "-1.0"));
    assert!(e.contains("`cost`"), "{e}");
    let bad_geometry = path(r#"[{"col":0,"row":0}]"#, "0.0").replace("\"width\":4", "\"width\":0");
    let e = rejection::<Path>(&bad_geometry);
    assert!(e.contains("0×3"), "{e}");
}

/// Every planner on a loaded costmap, between corners and the middle; errors are fine.
fn plan_on(costmap: &Costmap, people: &Grid<f64>) {
    let g = *costmap.geometry();
    let (w, h) = (g.width(), g.height());
    let ends = [
        (
            Cell::new(3, 3),
            Cell::new(w.saturating_sub(4), h.saturating_sub(4)),
        ),
        (Cell::new(0, 0), Cell::new(w - 1, h - 1)),
        (Cell::new(w / 2, h / 2), Cell::new(w / 2, h / 2)),
        (Cell::new(w, 0), Cell::new(0, 0)),
    ];
    let search = SearchParams::default().with_cost_weight(2.0);
    let mut planners: Vec<Box<dyn Planner>> = vec![
        Box::new(AStar::new(search).unwrap()),
        Box::new(Dijkstra::new(search).unwrap()),
        Box::new(StraightLine::new(search).unwrap()),
    ];
    // The activity planners need the activity on the costmap's grid: the loaded one's.
    let activity = Grid::from_fn(g, |c| people.get(c).copied().unwrap_or(0.0));
    planners.push(Box::new(
        ActivityAwareAStar::new(activity.clone(), ActivityAwareParams::default()).unwrap(),
    ));
    planners.push(Box::new(
        ActivityCostAStar::new(activity.clone(), ActivityCostParams::default()).unwrap(),
    ));
    for planner in &planners {
        for (start, goal) in ends {
            if let Ok(path) = planner.plan(costmap, start, goal) {
                assert_eq!((path.start(), path.goal()), (start, goal));
                assert!(
                    path.cost().is_finite() && path.cost() >= 0.0,
                    "{}",
                    path.cost()
                );
                path.metrics(&activity).unwrap();
                let _ = path.metrics(people);
            }
        }
        let _ = planner.plan_world(costmap, g.origin(), g.upper_corner());
    }
    let _ = Dijkstra::new(search)
        .unwrap()
        .cost_to_go(costmap, Cell::new(w / 2, h / 2))
        .map(|field| (field.grid(), field.path_from(Cell::new(0, 0))));
    let _ = max_activity_cell(&activity, costmap);
    let _ = crossings(costmap, Cell::new(w / 2, h / 2), 0.5, 8);
    let _ = costmap.nearest_free(g.cell_center(Cell::new(w / 2, h / 2)), 1.0);
    let _ = costmap.cost_at_world(g.origin());
}

/// Its endpoints, length, points and metrics, and re-planning between its endpoints.
fn use_path(path: &Path, costmap: &Costmap, people: &Grid<f64>) {
    let (start, goal) = (path.start(), path.goal());
    assert_eq!(path.points().len(), path.cells().len());
    assert!(path.length() >= 0.0);
    let _ = path.cost();
    let _ = path.metrics(people);
    let activity = Grid::filled(*path.geometry(), 1.0);
    let m = path.metrics(&activity).unwrap();
    assert_eq!(m.activity_mean, 1.0);
    let _ = AStar::default().plan(costmap, start, goal);
}

#[test]
fn corrupted_files_are_refused_or_usable_never_a_panic() {
    let (costmap, people) = scene();
    let costmaps = corrupt(&costmap, 5000, |loaded: &Costmap| plan_on(loaded, &people));
    let path = AStar::default()
        .plan(&costmap, Cell::new(3, 3), Cell::new(36, 16))
        .unwrap();
    let paths = corrupt(&path, 1000, |loaded: &Path| {
        use_path(loaded, &costmap, &people)
    });
    for (name, tally) in [("Costmap", costmaps), ("Path", paths)] {
        eprintln!("{name}: {tally:?}");
        assert!(tally.refused > 0 && tally.accepted > 0, "{name}: {tally:?}");
    }
}
