//! No parameter value makes the simulator panic: arbitrary values (NaN, infinities, zero,
//! negative, huge) are either refused with a typed error or simulated.

use haunts_sim::{PatrolParams, SimError, SimParams, Simulator};
use proptest::prelude::*;

/// Ordinary values mixed with the special ones.
fn num() -> impl Strategy<Value = f64> {
    prop_oneof![
        4 => -1.0f64..3.0,
        2 => 0.0f64..100.0,
        1 => Just(0.0),
        1 => Just(f64::NAN),
        1 => Just(f64::INFINITY),
        1 => Just(f64::NEG_INFINITY),
        1 => Just(1e300),
        1 => Just(-1e-300),
    ]
}

/// Sets parameter `k` (of [`FIELDS`]) of `p` to `v`.
fn set(p: &mut SimParams, k: usize, v: f64) {
    match k {
        0 => p.laser.fov = v,
        1 => p.laser.angular_resolution = v,
        2 => p.laser.range_min = v,
        3 => p.laser.range_max = v,
        4 => p.laser.noise_sd = v,
        5 => p.laser.dropout = v,
        6 => p.laser.rate = v,
        7 => p.patrol.start = v * 40_000.0,
        8 => p.patrol.duration = v * 10.0,
        9 => p.patrol.speed = v,
        10 => p.patrol.turn_rate = v,
        11 => p.people.visits_per_day = v * 100.0,
        12 => p.people.open = v * 30_000.0,
        13 => p.people.close = v * 60_000.0,
        14 => p.people.speed = v,
        15 => p.people.leg_radius = v,
        16 => p.people.group_probability = v,
        17 => p.odometry.translation_noise = v,
        18 => p.odometry.rotation_noise = v,
        19 => p.odometry.heading_bias = v,
        20 => p.furniture.chair_sd = v,
        21 => p.grid_resolution = v,
        22 => p.start_time = v * 1e9,
        23 => p.patrol.sessions = (v * 3.0) as usize,
        24 => p.patrol.interval = v * 100.0,
        _ => p.laser.spurious_max_range = v,
    }
}

const FIELDS: usize = 26;

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]
    #[test]
    fn any_parameters_error_or_simulate(
        changes in proptest::collection::vec((0..FIELDS, num()), 1..4),
    ) {
        let mut params = SimParams::default()
            .with_patrol(PatrolParams::default().with_duration(20.0));
        for (k, v) in changes {
            set(&mut params, k, v);
        }
        match Simulator::new(params.clone()) {
            Err(e) => prop_assert!(matches!(
                e,
                SimError::InvalidParameter(haunts_core::InvalidParameter { .. }) | SimError::TooLarge { .. }
            ), "{e}"),
            Ok(sim) => {
                let scans = params.patrol.scans_per_day(params.laser.rate) as usize;
                let small = scans <= 3000
                    && params.laser.beams() <= 3000
                    && sim.geometry().len() <= 2_000_000;
                if small {
                    let day = sim.day(1).unwrap();
                    prop_assert_eq!(day.scans.len(), scans);
                    prop_assert_eq!(day.odometry.len(), scans);
                    prop_assert!(day.scans.iter().all(|s| s.len() == params.laser.beams()));
                }
            }
        }
    }
}
