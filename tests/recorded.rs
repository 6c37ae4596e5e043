//! One recording, three files: the `leg_tracker` text export, the ROS 1 bag it was made from
//! and the bag's ROS 2 MCAP twin give the same tracking scores, and the text export as a
//! `Recording` holds the same scans and sensor poses as the bags. The MCAP through the daily
//! loop (`haunts::pipeline`): map, density, tracks scored as `evaluate_sequence` scores them,
//! a TA map of the day's tracks and plans across its busiest area.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use haunts_test_support::bag;
use haunts_test_support::data;

use haunts::bag::msg::Person;
use haunts::bag::{Bag, RecordingOptions};
use haunts::occupancy::Pose2;
use haunts::tracking::PersonPosition;
use haunts::tracking::detect::static_map::StaticMapParams;
use haunts::tracking::detect::{LegDetector, LegDetectorParams};
use haunts::tracking::eval::sequence::{EvalParams, EvalReport, Sequence, evaluate_sequence};
use haunts::tracking::track::Tracker;
use haunts::tracking::track::kalman::{KalmanParams, KalmanTracker};
use haunts::tracking::track::particle::{ParticleParams, ParticleTracker};
use nalgebra::{UnitComplex, Vector2};

/// The annotated people of a benchmark bag (`leg_tracker/msg/Person`).
fn ground_truth(bag: &Bag) -> Vec<PersonPosition> {
    haunts::live::replay::ground_truth(bag, "/ground_truth_people_tracks").unwrap()
}

/// The sequence of a bag, its ground truth from the `leg_tracker/msg/Person` topic.
fn from_bag(path: &std::path::Path) -> Sequence {
    let bag = Bag::open(path).unwrap();
    let recording = bag.recording(&RecordingOptions::new()).unwrap();
    Sequence::from_recording(&recording, ground_truth(&bag)).unwrap()
}

fn score(sequence: &Sequence, particle: bool) -> EvalReport {
    let detector = LegDetector::new(LegDetectorParams::default()).unwrap();
    let mut tracker: Box<dyn Tracker> = if particle {
        Box::new(ParticleTracker::new(ParticleParams::default()).unwrap())
    } else {
        Box::new(KalmanTracker::new(KalmanParams::default()).unwrap())
    };
    let params =
        EvalParams::leg_tracker_benchmarks().with_static_map(Some(StaticMapParams::default()));
    evaluate_sequence(sequence, &detector, tracker.as_mut(), &params).unwrap()
}

/// `v` as the text export wrote it: `%.{digits}f`.
fn round(v: f64, digits: i32) -> f64 {
    format!("{v:.*}", digits as usize).parse().unwrap_or(v)
}

/// The sequence with every value rounded as the text export rounds it (times, poses and yaws
/// to 6 decimals, angles to 9, ranges and limits to 3).
fn rounded_like_the_text(mut s: Sequence) -> Sequence {
    let pose = |p: &Pose2| {
        Pose2::from_parts(
            Vector2::new(round(p.translation.x, 6), round(p.translation.y, 6)).into(),
            UnitComplex::new(round(p.rotation.angle(), 6)),
        )
    };
    for scan in &mut s.scans {
        scan.bag_time = round(scan.bag_time, 6);
        let sc = &mut scan.scan;
        sc.stamp = round(sc.stamp, 6);
        sc.angle_min = round(sc.angle_min, 9);
        sc.angle_increment = round(sc.angle_increment, 9);
        sc.range_min = round(sc.range_min, 3);
        sc.range_max = round(sc.range_max, 3);
        for r in &mut sc.ranges {
            *r = round(*r, 3);
        }
    }
    for o in &mut s.odometry {
        o.stamp = round(o.stamp, 6);
        o.pose = pose(&o.pose);
    }
    for t in &mut s.static_transforms {
        t.transform = pose(&t.transform);
    }
    s
}

#[test]
fn text_bag_and_mcap_give_the_same_scores() {
    let (Some(text), Some(ros1), Some(mcap)) = (
        data::shared_data("leg_tracker/general_tracking_moving_1"),
        bag::moving_bag(),
        bag::moving_mcap(),
    ) else {
        return;
    };
    let text = Sequence::read(text).unwrap();
    let (ros1, mcap) = (from_bag(&ros1), from_bag(&mcap));
    assert_eq!(ros1.scans.len(), 873);
    assert_eq!(ros1.ground_truth.len(), 153);
    // The bag carries every link of the robot on /tf; the text export kept the left laser's.
    let left = |s: &Sequence| {
        s.static_transforms
            .iter()
            .find(|t| t.child == "left_laser")
            .map(|t| t.transform)
            .unwrap()
    };
    assert!((left(&ros1).translation.vector - left(&text).translation.vector).norm() < 1e-6);

    // The Kalman tracker: the same counts from all three.
    let k: Vec<_> = [&text, &ros1, &mcap]
        .iter()
        .map(|s| score(s, false).scores)
        .collect();
    // The same counts; MOTP (a mean distance) within the text's rounding of poses.
    let counts = |c: &haunts::tracking::eval::mot::ClearMot| {
        (
            c.id_switches,
            c.false_positives,
            c.misses,
            c.matches,
            c.ground_truth,
            c.frames,
        )
    };
    assert_eq!(counts(&k[0]), counts(&k[1]));
    assert_eq!(k[1], k[2]);
    assert!((k[0].motp - k[1].motp).abs() < 1e-4);
    assert!(k[0].mota > 0.5, "{:?}", k[0]);

    // The particle filter: the two bags agree exactly; the text export rounds stamps and poses
    // to 1e-6 (and the filter's resampling amplifies that), and the bag rounded the same way
    // scores as the text does.
    let p_ros1 = score(&ros1, true).scores;
    let p_mcap = score(&mcap, true).scores;
    assert_eq!(p_ros1, p_mcap);
    let p_text = score(&text, true).scores;
    let p_rounded = score(&rounded_like_the_text(ros1), true).scores;
    assert_eq!(counts(&p_text), counts(&p_rounded));
    assert!((p_text.motp - p_rounded.motp).abs() < 1e-4);
}

#[test]
fn the_text_export_as_a_recording_matches_the_bag() {
    let (Some(text), Some(mcap)) = (
        data::shared_data("leg_tracker/general_tracking_moving_1"),
        bag::moving_mcap(),
    ) else {
        return;
    };
    let from_text = Sequence::read(text)
        .unwrap()
        .to_recording("odom", "base_link")
        .unwrap();
    let from_bag = Bag::open(mcap)
        .unwrap()
        .recording(&RecordingOptions::new())
        .unwrap();
    let a: Vec<_> = from_text.scans().unwrap().map(Result::unwrap).collect();
    let b: Vec<_> = from_bag.scans().unwrap().map(Result::unwrap).collect();
    assert_eq!(a.len(), b.len());
    let mut compared = 0;
    for (x, y) in a.iter().zip(&b) {
        assert_eq!(x.frame, y.frame);
        assert!((x.scan.stamp - y.scan.stamp).abs() < 1e-6);
        assert_eq!(x.scan.ranges.len(), y.scan.ranges.len());
        let (Ok(p), Ok(q)) = (
            from_text.sensor_pose_at(&x.frame, x.scan.stamp),
            from_bag.sensor_pose_at(&y.frame, y.scan.stamp),
        ) else {
            continue;
        };
        assert!((p.translation.vector - q.translation.vector).norm() < 1e-5);
        assert!((p.rotation.angle() - q.rotation.angle()).abs() < 1e-5);
        compared += 1;
    }
    assert!(compared > 860, "{compared}");
}

/// The tracking crate's own evaluation of a bag (Kalman tracker, static map): every scan and
/// annotated scans.
fn reference_scores(
    path: &std::path::Path,
) -> (
    haunts::tracking::eval::mot::ClearMot,
    haunts::tracking::eval::mot::ClearMot,
) {
    use haunts::tracking::eval::sequence::EvalFrames;
    let sequence = from_bag(path);
    let run = |frames| {
        let detector = LegDetector::new(LegDetectorParams::default()).unwrap();
        let mut tracker = KalmanTracker::new(KalmanParams::default()).unwrap();
        let params = EvalParams::leg_tracker_benchmarks()
            .with_static_map(Some(StaticMapParams::default()))
            .with_frames(frames);
        evaluate_sequence(&sequence, &detector, &mut tracker, &params)
            .unwrap()
            .scores
    };
    (run(EvalFrames::EveryScan), run(EvalFrames::Annotated))
}

#[test]
fn the_daily_loop_in_the_odometry_frame_scores_as_evaluate_sequence() {
    use haunts::pipeline::{DayProcessor, PipelineError, PipelineParams, score};
    use haunts::similarity::LocaliserParams;
    let Some(mcap) = bag::moving_mcap() else {
        return;
    };
    // The daily loop set up as `evaluate_sequence` runs: no scan matching (tracking in the
    // odometry frame), the default Kalman tracker and the static map, no recurring objects.
    let params = {
        let mut p = PipelineParams::default();
        p.localiser = LocaliserParams::default().with_matching(false);
        p.tracker = KalmanParams::default();
        p.static_map = Some(StaticMapParams::default());
        p.recurring = None;
        p
    };
    let bag = Bag::open(&mcap).unwrap();
    let recording = bag.recording(&RecordingOptions::new()).unwrap();
    let geometry = DayProcessor::geometry_for(&recording, 0.1, 12.0).unwrap();
    let day = DayProcessor::new(geometry, params)
        .unwrap()
        .process(&recording)
        .unwrap();
    let ours = score::annotated(
        &day,
        &ground_truth(&bag),
        &EvalParams::leg_tracker_benchmarks(),
    )
    .unwrap();
    // Nothing to score is an error, never a perfect MOTA: no ground truth, or all of it
    // before the first scan (belonging to no scan).
    let protocol = EvalParams::leg_tracker_benchmarks();
    let none = score::annotated(&day, &[], &protocol);
    assert!(
        matches!(
            none,
            Err(PipelineError::NothingScored {
                annotations: 0,
                unassigned: 0,
                scans: 1..
            })
        ),
        "{none:?}"
    );
    let mut early = ground_truth(&bag);
    for p in &mut early {
        p.bag_time -= 1e6;
    }
    let before = score::annotated(&day, &early, &protocol);
    assert!(
        matches!(
            before,
            Err(PipelineError::NothingScored { annotations, unassigned, .. })
                if annotations == early.len() && unassigned == early.len() && annotations > 0
        ),
        "{before:?}"
    );
    // The reference: the tracking crate's own evaluation of the same bag.
    let (every, annotated) = reference_scores(&mcap);
    assert_eq!(ours.every_scan.misses, every.misses);
    assert_eq!(ours.every_scan.false_positives, every.false_positives);
    assert_eq!(ours.every_scan.id_switches, every.id_switches);
    assert_eq!(ours.every_scan.frames, every.frames);
    assert!((ours.every_scan.mota - every.mota).abs() < 1e-12);
    assert!((ours.annotated.mota - annotated.mota).abs() < 1e-12);
    assert!((ours.every_scan.motp - every.motp).abs() < 1e-9);
    // The figure of BENCHMARKS.md.
    assert!((every.mota - 0.256).abs() < 0.001, "{every:?}");
}

#[test]
fn a_real_bag_goes_through_the_daily_loop() {
    use haunts::pipeline::{DayOutput, DayProcessor, PipelineParams, score};
    let Some(mcap) = bag::moving_mcap() else {
        return;
    };
    let bag = Bag::open(&mcap).unwrap();
    let recording = bag.recording(&RecordingOptions::new()).unwrap();
    let truth = ground_truth(&bag);
    let geometry = DayProcessor::geometry_for(&recording, 0.1, 12.0).unwrap();
    let run = |params: PipelineParams| -> (DayOutput, score::AnnotatedScore) {
        let day = DayProcessor::new(geometry, params)
            .unwrap()
            .process(&recording)
            .unwrap();
        let scored = score::annotated(&day, &truth, &EvalParams::leg_tracker_benchmarks()).unwrap();
        (day, scored)
    };
    let (day, real) = run(PipelineParams::real_laser());
    let (_, simulated_defaults) = run(PipelineParams::default());
    let occupied = day.map.values().data().iter().filter(|v| **v >= 65).count();
    let refused = day.counts.refused_matches;
    eprintln!(
        "{} scans ({} skipped), {} keyframes ({refused} refused), {occupied} occupied cells, {} \
         trajectories, {} density cells known; real_laser: every scan {:?}, annotated {:?}; \
         defaults: every scan {:?}",
        day.counts.scans,
        day.skipped.len(),
        day.counts.keyframes,
        day.trajectories.len(),
        day.density.known_cells(),
        real.every_scan,
        real.annotated,
        simulated_defaults.every_scan,
    );
    assert_eq!(day.counts.scans, 873);
    assert_eq!(day.poses.len() + day.skipped.len(), 873);
    assert!(day.skipped.is_empty(), "{:?}", day.skipped);
    // Every annotation lies in a scored scan.
    assert_eq!(real.every_scan.ground_truth, real.annotated.ground_truth);
    assert!(real.every_scan.ground_truth > 100);
    assert!(occupied > 500, "{occupied}");
    assert!(day.density.known_cells() > 1000);
    // Most keyframes are matched (the rest enter unmapped ground faster than the map grows).
    assert!(
        refused * 2 < day.counts.keyframes,
        "{refused} of {}",
        day.counts.keyframes
    );
    // Tracked in the odometry frame and reported in the corrected one, the tracks are the
    // reference's, count for count, whatever scan matching did to the poses.
    let (every, annotated) = reference_scores(&mcap);
    let counts = |c: &haunts::tracking::eval::mot::ClearMot| {
        (
            c.misses,
            c.false_positives,
            c.id_switches,
            c.matches,
            c.frames,
        )
    };
    assert_eq!(counts(&real.every_scan), counts(&every));
    assert_eq!(counts(&real.annotated), counts(&annotated));
    // The simulated office's tracker settings confirm the real laser's clutter.
    assert!(
        simulated_defaults.every_scan.mota < -1.0,
        "{:?}",
        simulated_defaults.every_scan
    );
}

#[test]
fn the_real_days_tracks_make_a_ta_map_and_plans_across_its_busiest_area() {
    use haunts::affordance::ta::{TaMap, TaParams};
    use haunts::pipeline::{DayProcessor, PipelineParams};
    use haunts::planning::{
        AStar, ActivityAwareAStar, ActivityAwareParams, InflationLayer, InflationParams,
        LayeredCostmap, Planner, StaticLayer, crossings, max_activity_cell,
    };
    use haunts::tracking::track::dummy::{DummyFilterParams, filter_dummies};
    let Some(mcap) = bag::moving_mcap() else {
        return;
    };
    let recording = Bag::open(&mcap)
        .unwrap()
        .recording(&RecordingOptions::new())
        .unwrap();
    let geometry = DayProcessor::geometry_for(&recording, 0.1, 12.0).unwrap();
    let day = DayProcessor::new(geometry, PipelineParams::real_laser())
        .unwrap()
        .process(&recording)
        .unwrap();
    let kept = filter_dummies(day.trajectories.clone(), &DummyFilterParams::default())
        .unwrap()
        .kept;
    let ta = TaMap::fit(&kept, geometry, &TaParams::default()).unwrap();
    let activity = ta.raster();
    let costmap = LayeredCostmap::new(geometry)
        .with_layer(StaticLayer::new(&day.map, false))
        .with_layer(InflationLayer::new(InflationParams::default()).unwrap())
        .build()
        .unwrap();
    let busiest = max_activity_cell(activity, &costmap).unwrap();
    let trips = crossings(&costmap, busiest, 3.0, 8).unwrap();
    // θ as the main job takes it: the activity of the busiest quarter of the free cells (the
    // seed's 5.5 counts targets on far busier data; one 116 s day stays below it everywhere).
    let free = haunts::occupancy::Grid::from_fn(geometry, |c| match day.map.value(c) {
        Some(v) if (0..20).contains(&v) => activity.get(c).copied().unwrap_or(f64::NAN),
        _ => f64::NAN,
    });
    let theta = haunts::pipeline::serve::percentile(&free, 0.75).unwrap();
    let aware = ActivityAwareAStar::new(
        activity.clone(),
        ActivityAwareParams::default().with_threshold(theta),
    )
    .unwrap();
    let (mut plain_sum, mut aware_sum, mut planned) = ([0.0; 3], [0.0; 3], 0);
    for (start, goal) in &trips {
        let (Ok(p), Ok(a)) = (
            AStar::default().plan(&costmap, *start, *goal),
            aware.plan(&costmap, *start, *goal),
        ) else {
            continue;
        };
        planned += 1;
        for (sum, path) in [(&mut plain_sum, p), (&mut aware_sum, a)] {
            let m = path.metrics(activity).unwrap();
            for (s, v) in sum
                .iter_mut()
                .zip([m.length, m.activity_mean, m.activity_max])
            {
                *s += v;
            }
        }
    }
    eprintln!(
        "{} of {} trajectories kept; busiest cell {busiest:?}; θ {theta}; {planned} of {} trips \
         planned; plain {plain_sum:?}, activity-aware {aware_sum:?} (sums of length, mean, max)",
        kept.len(),
        day.trajectories.len(),
        trips.len()
    );
    // Measured: 27 of 73 kept, θ 1.32; over 8 trips plain 52.50 m, mean 27.34, max 37.52;
    // activity-aware 53.17 m, mean 26.98, max 37.14 (seed 002 Table 2's shape, smaller: one
    // short day).
    assert!(kept.len() > 10, "{} kept", kept.len());
    assert_eq!(planned, trips.len());
    assert!(
        aware_sum[1] < plain_sum[1],
        "{aware_sum:?} vs {plain_sum:?}"
    );
    assert!(
        aware_sum[2] <= plain_sum[2],
        "{aware_sum:?} vs {plain_sum:?}"
    );
    assert!(aware_sum[0] >= plain_sum[0] && aware_sum[0] < 1.1 * plain_sum[0]);
}

/// Issue 17's "no regression on another laser topic without odometry": the bag rewritten with
/// its scans on another topic and neither odometry nor TF (what a person-following robot's
/// log may hold; leg_tracker_benchmarks' person-following bags are not in `../shared`). The
/// topic is found on its own; `evaluate_sequence` tracks in the laser frame with the scores
/// of the same scans with the odometry taken away in memory, count for count; the daily
/// loop localises by scan matching alone and tracks in that frame.
#[test]
fn another_scan_topic_without_odometry_is_tracked_in_the_laser_frame() {
    use haunts::bag::McapWriter;
    use haunts::bag::convert::laser_scan_msg;
    use haunts::tracking::eval::sequence::{EvalFrames, TrackingFrame};

    let Some(mcap) = bag::moving_mcap() else {
        return;
    };
    let original = from_bag(&mcap);
    let path = std::env::temp_dir().join(format!("haunts-front-laser-{}.mcap", std::process::id()));
    let mut w = McapWriter::create(&path).unwrap();
    let annotate = |w: &mut McapWriter, p: &PersonPosition| {
        let mut person = Person::default();
        person.pose.position.x = p.position.x;
        person.pose.position.y = p.position.y;
        person.id = u32::try_from(p.id).unwrap();
        w.write("/ground_truth_people_tracks", p.bag_time, &person)
            .unwrap();
    };
    let mut truth = original.ground_truth.iter().peekable();
    for s in &original.scans {
        // The annotations logged before this scan, then the scan (the original's order).
        while let Some(p) = truth.next_if(|p| p.bag_time < s.bag_time) {
            annotate(&mut w, p);
        }
        w.write(
            "/front_laser/scan",
            s.bag_time,
            &laser_scan_msg(&s.scan, &s.frame),
        )
        .unwrap();
    }
    truth.for_each(|p| annotate(&mut w, p));
    w.finish().unwrap();
    let rewritten = from_bag(&path);
    // The daily loop on the same log: poses from scan matching alone (no odometry; a scan
    // the map refuses is matched against the scan before), tracks in that frame with the
    // static map.
    let daily = {
        use haunts::pipeline::{DayProcessor, PipelineParams, score};
        let bag = Bag::open(&path).unwrap();
        let recording = bag.recording(&RecordingOptions::new()).unwrap();
        let geometry = DayProcessor::geometry_for(&recording, 0.1, 12.0).unwrap();
        let day = DayProcessor::new(geometry, PipelineParams::real_laser())
            .unwrap()
            .process(&recording)
            .unwrap();
        score::annotated(
            &day,
            &ground_truth(&bag),
            &EvalParams::leg_tracker_benchmarks(),
        )
        .unwrap()
    };
    std::fs::remove_file(&path).ok();
    // Today every scan −0.158 (60 misses, 93 false positives), annotated scans 0.414; with
    // the odometry 0.256 / 0.541. Before the scan-before fallback: −3.06 / −0.38 (489 false
    // positives: refused scans kept a drifting constant-velocity guess). The level depends
    // on the sub-cell phase of the fallback's 5 cm target (−0.16 to −0.81 every scan over
    // four phases, BENCHMARKS.md): these bounds hold at today's phase, and a change of the
    // target's grid that breaks them must say what it does to the spread.
    eprintln!("daily loop without odometry: {daily:?}");
    assert!(daily.every_scan.false_positives < 150, "{daily:?}");
    assert!(
        daily.every_scan.mota > -0.4 && daily.annotated.mota > 0.3,
        "{daily:?}"
    );
    assert_eq!(rewritten.scans.len(), 873);
    assert!(rewritten.odometry.is_empty() && rewritten.static_transforms.is_empty());

    let blind = Sequence {
        odometry: Vec::new(),
        static_transforms: Vec::new(),
        ..original
    };
    let detector = LegDetector::new(LegDetectorParams::default()).unwrap();
    for frames in [EvalFrames::EveryScan, EvalFrames::Annotated] {
        let params = EvalParams::leg_tracker_benchmarks().with_frames(frames);
        let run = |s: &Sequence| {
            let mut kf = KalmanTracker::new(KalmanParams::default()).unwrap();
            evaluate_sequence(s, &detector, &mut kf, &params).unwrap()
        };
        let (a, b) = (run(&rewritten), run(&blind));
        assert_eq!(a.tracking_frame, TrackingFrame::Sensor);
        // Count for count; MOTP to the stamps' nanoseconds.
        let counts = |m: &haunts::tracking::eval::mot::ClearMot| {
            (
                m.misses,
                m.false_positives,
                m.id_switches,
                m.matches,
                m.frames,
            )
        };
        assert_eq!(counts(&a.scores), counts(&b.scores), "{frames:?}");
        assert!((a.scores.motp - b.scores.motp).abs() < 1e-6);
        // Today every scan: 48 misses, 497 false positives (MOTA −3.12); annotated scans:
        // 172 (−0.68). On a moving robot the laser frame moves the world: posts and walls
        // "walk" and are confirmed (BENCHMARKS.md).
        assert!(a.scores.matches >= 80, "{:?}", a.scores);
    }
}
