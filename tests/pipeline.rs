//! End to end on small simulations: the daily loop of `haunts::pipeline` against the
//! simulator's ground truth (poses, occupancy, layouts, people).

use haunts::affordance::{LayoutLibrary, LayoutParams};
use haunts::occupancy::{GridGeometry, OccupancyGrid};
use haunts::pipeline::{
    DayResult, Localised, LocaliserParams, PipelineError, PipelineParams, density_near, localise,
    process_day,
};
use haunts::sim::{Day, OdometryParams, PatrolParams, ScheduleParams, SimParams, Simulator};
use haunts::similarity::agreement;

/// Two-minute patrols (two sessions of a minute) on the given layouts.
fn simulator(seed: u64, layouts: Vec<usize>) -> Simulator {
    let params = SimParams::default()
        .with_seed(seed)
        .with_schedule(ScheduleParams::Fixed(layouts))
        .with_patrol(PatrolParams::sessions(10.0 * 3600.0, 60.0, 7200.0, 2));
    Simulator::new(params).expect("valid simulation")
}

/// The pipeline's 0.1 m grid over the simulated office.
fn geometry(sim: &Simulator) -> GridGeometry {
    sim.geometry().with_resolution(0.1).expect("valid geometry")
}

fn rms(a: &[haunts::occupancy::Pose2], b: &[haunts::occupancy::Pose2]) -> f64 {
    let sum: f64 = a
        .iter()
        .zip(b)
        .map(|(p, q)| (p.translation.vector - q.translation.vector).norm_squared())
        .sum();
    (sum / a.len() as f64).sqrt()
}

/// Day 0 of a simulation and its localisation with the default parameters.
fn localise_day(params: SimParams) -> (Day, Localised) {
    let sim = Simulator::new(params).expect("valid simulation");
    let day = sim.day(0).expect("day simulates");
    let localised = localise(
        &day.scans,
        &day.odometry,
        sim.geometry(),
        &LocaliserParams::default(),
    )
    .expect("localises");
    (day, localised)
}

#[test]
fn scan_matching_removes_most_of_the_odometry_drift() {
    // Five times the default odometry noise.
    let odometry = OdometryParams {
        translation_noise: 0.05,
        rotation_noise: 0.05,
        rotation_per_metre: 0.02,
        heading_bias: 0.0005,
    };
    let params = SimParams::default()
        .with_seed(11)
        .with_odometry(odometry)
        .with_patrol(PatrolParams::default().with_duration(240.0));
    let (day, localised) = localise_day(params);
    assert_eq!(localised.poses.len(), day.scans.len());
    let (before, after) = (
        rms(&day.odometry, &day.poses),
        rms(&localised.poses, &day.poses),
    );
    assert!(before > 0.2, "the test needs real drift: {before}");
    assert!(
        after < 0.06,
        "corrected RMS {after} m (odometry {before} m)"
    );
    assert!(localised.refused * 10 < localised.keyframes.len());
}

#[test]
fn scan_matching_keeps_exact_odometry_exact() {
    let params = SimParams::default()
        .with_seed(5)
        .with_odometry(OdometryParams::exact())
        .with_patrol(PatrolParams::default().with_duration(120.0));
    let (day, localised) = localise_day(params);
    // Matching against a 5 cm map costs a few centimetres (cell centres, not surfaces).
    let after = rms(&localised.poses, &day.poses);
    assert!(after < 0.05, "ICP moved exact poses by {after} m RMS");
}

/// Occupied cells of `map` lying within `tolerance` metres of an occupied cell of `truth`.
fn precision(map: &OccupancyGrid, truth: &OccupancyGrid, tolerance: f64) -> f64 {
    let g = map.geometry();
    let occupied: Vec<_> = map
        .values()
        .cells()
        .filter(|(_, v)| **v >= 65)
        .map(|(c, _)| g.cell_center(c))
        .collect();
    let t = truth.geometry();
    let near = occupied
        .iter()
        .filter(|p| {
            let r = (tolerance / t.resolution()).ceil() as i64;
            let Some(c) = t.world_to_cell(**p) else {
                return false;
            };
            (-r..=r).any(|dc| {
                (-r..=r).any(|dr| {
                    t.checked_cell(c.col as i64 + dc, c.row as i64 + dr)
                        .is_some_and(|n| truth.values()[n] >= 65)
                })
            })
        })
        .count();
    near as f64 / occupied.len().max(1) as f64
}

fn run(sim: &Simulator, days: usize) -> Vec<(Day, DayResult)> {
    let params = PipelineParams::default();
    (0..days)
        .map(|d| {
            let day = sim.day(d).expect("day simulates");
            let result = process_day(&day, geometry(sim), &params).expect("day processes");
            (day, result)
        })
        .collect()
}

#[test]
fn days_are_mapped_tracked_and_grouped_by_layout() {
    let truth = vec![0, 0, 2, 2, 0, 2];
    let sim = simulator(21, truth.clone());
    let days = run(&sim, truth.len());
    let mut library =
        LayoutLibrary::new(geometry(&sim), LayoutParams::default()).expect("valid library");
    let mut labels = Vec::new();
    for (day, r) in &days {
        assert_eq!(r.layout, day.layout);
        // The map is the true office: walls and furniture, people and noise aside.
        let p = precision(&r.map, &day.truth, 0.15);
        assert!(p > 0.85, "day {}: map precision {p}", day.index);
        assert!(r.pose_errors.corrected_rms < 0.06, "{:?}", r.pose_errors);
        // Tracks follow people: matches within the threshold, at a small distance.
        assert!(r.mot.ground_truth > 100 && r.mot.matches > 0);
        assert!(r.mot.motp < 0.2, "MOTP {}", r.mot.motp);
        // People were seen where the laser looked: most cells with hits were visited (the
        // rest lie behind the legs that stopped the beams).
        let hit: Vec<_> = r
            .density
            .hits()
            .data()
            .iter()
            .zip(r.density.visits().data())
            .filter(|(h, _)| **h > 0)
            .collect();
        let visited = hit.iter().filter(|(_, v)| **v > 0).count();
        assert!(
            !hit.is_empty() && visited * 2 > hit.len(),
            "{visited} of {}",
            hit.len()
        );
        labels.push(
            library
                .ingest(format!("day {}", day.index), &r.map, &r.density)
                .expect("day ingests")
                .layout
                .0,
        );
    }
    // Tracking on the simulated laser (issue target MOTA ≥ 0.85 on the 70-day run).
    let (errors, visible) = days.iter().fold((0, 0), |(e, v), (_, r)| {
        let m = &r.mot;
        (
            e + m.misses + m.false_positives + m.id_switches,
            v + m.ground_truth,
        )
    });
    let mota = 1.0 - errors as f64 / visible as f64;
    eprintln!("MOTA over {} days: {mota} ({visible} visible)", days.len());
    assert!(mota >= 0.8, "MOTA {mota}");
    let score = agreement(&labels, &truth).expect("labels agree in length");
    assert!(score.rand_index >= 0.95, "{labels:?} vs {truth:?}");
    // Each layout's affordance map is denser at its own tables and sofas than at the other
    // layout's (cells near both excluded).
    for layout in library.layouts() {
        let first = &days[layout.days()[0].id.0 as usize].1;
        let others: Vec<_> = days
            .iter()
            .filter(|(d, _)| d.layout != first.layout)
            .flat_map(|(_, r)| r.tables_and_sofas.iter().copied())
            .collect();
        let density = layout.affordance().density_grid();
        let own = density_near(&density, &first.tables_and_sofas, &others);
        let other = density_near(&density, &others, &first.tables_and_sofas);
        assert!(
            own > 2.0 * other,
            "layout {}: {own} vs {other}",
            first.layout
        );
    }
}

#[test]
fn a_day_is_the_same_with_one_or_two_threads() {
    let sim = simulator(4, vec![1]);
    let day = sim.day(0).expect("day simulates");
    let run_with = |threads| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("thread pool")
            .install(|| process_day(&day, geometry(&sim), &PipelineParams::default()))
            .expect("day processes")
    };
    let (one, two) = (run_with(1), run_with(2));
    assert_eq!(one.map, two.map);
    assert_eq!(one.density, two.density);
    assert_eq!(one.mot, two.mot);
    assert_eq!(one.tracked, two.tracked);
}

#[test]
fn malformed_days_and_parameters_are_typed_errors() {
    let sim = simulator(2, vec![0]);
    let mut day = sim.day(0).expect("day simulates");
    day.odometry.pop();
    match process_day(&day, geometry(&sim), &PipelineParams::default()) {
        Err(PipelineError::DayLengths {
            what, len, scans, ..
        }) => {
            assert_eq!((what, len + 1), ("odometry", scans));
        }
        other => panic!("expected DayLengths, got {other:?}"),
    }
    let day = sim.day(0).expect("day simulates");
    let params = PipelineParams {
        density_every: 0,
        ..PipelineParams::default()
    };
    assert!(matches!(
        process_day(&day, geometry(&sim), &params),
        Err(PipelineError::InvalidParameter {
            name: "density_every",
            ..
        })
    ));
    let mut params = PipelineParams::default();
    params.localiser.keyframe_distance = f64::NAN;
    assert!(matches!(
        process_day(&day, geometry(&sim), &params),
        Err(PipelineError::InvalidParameter {
            name: "localiser.keyframe_distance",
            ..
        })
    ));
}
