//! Layered costmaps: inflation against its formula, the full stack, and no stale costs.

use haunts_occupancy::{Cell, Grid, GridGeometry, OccupancyGrid};
use haunts_planning::{
    Combine, Costmap, DensityLayer, DensityLayerParams, INSCRIBED_INFLATED_OBSTACLE,
    InflationLayer, InflationParams, LETHAL_OBSTACLE, Layer, LayerId, LayeredCostmap,
    MAX_NON_OBSTACLE, NO_INFORMATION, PlanningError, StaticLayer,
};
use nalgebra::Point2;

fn geometry(w: usize, h: usize) -> GridGeometry {
    GridGeometry::new(0.05, Point2::new(-2.0, 1.0), w, h).unwrap()
}

/// Nav2's formula, written out: 254 at the obstacle, 253 within the inscribed radius,
/// ⌊252·exp(−k·(d − r_i))⌋ up to the inflation radius, nothing beyond.
fn formula(d: f64, r_i: f64, r: f64, k: f64) -> u8 {
    if d == 0.0 {
        254
    } else if d <= r_i {
        253
    } else if d <= r {
        (252.0 * (-k * (d - r_i)).exp()).floor() as u8
    } else {
        0
    }
}

#[test]
fn inflation_matches_the_formula_at_every_distance() {
    let g = geometry(61, 61);
    let obstacle = Cell::new(30, 30);
    let (r_i, r, k) = (0.18, 1.2, 4.0);
    let mut costmap = Costmap::new(Grid::from_fn(g, |c| {
        if c == obstacle { LETHAL_OBSTACLE } else { 0 }
    }));
    let params = InflationParams::default()
        .with_inscribed_radius(r_i)
        .with_inflation_radius(r)
        .with_cost_scaling_factor(k);
    InflationLayer::new(params)
        .unwrap()
        .apply(&mut costmap)
        .unwrap();
    let mut sampled = [0usize; 4]; // lethal, inscribed, falling, beyond
    for (cell, &cost) in costmap.grid().cells() {
        let d = (cell.col.abs_diff(30) as f64).hypot(cell.row.abs_diff(30) as f64) * 0.05;
        let expected = formula(d, r_i, r, k);
        assert_eq!(cost, expected, "cell {cell:?} at {d} m");
        assert_eq!(params.cost_at(d), expected);
        sampled[match cost {
            254 => 0,
            253 => 1,
            0 => 3,
            _ => 2,
        }] += 1;
    }
    assert_eq!(sampled[0], 1);
    assert!(sampled.iter().all(|&n| n > 0), "{sampled:?}");
    // Spot checks by hand: 0.15 m is inscribed; 0.25 m gives ⌊252·e^{−0.28}⌋ = 190.
    assert_eq!(
        costmap.cost(Cell::new(33, 30)),
        Some(INSCRIBED_INFLATED_OBSTACLE)
    );
    assert_eq!(costmap.cost(Cell::new(35, 30)), Some(190));
}

#[test]
fn inflation_keeps_the_maximum_and_leaves_unknown_cells_unknown() {
    let g = geometry(20, 1);
    let mut data = vec![0u8; 20];
    data[0] = LETHAL_OBSTACLE;
    data[4] = NO_INFORMATION; // 0.2 m away: inscribed
    data[8] = NO_INFORMATION; // 0.4 m away: inflated, stays unknown
    data[9] = 250; // higher than its inflation
    let mut costmap = Costmap::new(Grid::from_vec(g, data).unwrap());
    let params = InflationParams::default(); // 0.22 m, 0.55 m, k = 3
    InflationLayer::new(params)
        .unwrap()
        .apply(&mut costmap)
        .unwrap();
    assert_eq!(costmap.data()[4], INSCRIBED_INFLATED_OBSTACLE);
    assert_eq!(costmap.data()[8], NO_INFORMATION);
    assert_eq!(costmap.data()[9], 250);
    assert_eq!(costmap.data()[10], params.cost_at(0.5));
    assert!(costmap.data()[10] > 0);
    assert_eq!(costmap.data()[12], 0);
}

#[test]
fn a_costmap_without_lethal_cells_is_not_inflated() {
    let g = geometry(5, 5);
    let mut costmap = Costmap::filled(g, 7);
    InflationLayer::new(InflationParams::default())
        .unwrap()
        .apply(&mut costmap)
        .unwrap();
    assert!(costmap.data().iter().all(|&c| c == 7));
}

/// A 40 × 20 map: a wall along row 15 (columns 0..30), unknown in the top-right corner.
fn map() -> OccupancyGrid {
    let g = geometry(40, 20);
    OccupancyGrid::from_grid(Grid::from_fn(g, |c| {
        if c.row == 15 && c.col < 30 {
            100
        } else if c.col >= 35 && c.row >= 17 {
            -1
        } else {
            0
        }
    }))
    .unwrap()
}

fn blob(g: GridGeometry, at: Cell) -> Grid<f64> {
    Grid::from_fn(g, |c| {
        let d2 = (c.col.abs_diff(at.col).pow(2) + c.row.abs_diff(at.row).pow(2)) as f64;
        (-d2 / 8.0).exp()
    })
}

fn stack(density: Grid<f64>, params: DensityLayerParams) -> (LayeredCostmap, LayerId) {
    let map = map();
    let mut stack = LayeredCostmap::new(*map.geometry())
        .with_layer(StaticLayer::new(&map, true))
        .with_layer(InflationLayer::new(InflationParams::default()).unwrap());
    let id = stack.push(DensityLayer::new(density, params).unwrap());
    (stack, id)
}

#[test]
fn the_full_stack_combines_static_inflation_and_density() {
    let g = *map().geometry();
    let params = DensityLayerParams::default().with_weight(200.0);
    let (stack, _) = stack(blob(g, Cell::new(20, 3)), params);
    let costmap = stack.build().unwrap();
    assert_eq!(stack.layers().count(), 3);
    let inflation = InflationParams::default(); // 0.22 m, 0.55 m, k = 3
    let density = |d2: f64| (200.0 * (-d2 / 8.0).exp()).round() as u8;
    assert_eq!(costmap.cost(Cell::new(5, 15)), Some(LETHAL_OBSTACLE));
    assert_eq!(
        costmap.cost(Cell::new(5, 17)),
        Some(INSCRIBED_INFLATED_OBSTACLE)
    ); // 0.1 m from the wall
    assert_eq!(costmap.cost(Cell::new(38, 18)), Some(NO_INFORMATION)); // density does not touch it
    assert_eq!(costmap.cost(Cell::new(20, 3)), Some(200)); // the blob's peak, 0.6 m from the wall
    assert_eq!(costmap.cost(Cell::new(38, 3)), Some(0));
    // Max mode: 0.35 m from the wall inflation wins; 0.5 m from it the blob does.
    assert!(inflation.cost_at(0.35) > density(25.0));
    assert_eq!(
        costmap.cost(Cell::new(20, 8)),
        Some(inflation.cost_at(0.35))
    );
    assert!(density(4.0) > inflation.cost_at(0.5));
    assert_eq!(costmap.cost(Cell::new(20, 5)), Some(density(4.0)));
}

#[test]
fn replacing_a_density_layer_leaves_no_stale_costs() {
    let g = *map().geometry();
    for combine in [Combine::Max, Combine::Overwrite, Combine::Additive] {
        let params = DensityLayerParams::default()
            .with_weight(150.0)
            .with_combine(combine);
        let (mut moving, id) = stack(blob(g, Cell::new(20, 3)), params);
        let before = moving.build().unwrap();
        assert!(before.cost(Cell::new(20, 3)).unwrap() >= 150, "{combine:?}");
        // People moved to (5, 8): the old blob must vanish entirely.
        let old = moving
            .replace(
                id,
                DensityLayer::new(blob(g, Cell::new(5, 8)), params).unwrap(),
            )
            .unwrap();
        assert!(format!("{old:?}").contains("DensityLayer"));
        let after = moving.build().unwrap();
        let (fresh, _) = stack(blob(g, Cell::new(5, 8)), params);
        assert_eq!(after, fresh.build().unwrap(), "{combine:?}");
        assert!(after.cost(Cell::new(20, 3)).unwrap() < 5, "{combine:?}");
        // Building twice (additive mode included) does not accumulate.
        assert_eq!(moving.build().unwrap(), after, "{combine:?}");
        let mut reused = before.clone();
        moving.build_into(&mut reused).unwrap();
        assert_eq!(reused, after, "{combine:?}");
    }
}

#[test]
fn seeking_people_with_a_negative_weight_lowers_costs_where_they_are() {
    let g = *map().geometry();
    let seek = DensityLayerParams::default()
        .with_weight(-100.0)
        .with_offset(100.0)
        .with_combine(Combine::Additive);
    let (stack, _) = stack(blob(g, Cell::new(20, 3)), seek);
    let costmap = stack.build().unwrap();
    assert_eq!(costmap.cost(Cell::new(20, 3)), Some(0));
    assert_eq!(costmap.cost(Cell::new(33, 3)), Some(100));
    assert_eq!(costmap.cost(Cell::new(5, 15)), Some(LETHAL_OBSTACLE));
    assert_eq!(
        costmap.cost(Cell::new(5, 17)),
        Some(INSCRIBED_INFLATED_OBSTACLE)
    );
    // 0.35 m from the wall: inflation 170 + 100 saturates below lethal.
    assert_eq!(costmap.cost(Cell::new(5, 8)), Some(MAX_NON_OBSTACLE));
}

#[test]
fn layers_on_other_grids_and_unknown_layer_ids_are_typed_errors() {
    let map = map();
    let other = geometry(41, 20);
    let stack = LayeredCostmap::new(other).with_layer(StaticLayer::new(&map, true));
    assert!(matches!(
        stack.build(),
        Err(PlanningError::GeometryMismatch {
            what: "static layer",
            ..
        })
    ));
    let mut wrong = Costmap::filled(geometry(3, 3), 0);
    assert!(matches!(
        stack.build_into(&mut wrong),
        Err(PlanningError::GeometryMismatch { .. })
    ));
    let mut small = LayeredCostmap::new(other);
    let (big, id) = self::stack(
        blob(*map.geometry(), Cell::new(1, 1)),
        DensityLayerParams::default(),
    );
    assert_eq!(id.index(), 2);
    assert!(big.build().is_ok());
    assert!(matches!(
        small.replace(id, InflationLayer::new(InflationParams::default()).unwrap()),
        Err(PlanningError::NoSuchLayer {
            index: 2,
            layers: 0
        })
    ));
}

/// Snapping onto free space: the nearest free cell by centre, against a scan of every cell;
/// a point far outside or an unbounded radius still answers at once, bad input is `None`.
#[test]
fn nearest_free_is_the_closest_free_cell() {
    let g = GridGeometry::new(0.5, Point2::new(-3.0, 2.0), 30, 20).unwrap();
    let costmap = Costmap::new(Grid::from_fn(g, |c| {
        if (c.col * 7 + c.row * 3) % 5 == 0 || c.col < 10 {
            LETHAL_OBSTACLE
        } else {
            0
        }
    }));
    let brute = |p: Point2<f64>, within: f64| {
        costmap
            .grid()
            .cells()
            .filter(|(_, v)| **v < INSCRIBED_INFLATED_OBSTACLE)
            .map(|(c, _)| c)
            .map(|c| ((g.cell_center(c) - p).norm(), c))
            .filter(|(d, _)| *d <= within)
            .min_by(|a, b| {
                a.0.total_cmp(&b.0)
                    .then(a.1.row.cmp(&b.1.row))
                    .then(a.1.col.cmp(&b.1.col))
            })
            .map(|(_, c)| c)
    };
    for (x, y) in [
        (0.0, 5.0),
        (-2.9, 2.1),
        (4.0, 7.0),
        (-10.0, 4.0),
        (20.0, 30.0),
    ] {
        for within in [0.3, 1.0, 2.5, 40.0] {
            let p = Point2::new(x, y);
            assert_eq!(
                costmap.nearest_free(p, within),
                brute(p, within),
                "{p} {within}"
            );
        }
    }
    let far = Point2::new(1e12, -1e12);
    assert_eq!(costmap.nearest_free(far, f64::MAX), brute(far, f64::MAX));
    assert!(costmap.nearest_free(far, f64::INFINITY).is_some());
    assert_eq!(costmap.nearest_free(far, 10.0), None);
    assert_eq!(costmap.nearest_free(Point2::new(f64::NAN, 3.0), 1.0), None);
    assert_eq!(costmap.nearest_free(Point2::new(0.0, 5.0), -1.0), None);
    assert_eq!(costmap.nearest_free(Point2::new(0.0, 5.0), f64::NAN), None);
}
