//! Plans that keep out of people's way (issue 53), end to end on synthetic lanes: a flow map
//! fitted on earlier walkers, the flow weight chosen on the training observations alone,
//! and the plans scored on later walkers the map never saw.

use std::f64::consts::PI;

use haunts::affordance::flow::{FlowMap, FlowObservation, FlowParams, hold_out_last};
use haunts::occupancy::GridGeometry;
use haunts::pipeline::PipelineError;
use haunts::pipeline::flow::{
    FLOW_WEIGHTS, FlowPlanParams, MAX_LENGTH_RATIO, choose_flow_weight, directional_cost,
    flow_plans,
};
use haunts::planning::Costmap;
use nalgebra::Point2;
use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};
use rand_distr::{Distribution, Normal};

/// A hall 40 × 8 m: people walk east in its southern half and west in its northern half
/// (keeping right), with 0.25 rad of noise in heading, most of them seen in the middle of
/// the hall (x normal about 20 m, 6 m wide); `n` observations from `seed`, times in order.
fn keep_right(n: usize, seed: u64) -> Vec<FlowObservation> {
    let mut rng = StdRng::seed_from_u64(seed);
    let noise = Normal::new(0.0, 0.25).unwrap();
    let along = Normal::new(20.0, 6.0).unwrap();
    (0..n)
        .map(|i| {
            let east = rng.random::<f64>() < 0.5;
            let y = if east { 0.3 } else { 4.3 } + 3.4 * rng.random::<f64>();
            let heading = if east { 0.0 } else { PI } + noise.sample(&mut rng);
            let x: f64 = along.sample(&mut rng);
            FlowObservation::new(i as f64, Point2::new(x.clamp(0.1, 39.9), y), heading, 1.2)
        })
        .collect()
}

fn histogram(seen: &[FlowObservation]) -> FlowMap {
    let grid = GridGeometry::new(1.0, Point2::origin(), 40, 8).unwrap();
    FlowMap::fit(seen, grid, &FlowParams::default().with_mixture(false)).unwrap()
}

/// The hall's costmap, 0.25 m cells, all free.
fn hall() -> Costmap {
    Costmap::filled(
        GridGeometry::new(0.25, Point2::origin(), 160, 32).unwrap(),
        0,
    )
}

#[test]
fn on_held_out_walkers_the_flow_aware_plans_go_against_half_as_much_or_less() {
    let all = keep_right(20_000, 53);
    let (train, test) = hold_out_last(&all, 0.2);
    let costmap = hall();
    // Trips 8 m either side of the busiest cell: those along the hall (the ones across it,
    // 8 m wide, find no end and are dropped by `crossings`).
    let params = FlowPlanParams::default().with_crossings(12, 8.0);
    // The weight, on the training observations alone.
    let (inner_train, inner_test) = hold_out_last(&train, 0.2);
    let (weight, tried) = choose_flow_weight(
        &costmap,
        &histogram(&inner_train),
        &histogram(&inner_test),
        &FLOW_WEIGHTS,
        &params,
    )
    .unwrap();
    assert_eq!(tried.len(), FLOW_WEIGHTS.len());
    let chosen = tried.iter().find(|t| t.weight == weight).unwrap();
    assert!(chosen.plans.length_ratio() <= MAX_LENGTH_RATIO);
    for t in &tried {
        // No weight short enough goes less against the flow than the one chosen.
        if t.plans.length_ratio() <= MAX_LENGTH_RATIO {
            assert!(
                t.plans.flow_aware.against_flow_share >= chosen.plans.flow_aware.against_flow_share
            );
        }
    }
    let plans = flow_plans(
        &costmap,
        &histogram(&train),
        &histogram(&test),
        weight,
        &params,
    )
    .unwrap();
    assert!(plans.trips >= 5 && plans.no_path == 0, "{plans:?}");
    // The busiest cell lies inside the hall, and plain A* crosses it in every direction.
    assert!(plans.plain.against_flow_share > 0.2, "{plans:?}");
    assert!(plans.against_ratio() <= 0.5, "{plans:?}");
    // The weight was held to 10 % on the training data's own split; on the held-out walkers
    // the busiest cell and so the trips move, and a change of lane (about 2.5 m over and
    // back on a 16 m trip) costs about 13 %: bounded here by 20 %.
    assert!(plans.length_ratio() <= 1.2, "{plans:?}");
    assert!(plans.length_ratio() >= 1.0, "{plans:?}");
    // The lenient figure (the map planned on) and the traffic along the way are filled in.
    assert!(plans.flow_aware.against_flow_share_planned <= plans.plain.against_flow_share_planned);
    assert!(plans.plain.activity_mean > 0.0);
}

#[test]
fn a_weight_of_zero_plans_as_plain_a_star() {
    let seen = keep_right(4000, 7);
    let map = histogram(&seen);
    let plans = flow_plans(&hall(), &map, &map, 0.0, &FlowPlanParams::default()).unwrap();
    assert_eq!(plans.plain, plans.flow_aware);
}

#[test]
fn the_directional_cost_is_the_opposing_traffic_over_the_busiest() {
    let map = histogram(&keep_right(6000, 9));
    let g = *hall().geometry();
    let cost = directional_cost(&map, g).unwrap();
    let max = map.max_traffic();
    for (col, row) in [(10, 4), (50, 20), (95, 31)] {
        let cell = haunts::occupancy::Cell::new(col, row);
        for k in 0..8 {
            let expected =
                map.against(g.cell_center(cell), haunts::planning::move_heading(k)) / max;
            assert_eq!(cost.at(cell, k), Some(expected));
            assert!((0.0..=1.0).contains(&expected));
        }
    }
    // East in the westbound half costs, west there next to nothing.
    let north = haunts::occupancy::Cell::new(40, 24);
    assert!(cost.at(north, 0).unwrap() > 0.3);
    assert!(cost.at(north, 4).unwrap() < 0.05);
    // A map of nobody: a typed error, not a division by zero.
    let empty = histogram(&[]);
    assert!(matches!(
        directional_cost(&empty, g),
        Err(PipelineError::NoTraffic)
    ));
}

#[test]
fn the_flow_field_is_drawn_along_the_lanes_in_the_colours_of_its_headings() {
    use haunts::pipeline::flow::{flow_arrows, heading_rgb};
    let map = histogram(&keep_right(20_000, 11));
    let arrows = flow_arrows(&map, 0.1);
    assert!(arrows.len() > 100, "{}", arrows.len());
    for (tail, head) in &arrows {
        let d = head - tail;
        assert!((d.norm() - 0.8).abs() < 1e-9);
        let middle = Point2::from((tail.coords + head.coords) / 2.0);
        // East in the southern half, west in the northern.
        let expected = if middle.y < 4.0 { 1.0 } else { -1.0 };
        assert!((d.x / d.norm() - expected).abs() < 1e-9, "{tail} → {head}");
        assert!(map.traffic_at(middle) >= 0.1 * map.max_traffic());
    }
    // Fewer arrows for a higher floor; none over the busiest cell's own traffic.
    assert!(flow_arrows(&map, 0.5).len() < arrows.len());
    assert!(flow_arrows(&map, 1.01).is_empty());
    assert!(flow_arrows(&histogram(&[]), 0.1).is_empty());
    let close = |a: [f64; 3], b: [f64; 3]| a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-12);
    assert!(close(heading_rgb(0.0), [0.84, 0.0, 0.0]));
    assert!(close(heading_rgb(2.0 * PI / 3.0), [0.0, 0.84, 0.0]));
    assert!(close(heading_rgb(-2.0 * PI / 3.0), [0.0, 0.0, 0.84]));
    assert!(close(heading_rgb(2.0 * PI), heading_rgb(0.0)));
}
