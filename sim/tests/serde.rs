//! With the `serde` feature, parameters, office descriptions and simulated days round-trip
//! through JSON; an office loaded from JSON simulates exactly the days of the original, and
//! deserialising a visit checks its path.
#![cfg(feature = "serde")]
#![allow(clippy::unwrap_used)]

use haunts_occupancy::Pose2;
use haunts_occupancy::mapping::{MapperParams, OccupancyMapper};
use haunts_sim::{
    Activity, Day, Door, Furniture, FurnitureKind, FurnitureNoise, LaserParams, Layout,
    MaxRangeReturn, OdometryParams, Office, PatrolParams, PeopleParams, PersonTruth, RatePeak,
    ScheduleParams, Shape, SimError, SimParams, Simulator, Visit,
};
use nalgebra::{Point2, Vector2};

use haunts_test_support::json;
use json::{Tally, corrupt, rejection, round_trip, trip};

/// Parameters with every value changed from its default.
fn custom_params() -> SimParams {
    {
        let mut p = SimParams::default();
        p.seed = 99;
        p.start_time = 1_700_000_000.5;
        p.grid_resolution = 0.1;
        p.schedule = ScheduleParams::Runs {
            min_run: 2,
            max_run: 3,
        };
        p.furniture = FurnitureNoise {
            chair_sd: 0.2,
            chair_angle_sd: 0.4,
            table_sd: 0.05,
            table_angle_sd: 0.06,
            solid_sd: 0.01,
            solid_angle_sd: 0.02,
        };
        p.people = {
            let mut p = PeopleParams::default();
            p.visits_per_day = 90.0;
            p.open = 8.0 * 3600.0;
            p.close = 18.5 * 3600.0;
            p.background = 0.25;
            p.peaks = vec![
                RatePeak {
                    time: 12.5 * 3600.0,
                    width: 1800.0,
                    weight: 2.0,
                    activity_weights: Some([0.2, 0.7, 0.1]),
                },
                RatePeak {
                    time: 16.0 * 3600.0,
                    width: 900.0,
                    weight: 0.5,
                    activity_weights: None,
                },
            ];
            p.activity_weights = [0.5, 0.25, 0.25];
            p.group_probability = 0.75;
            p.coffee_first = 0.125;
            p.max_group = 3;
            p.dwell = [(30.0, 200.0), (400.0, 1500.0), (500.0, 3000.0)];
            p.speed = 1.25;
            p.speed_sd = 0.1;
            p.leg_radius = 0.07;
            p.leg_spread = 0.12;
            p.stride = 1.1;
            p.swing = 0.2;
            p
        };
        p.patrol = {
            let mut p = PatrolParams::default();
            p.start = 12.0 * 3600.0 + 900.0;
            p.duration = 2.0;
            p.speed = 0.4;
            p.turn_rate = 0.8;
            p.sessions = 2;
            p.interval = 600.0;
            p
        };
        p.laser = {
            let mut p = LaserParams::default();
            p.fov = 3.0;
            p.angular_resolution = 0.025;
            p.range_min = 0.1;
            p.range_max = 25.0;
            p.noise_sd = 0.02;
            p.dropout = 0.0;
            p.spurious_max_range = 0.0;
            p.max_range_return = MaxRangeReturn::RangeMax;
            p.rate = 5.0;
            p
        };
        p.odometry = {
            let mut p = OdometryParams::default();
            p.translation_noise = 0.02;
            p.rotation_noise = 0.03;
            p.rotation_per_metre = 0.005;
            p.heading_bias = -0.0002;
            p
        };
        p.max_scans_per_day = 5000;
        p
    }
}

#[test]
fn parameters_round_trip_through_json() {
    let params = custom_params();
    let d = SimParams::default();
    // Every part differs from its default, so a field lost on the way would show.
    assert_ne!(params.schedule, d.schedule);
    assert_ne!(params.furniture, d.furniture);
    assert_ne!(params.people, d.people);
    assert_ne!(params.patrol, d.patrol);
    assert_ne!(params.laser, d.laser);
    assert_ne!(params.odometry, d.odometry);
    params.clone().check(5).unwrap();
    round_trip(&params);
    round_trip(&d);
    round_trip(&ScheduleParams::Fixed(vec![3, 1, 4, 1]));
    for m in [MaxRangeReturn::Infinity, MaxRangeReturn::RangeMax] {
        round_trip(&m);
    }
    for a in [Activity::Coffee, Activity::Table, Activity::Desk] {
        round_trip(&a);
    }
    for kind in [
        FurnitureKind::Table,
        FurnitureKind::Chair,
        FurnitureKind::Sofa,
        FurnitureKind::Cabinet,
    ] {
        round_trip(&Furniture::new(kind, 1.5, -2.25, 0.8, 0.6, 0.3));
    }
    for shape in [
        Shape::Circle {
            center: Point2::new(1.0, 2.0),
            radius: 0.25,
        },
        Shape::Rect {
            center: Point2::new(-1.0, 0.5),
            half: Vector2::new(2.0, 0.05),
            angle: 0.75,
        },
        Shape::Segment {
            a: Point2::new(0.0, 0.0),
            b: Point2::new(3.0, 4.0),
        },
    ] {
        round_trip(&shape);
    }
}

/// A small office: a 6 m × 4 m room with one door, one table layout and one sofa layout.
fn small_office() -> Office {
    let w = |x0, y0, x1, y1| Shape::aabb(Point2::new(x0, y0), Point2::new(x1, y1));
    Office {
        min: Point2::new(-1.0, -1.0),
        max: Point2::new(7.0, 5.0),
        walls: vec![
            w(0.0, 0.0, 6.0, 0.1),
            w(0.0, 3.9, 6.0, 4.0),
            w(0.0, 0.0, 0.1, 1.5),
            w(0.0, 2.5, 0.1, 4.0),
            w(5.9, 0.0, 6.0, 4.0),
            Shape::Segment {
                a: Point2::new(-1.0, -1.0),
                b: Point2::new(7.0, -1.0),
            },
        ],
        fixed: vec![Furniture::new(
            FurnitureKind::Cabinet,
            5.5,
            2.0,
            0.6,
            1.2,
            0.0,
        )],
        layouts: vec![
            Layout {
                name: "one table".to_string(),
                furniture: vec![Furniture::new(
                    FurnitureKind::Table,
                    3.0,
                    2.0,
                    1.2,
                    0.8,
                    0.1,
                )],
            },
            Layout {
                name: "a sofa".to_string(),
                furniture: vec![Furniture::new(FurnitureKind::Sofa, 3.0, 1.0, 1.8, 0.8, 0.0)],
            },
        ],
        doors: vec![Door {
            inside: Point2::new(0.5, 2.0),
            outside: Point2::new(-0.7, 2.0),
        }],
        coffee: vec![Point2::new(4.8, 3.4)],
        desks: vec![Point2::new(5.0, 1.0)],
        waypoints: vec![
            Point2::new(1.0, 1.0),
            Point2::new(4.5, 1.0),
            Point2::new(4.5, 3.0),
            Point2::new(1.0, 3.0),
            Point2::new(1.0, 1.0),
        ],
    }
}

#[test]
fn an_office_loaded_from_json_simulates_the_same_days() {
    round_trip(&Office::builtin());
    let office = small_office();
    office.clone().check().unwrap();
    let loaded = round_trip(&office);
    let params = custom_params().with_schedule(ScheduleParams::Fixed(vec![1, 0]));
    let a = Simulator::with_office(office, params.clone()).unwrap();
    let b = Simulator::with_office(loaded, params).unwrap();
    for day in 0..2 {
        assert!(a.day(day).unwrap().bit_eq(&b.day(day).unwrap()));
    }
    assert_eq!(a.day(0).unwrap().layout, 1);
}

#[test]
fn an_invalid_office_from_json_is_refused_by_the_simulator() {
    let json = serde_json::to_string(&small_office()).unwrap();
    let no_doors: Office = serde_json::from_str(&json.replace(
        r#""doors":[{"inside":[0.5,2.0],"outside":[-0.7,2.0]}]"#,
        r#""doors":[]"#,
    ))
    .unwrap();
    let e = Simulator::with_office(no_doors, SimParams::default()).unwrap_err();
    assert!(
        matches!(e, SimError::InvalidOffice { what: "door", .. }),
        "{e}"
    );
    assert!(e.to_string().contains("door"), "{e}");
    let negative_radius: Office = serde_json::from_str(&json.replace(
        r#""walls":["#,
        r#""walls":[{"Circle":{"center":[1.0,1.0],"radius":-0.5}},"#,
    ))
    .unwrap();
    let e = Simulator::with_office(negative_radius, SimParams::default()).unwrap_err();
    assert!(e.to_string().contains("wall #0"), "{e}");
}

#[test]
fn a_day_with_dropouts_and_infinite_readings_round_trips_through_json() {
    // NaN dropouts and `+inf` max-range readings, which JSON has no numbers for, are written
    // as "NaN" and "inf" (they used to be written as null and refused on reading).
    let mut params = custom_params();
    params.laser.dropout = 0.05;
    params.laser.spurious_max_range = 0.05;
    params.laser.max_range_return = MaxRangeReturn::Infinity;
    let day: Day = Simulator::new(params).unwrap().day(0).unwrap();
    let ranges = day.scans.iter().flat_map(|s| s.ranges.iter());
    assert!(ranges.clone().any(|r| r.is_nan()), "dropouts");
    assert!(ranges.clone().any(|r| *r == f64::INFINITY), "no returns");
    let back: Day = trip(&day);
    assert!(back.bit_eq(&day));
}

#[test]
fn a_simulated_day_round_trips_through_json() {
    // Finite readings only: the day also compares equal with `==`.
    let params = custom_params().with_people({
        let mut p = PeopleParams::default();
        p.visits_per_day = 400.0;
        p
    });
    let sim = Simulator::new(params).unwrap();
    let day: Day = sim.day(1).unwrap();
    assert_eq!(day.scans.len(), 20); // 2 sessions of 2 s at 5 Hz
    assert!(!day.visits.is_empty());
    assert!(
        day.people.iter().any(|p| !p.is_empty()),
        "people are in view"
    );
    assert!(
        day.scans
            .iter()
            .all(|s| s.ranges.iter().all(|r| r.is_finite()))
    );
    let back = round_trip(&day);
    assert!(back.bit_eq(&day));
    round_trip(&day.visits[0]);
    let person: PersonTruth = day.people.iter().flatten().copied().next().unwrap();
    round_trip(&person);
    // A visit read back is the same person at every instant.
    let (v, w) = (&day.visits[3], &back.visits[3]);
    let t = 0.5 * (v.arrival() + v.departure());
    assert_eq!(v.at(t), w.at(t));
    assert!(v.at(t).is_some());
}

#[test]
fn an_invalid_visit_is_rejected() {
    let visit = |place: &str, facing: &str, keys: &str| {
        format!(r#"{{"id":7,"activity":"Table","place":{place},"facing":{facing},"keys":{keys}}}"#)
    };
    let keys = r#"[{"t":10.0,"p":[0.0,0.0],"s":0.0},{"t":12.0,"p":[2.0,0.0],"s":2.0},{"t":20.0,"p":[2.0,0.0],"s":2.0}]"#;
    let ok: Visit = serde_json::from_str(&visit("[2.0,0.0]", "1.5", keys)).unwrap();
    assert_eq!((ok.arrival(), ok.departure()), (10.0, 20.0));
    assert_eq!(ok.at(11.0).unwrap().position, Point2::new(1.0, 0.0));
    round_trip(&ok);

    let e = rejection::<Visit>(&visit(
        "[2.0,0.0]",
        "1.5",
        r#"[{"t":10.0,"p":[0.0,0.0],"s":0.0}]"#,
    ));
    assert!(e.contains("`visit.keys`"), "{e}");
    let e = rejection::<Visit>(&visit(
        "[2.0,0.0]",
        "1.5",
        &keys.replace(r#""t":20.0"#, r#""t":11.0"#),
    ));
    assert!(e.contains("`visit.keys.t`"), "{e}");
    let e = rejection::<Visit>(&visit(
        "[2.0,0.0]",
        "1.5",
        &keys.replace(
            r#""t":12.0,"p":[2.0,0.0],"s":2.0"#,
            r#""t":12.0,"p":[2.0,0.0],"s":-1.0"#,
        ),
    ));
    assert!(e.contains("`visit.keys.s`"), "{e}");
    let e = rejection::<Visit>(&visit(
        "[2.0,0.0]",
        "1.5",
        &keys.replace(r#""s":0.0"#, r#""s":-0.5"#),
    ));
    assert!(e.contains("`visit.keys.s`"), "{e}");
    let e = rejection::<Visit>(&visit("[2.0,0.0]", r#""east""#, keys));
    assert!(e.contains("invalid type"), "{e}");
    let e = rejection::<Visit>(
        &visit("[2.0,0.0]", "1.5", keys).replace(r#""activity":"Table""#, r#""activity":"Nap""#),
    );
    assert!(e.contains("Nap"), "{e}");
}

#[test]
fn a_day_with_an_invalid_scan_is_rejected() {
    let day = Simulator::new(custom_params()).unwrap().day(0).unwrap();
    let json = serde_json::to_string(&day).unwrap();
    let increment = format!(
        r#""angle_increment":{}"#,
        serde_json::to_string(&day.scans[0].angle_increment).unwrap()
    );
    assert!(json.contains(&increment));
    let e = rejection::<Day>(&json.replacen(&increment, r#""angle_increment":0.0"#, 1));
    assert!(e.contains("angle_increment"), "{e}");
}

/// Tiny parameters: 2 patrols of 1 s at 5 Hz, few people.
fn tiny_params() -> SimParams {
    let mut params = custom_params();
    params.schedule = ScheduleParams::Fixed(vec![1, 0]);
    params.patrol.duration = 1.0;
    params.people.visits_per_day = 30.0;
    params.people.open = 12.0 * 3600.0;
    params.people.close = 13.0 * 3600.0;
    params
}

/// A visit's times, path, truth and legs at a few instants, and a laser cast at its legs.
fn use_visit(visit: &Visit, sim: &Simulator) {
    let (a, d) = (visit.arrival(), visit.departure());
    assert!(a <= d);
    let _ = visit.path().count();
    for t in [a, d, 0.5 * (a + d), a + 1.0, d - 1.0, a - 1.0, f64::NAN] {
        let _ = visit.at(t);
        if let Some(legs) = visit.legs(t, &sim.params().people) {
            let ranges = sim.exact_ranges(&Pose2::identity(), &legs);
            assert!(!ranges.is_empty());
        }
    }
}

/// A day's scans mapped at its true poses, its truth grid read, its people's legs cast.
fn use_day(day: &Day, sim: &Simulator) {
    let g = *day.truth.geometry();
    let _ = day.truth.counts();
    let mut mapper = OccupancyMapper::new(g, MapperParams::default()).unwrap();
    for (scan, pose) in day.scans.iter().zip(&day.poses) {
        let _ = mapper.insert(scan, pose);
        let legs = sim.legs_at(day, scan.stamp);
        let _ = sim.exact_ranges(pose, &legs);
    }
    let _ = mapper.occupancy_grid();
    for (odometry, truth) in day.odometry.iter().zip(&day.poses) {
        let _ = odometry.inverse() * truth;
    }
    for visit in &day.visits {
        use_visit(visit, sim);
    }
    let _ = day.people.iter().flatten().map(|p| p.beams).sum::<usize>();
    assert!(
        day.bit_eq(day)
            || day
                .scans
                .iter()
                .any(|s| s.ranges.iter().any(|r| r.is_nan()))
    );
    let _ = sim.furniture(day.index, day.layout);
}

#[test]
fn corrupted_files_are_refused_or_usable_never_a_panic() {
    let params = tiny_params();
    // An office is plain data: the simulator checks it; a day from an accepted one must
    // simulate.
    let mut offices = Tally::default();
    let office = serde_json::to_value(small_office()).unwrap();
    offices.read(
        json::mutations(&office, 1000),
        |office: &Office, _| match Simulator::with_office(office.clone(), params.clone()) {
            Err(_) => false,
            Ok(sim) => {
                let day = sim.day(0).unwrap();
                assert_eq!(day.scans.len(), day.poses.len());
                use_day(&day, &sim);
                true
            }
        },
    );
    // A coarse day (0.5 m cells, 31 beams a scan), so that the corruptions sampled from it
    // are not all in the truth grid and the ranges.
    let mut coarse = params.clone();
    coarse.grid_resolution = 0.5;
    coarse.laser.angular_resolution = 0.1;
    let sim = Simulator::with_office(small_office(), coarse).unwrap();
    let day = sim.day(1).unwrap();
    assert!(!day.visits.is_empty() && !day.scans.is_empty());
    let days = corrupt(&day, 1500, |loaded: &Day| use_day(loaded, &sim));
    let mut visits = Tally::default();
    for visit in day.visits.iter().take(3) {
        let t = corrupt(visit, 200, |loaded: &Visit| use_visit(loaded, &sim));
        visits.accepted += t.accepted;
        visits.refused += t.refused;
    }
    for (name, tally) in [("Office", offices), ("Day", days), ("Visit", visits)] {
        eprintln!("{name}: {tally:?}");
        assert!(tally.refused > 0 && tally.accepted > 0, "{name}: {tally:?}");
    }
}
