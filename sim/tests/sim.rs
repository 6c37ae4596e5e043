//! End-to-end properties of simulated days: determinism, ground truth consistency, people,
//! odometry drift and the layout schedule.

use approx::assert_relative_eq;
use haunts_occupancy::{Reading, StateThresholds};
use haunts_sim::{
    Activity, FurnitureKind, FurnitureNoise, LaserParams, MaxRangeReturn, OdometryParams,
    PatrolParams, ScheduleParams, SimError, SimParams, Simulator,
};
use nalgebra::Point2;

/// A short patrol (60 s, 600 scans) that keeps debug-build tests quick.
fn short(seed: u64) -> SimParams {
    SimParams::default()
        .with_seed(seed)
        .with_patrol(PatrolParams::default().with_duration(60.0))
}

#[test]
fn same_seed_gives_identical_days() {
    let sim = Simulator::new(short(11)).unwrap();
    let a = sim.days(0..3).unwrap();
    let b = sim.days(0..3).unwrap();
    assert!(a.iter().zip(&b).all(|(x, y)| x.bit_eq(y)));
    // A day alone equals the same day within a range.
    assert!(sim.day(2).unwrap().bit_eq(&a[2]));
    assert!(!a[1].bit_eq(&a[2]));
    // Dropouts are there (NaN), which is why plain `==` is not the test.
    assert!(
        a[0].scans
            .iter()
            .any(|s| s.ranges.iter().any(|r| r.is_nan()))
    );
}

#[test]
fn a_day_as_a_recording_has_its_scans_and_odometry_and_no_truth() {
    let day = Simulator::new(short(5)).unwrap().day(0).unwrap();
    let recording = day.to_recording().unwrap();
    let scans: Vec<_> = recording.scans().unwrap().map(Result::unwrap).collect();
    assert_eq!(scans.len(), day.scans.len());
    for ((r, scan), odom) in scans.iter().zip(&day.scans).zip(&day.odometry) {
        assert_eq!(r.scan.stamp, scan.stamp);
        assert_eq!(r.frame, "laser");
        let pose = recording.sensor_pose_at(&r.frame, r.scan.stamp).unwrap();
        // At each scan the sensor is where the (drifting) odometry says, not the true pose.
        assert_relative_eq!(
            pose.translation.vector,
            odom.translation.vector,
            epsilon = 1e-12
        );
    }
    assert_eq!(
        (recording.odom_frame(), recording.base_frame()),
        ("odom", "base_link")
    );
    assert!(recording.map().is_none());
}

#[test]
fn one_and_two_threads_give_identical_days() {
    let sim = Simulator::new(short(5)).unwrap();
    let run = |threads| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| sim.days(0..3).unwrap())
    };
    let (one, two) = (run(1), run(2));
    assert_eq!(one.len(), 3);
    for (a, b) in one.iter().zip(&two) {
        assert!(
            a.bit_eq(b),
            "day {} differs between 1 and 2 threads",
            a.index
        );
    }
}

#[test]
fn different_seeds_differ() {
    let a = Simulator::new(short(1)).unwrap().day(0).unwrap();
    let b = Simulator::new(short(2)).unwrap().day(0).unwrap();
    assert!(!a.bit_eq(&b));
    assert_ne!(a.scans[0].ranges, b.scans[0].ranges);
    assert_ne!(a.furniture, b.furniture);
    assert_ne!(
        a.visits.iter().map(|v| v.arrival()).collect::<Vec<_>>(),
        b.visits.iter().map(|v| v.arrival()).collect::<Vec<_>>()
    );
}

#[test]
fn layouts_differ_in_the_ground_truth_grid() {
    let sim = Simulator::new(short(0).with_furniture(FurnitureNoise::none())).unwrap();
    let n = sim.office().layouts.len();
    assert!(n >= 4);
    let grids: Vec<_> = (0..n)
        .map(|l| {
            let f = sim.furniture(0, l).unwrap();
            sim.truth_grid(&sim.static_shapes(&f)).unwrap()
        })
        .collect();
    for i in 0..n {
        for j in i + 1..n {
            let differing = grids[i]
                .values()
                .data()
                .iter()
                .zip(grids[j].values().data())
                .filter(|(a, b)| a != b)
                .count();
            assert!(
                differing > 20,
                "layouts {i} and {j} differ in {differing} cells"
            );
        }
    }
    // Walls are in every grid: the cell at the middle of the south wall's left part.
    let cell = sim
        .geometry()
        .world_to_cell(Point2::new(3.0, 0.05))
        .unwrap();
    assert!(grids.iter().all(|g| g.value(cell) == Some(100)));
    let free = sim.geometry().world_to_cell(Point2::new(1.5, 1.5)).unwrap();
    assert!(grids.iter().all(|g| g.value(free) == Some(0)));
}

#[test]
fn daily_displacement_moves_chairs_more_than_tables() {
    let sim = Simulator::new(short(3)).unwrap();
    let layout = &sim.office().layouts[0].furniture;
    let moved = sim.furniture(9, 0).unwrap();
    let (mut chairs, mut tables) = (Vec::new(), Vec::new());
    for (a, b) in layout.iter().zip(&moved) {
        let d = (a.center - b.center).norm();
        assert!(d <= 3.0 * 0.12 * 2f64.sqrt() + 1e-9, "clipped at 3 sigma");
        match a.kind {
            FurnitureKind::Chair => chairs.push(d),
            FurnitureKind::Table => tables.push(d),
            _ => {}
        }
    }
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    assert!(mean(&chairs) > 2.0 * mean(&tables));
}

#[test]
fn laser_ranges_match_the_true_geometry_within_noise() {
    let sigma = 0.01;
    let laser = {
        let mut p = LaserParams::default();
        p.noise_sd = sigma;
        p.dropout = 0.02;
        p.spurious_max_range = 0.0;
        p.max_range_return = MaxRangeReturn::RangeMax;
        p
    };
    let sim = Simulator::new(short(4).with_laser(laser)).unwrap();
    let day = sim.day(1).unwrap();
    let shapes = sim.static_shapes(&day.furniture);
    let (mut hits, mut nan, mut total, mut max_range) = (0usize, 0usize, 0usize, 0usize);
    let mut worst: f64 = 0.0;
    for (scan, pose) in day.scans.iter().zip(&day.poses).step_by(7) {
        let mut all = shapes.clone();
        all.extend(sim.legs_at(&day, scan.stamp));
        let exact = sim.exact_ranges(pose, &all);
        assert_eq!(exact.len(), scan.ranges.len());
        for (beam, e) in scan.beams().zip(&exact) {
            total += 1;
            match beam.reading {
                Reading::Hit(r) => {
                    hits += 1;
                    worst = worst.max((r - e).abs());
                }
                Reading::Invalid => {
                    assert!(scan.ranges[beam.index].is_nan());
                    nan += 1;
                }
                Reading::MaxRange => {
                    max_range += 1;
                    assert_eq!(scan.ranges[beam.index], laser.range_max);
                    assert!(*e >= laser.range_max - 6.0 * sigma);
                }
            }
        }
    }
    assert!(hits > total / 2, "{hits} hits of {total}");
    assert!(worst < 6.0 * sigma, "worst error {worst}");
    // Dropouts near the configured 2 %.
    let rate = nan as f64 / total as f64;
    assert!((0.01..0.03).contains(&rate), "dropout rate {rate}");
    // The room is closed except for doors: few max-range readings.
    assert!(max_range < total / 10);
}

#[test]
fn hits_fall_on_occupied_ground_truth_cells_or_people() {
    let sim = Simulator::new(short(8).with_laser(LaserParams::default().noiseless())).unwrap();
    let day = sim.day(0).unwrap();
    let occupied = day.truth.occupied_mask();
    let (mut on_map, mut on_people, mut total) = (0, 0, 0);
    for (k, scan) in day.scans.iter().enumerate().step_by(10) {
        for p in scan.endpoints_world(&day.poses[k]) {
            total += 1;
            // A 3 × 3 neighbourhood: an endpoint on a shape's boundary may sit in the
            // neighbouring cell.
            let near_map = (-1..=1).any(|dx| {
                (-1..=1).any(|dy| {
                    let q = Point2::new(p.x + dx as f64 * 0.05, p.y + dy as f64 * 0.05);
                    occupied.at_world(q).copied().unwrap_or(false)
                })
            });
            if near_map {
                on_map += 1;
            } else if day.people[k].iter().any(|h| (h.position - p).norm() < 0.35) {
                on_people += 1;
            }
        }
    }
    assert_eq!(
        on_map + on_people,
        total,
        "every hit is a wall, furniture or a leg"
    );
}

#[test]
fn people_are_seen_as_leg_returns() {
    let sim = Simulator::new(short(21)).unwrap();
    let day = sim.day(0).unwrap();
    let (mut near, mut seen) = (0, 0);
    for (k, scan) in day.scans.iter().enumerate().step_by(5) {
        let pose = day.poses[k];
        let points: Vec<_> = scan.endpoints_world(&pose).collect();
        for person in &day.people[k] {
            let local = pose.inverse() * person.position;
            let in_fov = local.y.atan2(local.x).abs() < 135f64.to_radians() - 0.05;
            if local.coords.norm() < 5.0 && in_fov {
                near += 1;
                if points.iter().any(|p| (p - person.position).norm() < 0.25) {
                    seen += 1;
                }
            }
        }
    }
    assert!(
        near > 50,
        "only {near} person-scans near the robot during lunch"
    );
    // Occlusion by other people and furniture hides some.
    assert!(seen as f64 > 0.7 * near as f64, "{seen} of {near} seen");
}

#[test]
fn beams_count_the_returns_from_each_persons_legs() {
    // Reference: every valid return of the noiseless laser whose endpoint lies on one of the
    // person's own leg circles (from the visit, not from the scan).
    let params = short(21).with_laser(LaserParams::default().noiseless());
    let sim = Simulator::new(params).unwrap();
    let day = sim.day(0).unwrap();
    let (mut checked, mut seen) = (0, 0);
    for (k, scan) in day.scans.iter().enumerate().step_by(7) {
        let points: Vec<_> = scan.endpoints_world(&day.poses[k]).collect();
        for person in &day.people[k] {
            let visit = day.visits.iter().find(|v| v.id == person.id).unwrap();
            let legs = visit.legs(scan.stamp, &sim.params().people).unwrap();
            let on_legs = points
                .iter()
                .filter(|p| {
                    legs.iter().any(|leg| match *leg {
                        haunts_sim::Shape::Circle { center, radius } => {
                            ((*p - center).norm() - radius).abs() < 1e-6
                        }
                        _ => false,
                    })
                })
                .count();
            assert_eq!(person.beams, on_legs, "scan {k}, person {}", person.id);
            checked += 1;
            seen += usize::from(on_legs > 0);
        }
    }
    assert!(checked > 100 && seen > 20, "{seen} of {checked}");
}

#[test]
fn nobody_stands_inside_another_person() {
    // Places are held by one person at a time: standing people stay a body's width apart.
    let sim =
        Simulator::new(short(6).with_patrol(PatrolParams::default().with_duration(0.0))).unwrap();
    for day in sim.days(0..4).unwrap() {
        let mut t = day.midnight + 8.0 * 3600.0;
        while t < day.midnight + 18.0 * 3600.0 {
            let standing: Vec<_> = day
                .visits
                .iter()
                .filter_map(|v| v.at(t))
                .filter(|p| p.velocity.norm() == 0.0)
                .collect();
            for (i, a) in standing.iter().enumerate() {
                for b in &standing[i + 1..] {
                    let d = (a.position - b.position).norm();
                    assert!(
                        d >= 0.45,
                        "day {}, t {t}: {} and {} {d} m apart",
                        day.index,
                        a.id,
                        b.id
                    );
                }
            }
            t += 30.0;
        }
    }
}

#[test]
fn people_follow_the_daily_rhythm_and_the_tables() {
    let sim =
        Simulator::new(short(6).with_patrol(PatrolParams::default().with_duration(0.0))).unwrap();
    let days = sim.days(0..8).unwrap();
    let hour = |h: f64| h * 3600.0;
    let (mut lunch, mut late) = (0, 0);
    for day in &days {
        assert!(day.scans.is_empty());
        for v in &day.visits {
            let t = v.arrival() - day.midnight;
            if (hour(12.25)..hour(13.25)).contains(&t) {
                lunch += 1;
            }
            if (hour(17.0)..hour(18.0)).contains(&t) {
                late += 1;
            }
            if v.activity == Activity::Table {
                // Table visitors stand at one of the day's tables or sofas.
                let d = day
                    .furniture
                    .iter()
                    .filter(|f| matches!(f.kind, FurnitureKind::Table | FurnitureKind::Sofa))
                    .map(|f| (f.center - v.place).norm() - f.size.norm() / 2.0)
                    .fold(f64::INFINITY, f64::min);
                assert!(d < 0.6, "table visitor {} is {d} m from any table", v.id);
            }
        }
    }
    assert!(lunch > 3 * late, "lunch {lunch} vs late afternoon {late}");
    // What people come for follows the time of day: coffee in the morning, tables at lunch.
    let share = |from: f64, to: f64, activity: Activity| {
        let visits: Vec<_> = days
            .iter()
            .flat_map(|d| d.visits.iter().map(move |v| (v.arrival() - d.midnight, v)))
            .filter(|(t, _)| (hour(from)..hour(to)).contains(t))
            .collect();
        let n = visits
            .iter()
            .filter(|(_, v)| v.activity == activity)
            .count();
        n as f64 / visits.len().max(1) as f64
    };
    let (morning, lunchtime) = (
        share(9.0, 10.0, Activity::Coffee),
        share(12.5, 13.0, Activity::Coffee),
    );
    assert!(
        morning > 2.0 * lunchtime,
        "coffee share {morning} at 9 vs {lunchtime} at 12:30"
    );
    let (morning, lunchtime) = (
        share(9.0, 10.0, Activity::Table),
        share(12.5, 13.0, Activity::Table),
    );
    assert!(
        lunchtime > 2.0 * morning,
        "table share {lunchtime} at 12:30 vs {morning} at 9"
    );
    // Some table and desk visitors get a coffee on the way (about 30 %).
    let coffee = &sim.office().coffee;
    let (mut others, mut via_coffee) = (0, 0);
    for v in days.iter().flat_map(|d| &d.visits) {
        if v.activity != Activity::Coffee {
            others += 1;
            if v.path().any(|(_, p)| coffee.contains(&p)) {
                via_coffee += 1;
            }
        }
    }
    let share = via_coffee as f64 / others as f64;
    assert!(
        (0.2..0.4).contains(&share),
        "{share} stopped for coffee first"
    );
}

#[test]
fn odometry_drift_matches_the_configured_noise() {
    // Exact odometry: no drift at all.
    let exact = Simulator::new(short(1).with_odometry(OdometryParams::exact()))
        .unwrap()
        .day(0)
        .unwrap();
    for (o, p) in exact.odometry.iter().zip(&exact.poses) {
        assert_relative_eq!(o.translation.vector, p.translation.vector, epsilon = 1e-9);
    }
    // Bias only: the heading drifts by exactly bias · distance.
    let bias = {
        let mut p = OdometryParams::exact();
        p.heading_bias = 0.01;
        p
    };
    let laser = {
        let mut p = LaserParams::default();
        p.rate = 2.0;
        p
    };
    let biased = Simulator::new(short(1).with_odometry(bias).with_laser(laser))
        .unwrap()
        .day(0)
        .unwrap();
    let distance: f64 = biased
        .poses
        .windows(2)
        .map(|w| (w[1].translation.vector - w[0].translation.vector).norm())
        .sum();
    let heading_error = |d: &haunts_sim::Day| {
        let last = d.poses.len() - 1;
        (d.poses[last].inverse() * d.odometry[last])
            .rotation
            .angle()
    };
    assert_relative_eq!(heading_error(&biased), 0.01 * distance, epsilon = 1e-9);
    // Noise only: the variance of the final heading error over many days is the
    // configured one (for 150 samples the ratio's standard deviation is about 0.12).
    let noise = {
        let mut p = OdometryParams::default();
        p.heading_bias = 0.0;
        p
    };
    let sim = Simulator::new(short(2).with_odometry(noise).with_laser(laser)).unwrap();
    let days = sim.days(0..150).unwrap();
    let mut ratio_sum = 0.0;
    for d in &days {
        let turned: f64 = d
            .poses
            .windows(2)
            .map(|w| (w[0].inverse() * w[1]).rotation.angle().abs())
            .sum();
        let dist: f64 = d
            .poses
            .windows(2)
            .map(|w| (w[1].translation.vector - w[0].translation.vector).norm())
            .sum();
        ratio_sum += heading_error(d).powi(2) / noise.heading_variance(dist, turned);
    }
    let ratio = ratio_sum / days.len() as f64;
    assert!((0.65..1.4).contains(&ratio), "variance ratio {ratio}");
}

#[test]
fn seventy_days_see_at_least_four_layouts() {
    for seed in 0..20 {
        let sim = Simulator::new(short(seed)).unwrap();
        let layouts = sim.layouts(70).unwrap();
        let mut seen = layouts.clone();
        seen.sort_unstable();
        seen.dedup();
        assert!(seen.len() >= 4, "seed {seed}: {seen:?}");
        let changes = layouts.windows(2).filter(|w| w[0] != w[1]).count();
        assert!(changes >= 5, "seed {seed}: {changes} changes");
    }
    let fixed = Simulator::new(short(0).with_schedule(ScheduleParams::Fixed(vec![2, 3])))
        .unwrap()
        .day(5)
        .unwrap();
    assert_eq!(fixed.layout, 3);
}

#[test]
fn hourly_patrols_see_the_whole_day() {
    let patrol = PatrolParams::sessions(8.0 * 3600.0, 30.0, 3600.0, 10);
    let laser = {
        let mut p = LaserParams::default();
        p.rate = 5.0;
        p
    };
    let sim = Simulator::new(short(9).with_patrol(patrol).with_laser(laser)).unwrap();
    let day = sim.day(0).unwrap();
    assert_eq!(day.scans.len(), 10 * 150);
    let first = sim.office().waypoints[0];
    for k in 0..10 {
        let scan = &day.scans[k * 150];
        assert_relative_eq!(
            scan.stamp - day.midnight,
            (8.0 + k as f64) * 3600.0,
            epsilon = 1e-3
        );
        let p = day.poses[k * 150].translation.vector;
        assert_relative_eq!(p, first.coords, epsilon = 1e-9);
    }
    // People are around at several hours, not only in one window.
    let hours_with_people = (0..10)
        .filter(|k| {
            day.people[k * 150..(k + 1) * 150]
                .iter()
                .any(|p| !p.is_empty())
        })
        .count();
    assert!(hours_with_people >= 6, "{hours_with_people}");
    // Overlapping patrols are refused.
    let overlapping = PatrolParams::sessions(8.0 * 3600.0, 600.0, 300.0, 3);
    assert!(matches!(
        Simulator::new(short(0).with_patrol(overlapping)),
        Err(SimError::InvalidParameter(
            haunts_core::InvalidParameter { .. }
        ))
    ));
}

#[test]
fn bad_parameters_are_typed_errors() {
    let bad = [
        {
            let mut p = short(0);
            p.grid_resolution = 0.0;
            p
        },
        {
            let mut p = short(0);
            p.start_time = f64::NAN;
            p
        },
        short(0).with_laser({
            let mut p = LaserParams::default();
            p.fov = 7.0;
            p
        }),
        short(0).with_laser({
            let mut p = LaserParams::default();
            p.range_max = 0.0;
            p
        }),
        short(0).with_patrol(PatrolParams::default().with_start(86_000.0)),
        short(0).with_patrol({
            let mut p = PatrolParams::default();
            p.speed = f64::INFINITY;
            p
        }),
        short(0).with_odometry({
            let mut p = OdometryParams::default();
            p.translation_noise = f64::NAN;
            p
        }),
        short(0).with_schedule(ScheduleParams::Runs {
            min_run: 0,
            max_run: 3,
        }),
    ];
    for p in bad {
        assert!(matches!(
            Simulator::new(p),
            Err(SimError::InvalidParameter(
                haunts_core::InvalidParameter { .. }
            ))
        ));
    }
    let huge = short(0).with_patrol(PatrolParams::all_day()).with_laser({
        let mut p = LaserParams::default();
        p.rate = 1000.0;
        p
    });
    assert!(matches!(
        Simulator::new(huge),
        Err(SimError::TooLarge { .. })
    ));
    let sim = Simulator::new(short(0)).unwrap();
    assert!(matches!(
        sim.day(usize::MAX),
        Err(SimError::DayOutOfRange { .. })
    ));
    assert!(sim.furniture(0, 99).is_err());
    // Thresholds of the truth grid are the defaults: occupied means 100.
    assert_eq!(
        sim.day(0).unwrap().truth.thresholds(),
        StateThresholds::default()
    );
}

/// With random starts each day's odometry is zeroed at its own random free pose of the
/// office (clear of obstacles by `START_CLEARANCE`, any heading): the odometry in the world
/// frame is the same as without random starts, the patrols, scans and truth are the same,
/// and only the odometry's frame differs.
#[test]
fn random_starts_zero_the_odometry_at_free_poses_and_change_nothing_else() {
    let plain = Simulator::new(short(5)).unwrap();
    let sim = Simulator::new(short(5).with_random_start(true)).unwrap();
    let mut starts = Vec::new();
    for index in 0..4 {
        let day = sim.day(index).unwrap();
        let same = plain.day(index).unwrap();
        assert_eq!(same.odometry_frame, haunts_occupancy::Pose2::identity());
        assert_eq!(day.poses, same.poses);
        assert_eq!(day.scans.len(), same.scans.len());
        assert!(day.scans.iter().zip(&same.scans).all(|(a, b)| {
            a.ranges
                .iter()
                .zip(&b.ranges)
                .all(|(x, y)| x.to_bits() == y.to_bits())
        }));
        assert_eq!(day.truth, same.truth);
        for (k, o) in day.odometry.iter().enumerate() {
            let world = day.odometry_frame * o;
            let d = (world.translation.vector - same.odometry[k].translation.vector).norm();
            assert!(d < 1e-9, "day {index} scan {k}: {d}");
        }
        // Free ground all round the start, in the office frame.
        let f = day.odometry_frame;
        let g = day.truth.geometry();
        let c = g.world_to_cell(f.translation.vector.into()).unwrap();
        let reach = (haunts_sim::START_CLEARANCE / g.resolution()).ceil() as i64;
        for dc in -reach..=reach {
            for dr in -reach..=reach {
                let n = g
                    .checked_cell(c.col as i64 + dc, c.row as i64 + dr)
                    .unwrap();
                assert_eq!(day.truth.value(n), Some(0), "day {index}: {n:?}");
            }
        }
        starts.push(f);
    }
    for (i, a) in starts.iter().enumerate() {
        for b in &starts[i + 1..] {
            assert!((a.translation.vector - b.translation.vector).norm() > 1e-6);
            assert!((a.rotation.angle() - b.rotation.angle()).abs() > 1e-9);
        }
    }
}
