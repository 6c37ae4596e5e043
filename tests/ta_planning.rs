//! Seed 002's activity-aware A* (θ = 5.5) on the TA maps of the real ETH scenes, over trips
//! that cross the busiest cell from twelve directions (as `examples/ta_map.rs` reports them):
//! on average it meets less activity, both in the mean and at the worst point, for a
//! slightly longer path (seed 002, Table 2). Skipped with a notice when `../shared/data` is
//! absent.
//!
//! Single trips differ: one straight along the flow of `seq_eth`, where every cell within
//! reach is above θ, is the plain path (see issue 7's notes); the average over directions
//! is the behaviour a user sees across goals.
#![allow(clippy::unwrap_used)]

use haunts::affordance::ta::{TaMap, TaParams};
use haunts::occupancy::GridGeometry;
use haunts::planning::{
    AStar, ActivityAwareAStar, ActivityAwareParams, Costmap, PathMetrics, Planner, crossings,
    max_activity_cell,
};
use haunts::tracking::track::dummy::{DummyFilterParams, filter_dummies};
use haunts::tracking::{EthOptions, read_eth};

use data::shared_data;
use haunts_test_support::data;

/// Mean length, mean activity and mean maximum activity over the crossings, for the plain
/// and the activity-aware A*.
fn crossing_means(scene: &str) -> Option<[[f64; 3]; 2]> {
    let file = shared_data(&format!("trajectories/eth/{scene}/obsmat.txt"))?;
    let all = read_eth(&file, &EthOptions::default()).unwrap().records;
    let kept = filter_dummies(all, &DummyFilterParams::default().with_min_samples(5))
        .unwrap()
        .kept;
    let points = kept.iter().flat_map(|t| t.samples.iter().map(|s| s.1));
    let geometry = GridGeometry::bounding(points, 0.1, 2.0).unwrap();
    let ta = TaMap::fit(&kept, geometry, &TaParams::default()).unwrap();
    let activity = ta.raster();
    let costmap = Costmap::filled(geometry, 0);
    let busiest = max_activity_cell(activity, &costmap).unwrap();
    let aware = ActivityAwareAStar::new(activity.clone(), ActivityAwareParams::default()).unwrap();
    let planners: [&dyn Planner; 2] = [&AStar::default(), &aware];
    let trips = crossings(&costmap, busiest, 5.0, 12).unwrap();
    assert_eq!(trips.len(), 12, "{scene}: the map is free all round");
    let mut sums = [[0.0; 3]; 2];
    for (start, goal) in trips {
        for (sum, planner) in sums.iter_mut().zip(planners) {
            let m: PathMetrics = planner
                .plan(&costmap, start, goal)
                .unwrap()
                .metrics(activity)
                .unwrap();
            for (s, v) in sum
                .iter_mut()
                .zip([m.length, m.activity_mean, m.activity_max])
            {
                *s += v / 12.0;
            }
        }
    }
    eprintln!("{scene}: plain {:?}, activity-aware {:?}", sums[0], sums[1]);
    Some(sums)
}

#[test]
fn across_the_busiest_area_the_seed_planner_meets_less_activity_for_a_little_more_length() {
    for scene in ["seq_eth", "seq_hotel"] {
        let Some([plain, aware]) = crossing_means(scene) else {
            return;
        };
        // Today: seq_eth 10.43 → 10.75 m, mean 119.6 → 104.0, max 289.8 → 286.1;
        // seq_hotel 10.21 → 10.46 m, mean 96.7 → 83.6, max 232.8 → 226.8.
        assert!(
            aware[1] < 0.92 * plain[1],
            "{scene}: mean {aware:?} vs {plain:?}"
        );
        assert!(aware[2] < plain[2], "{scene}: max {aware:?} vs {plain:?}");
        assert!(
            aware[0] > plain[0] && aware[0] < 1.1 * plain[0],
            "{scene}: length {aware:?} vs {plain:?}"
        );
    }
}
