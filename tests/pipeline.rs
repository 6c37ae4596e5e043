//! End to end on small simulations: the daily loop of `haunts::pipeline` against the
//! simulator's ground truth (poses, occupancy, layouts, people).

use haunts::affordance::{LayoutLibrary, LayoutParams};
use haunts::occupancy::Pose2;
use haunts::occupancy::recording::{RecordedScan, Recording, ScanList};
use haunts::occupancy::{GridGeometry, OccupancyGrid};
use haunts::pipeline::score::{self, SimulatedScore};
use haunts::pipeline::{DayOutput, DayProcessor, PipelineError, PipelineParams, density_near};
use haunts::sim::{
    Day, LaserParams, OdometryParams, PatrolParams, ScheduleParams, SimParams, Simulator,
};
use haunts::similarity::{Localiser, LocaliserParams, agreement};

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

/// Day 0 of a simulation and its corrected poses, scan by scan through a [`Localiser`]
/// (with odometry, or by scan matching alone), and the number of keyframes and refusals.
fn localise_day(params: SimParams, with_odometry: bool) -> (Day, Vec<Pose2>, usize, usize) {
    let sim = Simulator::new(params).expect("valid simulation");
    let day = sim.day(0).expect("day simulates");
    let mut localiser =
        Localiser::new(sim.geometry(), LocaliserParams::default()).expect("valid localiser");
    let poses = day
        .scans
        .iter()
        .zip(&day.odometry)
        .map(|(scan, odom)| {
            let out = if with_odometry {
                localiser.update(scan, odom)
            } else {
                // Scan matching alone works in the first scan's frame: back to the world's.
                localiser.update_without_odometry(scan).map(|mut o| {
                    o.pose = day.poses[0] * o.pose;
                    o
                })
            };
            out.expect("localises").pose
        })
        .collect();
    (day, poses, localiser.keyframes(), localiser.refused())
}

#[test]
fn scan_matching_removes_most_of_the_odometry_drift() {
    // Five times the default odometry noise.
    let odometry = {
        let mut p = OdometryParams::default();
        p.translation_noise = 0.05;
        p.rotation_noise = 0.05;
        p.rotation_per_metre = 0.02;
        p.heading_bias = 0.0005;
        p
    };
    let params = SimParams::default()
        .with_seed(11)
        .with_odometry(odometry)
        .with_patrol(PatrolParams::default().with_duration(240.0));
    let (day, poses, keyframes, refused) = localise_day(params, true);
    assert_eq!(poses.len(), day.scans.len());
    let (before, after) = (rms(&day.odometry, &day.poses), rms(&poses, &day.poses));
    assert!(before > 0.2, "the test needs real drift: {before}");
    assert!(
        after < 0.06,
        "corrected RMS {after} m (odometry {before} m)"
    );
    assert!(refused * 10 < keyframes);
}

#[test]
fn scan_matching_keeps_exact_odometry_exact() {
    let params = SimParams::default()
        .with_seed(5)
        .with_odometry(OdometryParams::exact())
        .with_patrol(PatrolParams::default().with_duration(120.0));
    let (day, poses, _, _) = localise_day(params, true);
    // Matching against a 5 cm map costs a few centimetres (cell centres, not surfaces).
    let after = rms(&poses, &day.poses);
    assert!(after < 0.05, "ICP moved exact poses by {after} m RMS");
}

#[test]
fn scan_matching_alone_follows_a_patrol_without_odometry() {
    let params = SimParams::default()
        .with_seed(5)
        .with_patrol(PatrolParams::default().with_duration(120.0));
    let (day, poses, keyframes, _) = localise_day(params, false);
    let after = rms(&poses, &day.poses);
    // A constant-velocity guess and every scan matched: no odometry to drift, only the
    // map's own small errors accumulate.
    assert!(after < 0.15, "scan matching alone: {after} m RMS");
    assert!(keyframes > 10);
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

fn run(sim: &Simulator, days: usize) -> Vec<(Day, DayOutput, SimulatedScore)> {
    run_with(sim, days, PipelineParams::default())
}

fn run_with(
    sim: &Simulator,
    days: usize,
    params: PipelineParams,
) -> Vec<(Day, DayOutput, SimulatedScore)> {
    let processor = DayProcessor::new(sim.geometry(), params).expect("valid processor");
    (0..days)
        .map(|d| {
            let day = sim.day(d).expect("day simulates");
            let output = processor
                .process(&day.to_recording().expect("a recording"))
                .expect("day processes");
            let scored = score::simulated(&output, &day, processor.params()).expect("scores");
            (day, output, scored)
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
    for (day, r, scored) in &days {
        assert!(r.skipped.is_empty(), "{:?}", r.skipped.first());
        assert_eq!(r.poses.len(), day.scans.len());
        // The map is the true office: walls and furniture, people and noise aside.
        let p = precision(&r.map, &day.truth, 0.15);
        assert!(p > 0.85, "day {}: map precision {p}", day.index);
        assert!(
            scored.pose_errors.corrected_rms < 0.06,
            "{:?}",
            scored.pose_errors
        );
        // Tracks follow people: matches within the threshold, at a small distance.
        let mot = &scored.mot;
        assert!(mot.ground_truth > 100 && mot.matches > 0);
        assert!(mot.motp < 0.2, "MOTP {}", mot.motp);
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
    let (errors, visible) = days.iter().fold((0, 0), |(e, v), (_, _, s)| {
        let m = &s.mot;
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
        let first = &days[layout.days()[0].id.0 as usize].0;
        let own_tables = score::tables_and_sofas(first);
        let others: Vec<_> = days
            .iter()
            .filter(|(d, _, _)| d.layout != first.layout)
            .flat_map(|(d, _, _)| score::tables_and_sofas(d))
            .collect();
        let density = layout.affordance().density_grid();
        let own = density_near(&density, &own_tables, &others);
        let other = density_near(&density, &others, &own_tables);
        assert!(
            own > 2.0 * other,
            "layout {}: {own} vs {other}",
            first.layout
        );
        served_layout_avoids_people(layout);
    }
}

/// Seed 000's costmap use: the layer only raises costs, never makes or removes an obstacle,
/// and a plan across the room that uses it meets fewer people than one that does not.
fn served_layout_avoids_people(layout: &haunts::affordance::layout::Layout) {
    use haunts::pipeline::serve::{ServeParams, compare_plans, serve_layout};
    use haunts::planning::{INSCRIBED_INFLATED_OBSTACLE, SearchParams};
    let served = serve_layout(layout, &ServeParams::default()).expect("layout serves");
    let (without, with) = (served.without_layer.data(), served.with_layer.data());
    let mut raised = 0;
    for (a, b) in without.iter().zip(with) {
        assert_eq!(
            *a >= INSCRIBED_INFLATED_OBSTACLE,
            *b >= INSCRIBED_INFLATED_OBSTACLE,
            "obstacles changed: {a} → {b}"
        );
        assert!(b >= a);
        raised += usize::from(b > a);
    }
    assert!(raised > 100, "{raised} cells raised");
    let (from, to) = (
        nalgebra::Point2::new(1.0, 4.8),
        nalgebra::Point2::new(14.2, 5.0),
    );
    let plans = compare_plans(&served, from, to, SearchParams::default()).expect("plans");
    let (a, b) = (plans.without_layer, plans.with_layer);
    eprintln!("without layer {a:?}; with {b:?}");
    assert!(b.activity_mean <= a.activity_mean, "{a:?} vs {b:?}");
    assert!(b.length >= a.length - 1e-9);
}

#[test]
fn a_day_is_the_same_with_one_or_two_threads() {
    let sim = simulator(4, vec![1]);
    let day = sim.day(0).expect("day simulates");
    let recording = day.to_recording().expect("a recording");
    let processor =
        DayProcessor::new(sim.geometry(), PipelineParams::default()).expect("valid processor");
    let run_with = |threads| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("thread pool")
            .install(|| processor.process(&recording))
            .expect("day processes")
    };
    let (one, two) = (run_with(1), run_with(2));
    assert_eq!(one.map, two.map);
    assert_eq!(one.density, two.density);
    assert_eq!(one.reports, two.reports);
    assert_eq!(one.tracked, two.tracked);
}

/// Day 0's recording with its scans edited by `edit` (odometry and transforms kept).
fn edited(day: &Day, edit: impl FnOnce(&mut Vec<RecordedScan>)) -> Recording {
    let recording = day.to_recording().expect("a recording");
    let mut scans: Vec<RecordedScan> = recording
        .scans()
        .expect("scans")
        .map(|s| s.expect("a scan"))
        .collect();
    edit(&mut scans);
    let odometry = recording.odometry().expect("odometry").clone();
    Recording::new(ScanList(scans))
        .with_transforms(recording.transforms().clone())
        .with_odometry(odometry, "odom", "base_link")
}

#[test]
fn unusable_scans_are_skipped_and_counted_and_the_rest_of_the_day_kept() {
    let sim = simulator(2, vec![0]);
    let day = sim.day(0).expect("day simulates");
    let processor =
        DayProcessor::new(sim.geometry(), PipelineParams::default()).expect("valid processor");
    let whole = processor
        .process(&day.to_recording().expect("a recording"))
        .expect("day processes");
    let recording = edited(&day, |scans| {
        // A stamp going backwards, one that is not a number, one before the odometry, one in
        // a frame the tree does not know.
        scans[10].scan.stamp = scans[9].scan.stamp - 1.0;
        scans[20].scan.stamp = f64::NAN;
        scans[0].scan.stamp -= 100.0;
        scans[30].frame = "elsewhere".into();
    });
    let out = processor.process(&recording).expect("day processes");
    let skipped: Vec<usize> = out.skipped.iter().map(|s| s.index).collect();
    assert_eq!(skipped, vec![0, 10, 20, 30], "{:?}", out.skipped);
    assert!(
        out.skipped[3].reason.contains("elsewhere"),
        "{}",
        out.skipped[3].reason
    );
    assert_eq!(out.counts.scans, day.scans.len());
    assert_eq!(out.poses.len() + out.skipped.len(), day.scans.len());
    // The rest of the day is as good as the whole day's.
    let (a, b) = (
        score::simulated(&out, &day, processor.params()).expect("scores"),
        score::simulated(&whole, &day, processor.params()).expect("scores"),
    );
    assert!(a.pose_errors.corrected_rms < 0.06, "{:?}", a.pose_errors);
    assert!(
        (a.mot.mota - b.mot.mota).abs() < 0.05,
        "{} vs {}",
        a.mot.mota,
        b.mot.mota
    );
}

#[test]
fn malformed_days_and_parameters_are_typed_errors() {
    let sim = simulator(2, vec![0]);
    let day = sim.day(0).expect("day simulates");
    let processor =
        DayProcessor::new(sim.geometry(), PipelineParams::default()).expect("valid processor");
    let output = processor
        .process(&day.to_recording().expect("a recording"))
        .expect("day processes");
    // Scoring against another day's truth of another length.
    let mut shorter = day.clone();
    shorter.people.pop();
    match score::simulated(&output, &shorter, processor.params()) {
        Err(PipelineError::DayLengths { what, len, .. }) => {
            assert_eq!((what, len + 1), ("people", day.scans.len()));
        }
        other => panic!("expected DayLengths, got {other:?}"),
    }
    // A recording with no usable scan.
    let empty = edited(&day, |scans| {
        scans.iter_mut().for_each(|s| s.scan.stamp = f64::NAN)
    });
    assert!(matches!(
        processor.process(&empty),
        Err(PipelineError::EmptyDay { .. })
    ));
    let params = {
        let mut p = PipelineParams::default();
        p.density_every = 0;
        p
    };
    assert!(matches!(
        DayProcessor::new(sim.geometry(), params),
        Err(PipelineError::InvalidParameter(
            haunts_core::InvalidParameter {
                name: "density_every",
                ..
            }
        ))
    ));
    let mut params = PipelineParams::default();
    params.localiser.keyframe_distance = f64::NAN;
    assert!(matches!(
        DayProcessor::new(sim.geometry(), params),
        Err(PipelineError::Similarity(
            haunts::similarity::SimilarityError::InvalidParameter(haunts_core::InvalidParameter {
                name: "localiser.keyframe_distance",
                ..
            })
        ))
    ));
}

#[test]
fn a_recording_without_transforms_takes_the_laser_at_the_robot() {
    // The simulated laser sits at the robot's origin: without a TF tree (the mount taken as
    // the identity, as `Recording::mount_at` documents) the day is the same.
    let sim = simulator(3, vec![0]);
    let day = sim.day(0).expect("day simulates");
    let with_tf = day.to_recording().expect("a recording");
    let scans: Vec<RecordedScan> = with_tf
        .scans()
        .expect("scans")
        .map(|s| s.expect("a scan"))
        .collect();
    let without_tf = Recording::new(ScanList(scans)).with_odometry(
        with_tf.odometry().expect("odometry").clone(),
        "odom",
        "base_link",
    );
    assert!(without_tf.transforms().is_empty());
    let processor =
        DayProcessor::new(sim.geometry(), PipelineParams::default()).expect("valid processor");
    let (a, b) = (
        processor.process(&with_tf).expect("day processes"),
        processor.process(&without_tf).expect("day processes"),
    );
    assert!(b.skipped.is_empty());
    assert_eq!(a.map, b.map);
    assert_eq!(a.reports, b.reports);
    assert_eq!(a.density, b.density);
}

#[test]
fn a_forty_hertz_laser_is_localised_and_tracked_as_well_as_a_ten_hertz_one() {
    // The same two one-minute patrols with the laser at 10 Hz and at 40 Hz (a day of a 40 Hz
    // laser is four times the scans; keyframes are spaced by motion, not by scans).
    let day_at = |rate: f64, pipeline: PipelineParams| {
        let params = SimParams::default()
            .with_seed(31)
            .with_schedule(ScheduleParams::Fixed(vec![0]))
            .with_patrol(PatrolParams::sessions(10.0 * 3600.0, 60.0, 7200.0, 2))
            .with_laser({
                let mut p = LaserParams::default();
                p.rate = rate;
                p
            });
        let sim = Simulator::new(params).expect("valid simulation");
        run_with(&sim, 1, pipeline).remove(0)
    };
    let (slow_day, slow, slow_score) = day_at(10.0, PipelineParams::default());
    let (fast_day, fast, fast_score) = day_at(40.0, PipelineParams::default().at_scan_rate(40.0));
    // Counted in scans, the 10 Hz confirmation confirms clutter four times as fast.
    let (_, _, unscaled) = day_at(40.0, PipelineParams::default());
    assert!(
        unscaled.mot.false_positives > 5 * fast_score.mot.false_positives,
        "{unscaled:?}"
    );
    assert!(
        fast.notes.iter().any(|n| n.contains("40.0 Hz")),
        "{:?}",
        fast.notes
    );
    let ratio = fast_day.scans.len() as f64 / slow_day.scans.len() as f64;
    assert!((ratio - 4.0).abs() < 0.05, "scans 40 Hz / 10 Hz: {ratio}");
    assert!(fast.skipped.is_empty(), "{:?}", fast.skipped.first());
    assert_eq!(fast.poses.len(), fast_day.scans.len());
    let keyframes = fast.counts.keyframes as f64 / slow.counts.keyframes as f64;
    assert!(
        (0.8..1.25).contains(&keyframes),
        "keyframes {} at 40 Hz, {} at 10 Hz",
        fast.counts.keyframes,
        slow.counts.keyframes
    );
    assert!(
        fast_score.pose_errors.corrected_rms < 0.1,
        "{:?}",
        fast_score.pose_errors
    );
    assert!(
        fast_score.mot.mota > 0.8 && fast_score.mot.mota > slow_score.mot.mota - 0.05,
        "40 Hz: {:?}\n10 Hz: {:?}",
        fast_score.mot,
        slow_score.mot
    );
}
