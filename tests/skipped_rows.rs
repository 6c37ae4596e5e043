//! One bad row is skipped, not fatal (issue 44): for each reader of coordinates the examples
//! and the CLI use — detections (`hypertime`), trajectories (`ta_map`), CARMEN laser poses
//! (`carmen_map`) — good rows plus far and non-finite rows give the result of the good rows
//! alone, bit for bit, through the same calls the example makes, and the rows are counted and
//! named. (The bag poses of `haunts day` are checked end to end in `cli/tests/cli.rs`.) A test
//! day from a much wider area than the training days is scored, and its strip drawn coarser.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use haunts::affordance::hypertime::{
    DENSITY_UNITS, DetectionColumns, EvaluationParams, HypertimeModel, HypertimeParams, TimedPoint,
    evaluate, parse_detections,
};
use haunts::affordance::ta::{TaMap, TaParams};
use haunts::occupancy::bounds::{BoundsRule, RowCounts};
use haunts::occupancy::budget;
use haunts::occupancy::carmen::{CarmenOptions, parse_carmen};
use haunts::occupancy::mapping::{MapperParams, OccupancyMapper};
use haunts::occupancy::{GridGeometry, OccupancyError};
use haunts::tracking::{EthOptions, keep_near, parse_eth};

/// `lines` with `bad` inserted before line `at` of each pair.
fn with_bad_lines(good: &[String], bad: &[(usize, String)]) -> String {
    let mut out = String::new();
    for (i, line) in good.iter().enumerate() {
        for (at, b) in bad {
            if *at == i {
                out.push_str(b);
                out.push('\n');
            }
        }
        out.push_str(line);
        out.push('\n');
    }
    out
}

/// Detections of two busy places over a day: `t x y`, deterministic.
fn detection_lines(n: usize, spread: f64) -> Vec<String> {
    (0..n)
        .map(|i| {
            let f = i as f64;
            let t = 1_495_670_400.0 + f * 86_400.0 / n as f64;
            let (cx, cy) = if i % 3 == 0 { (2.0, 3.0) } else { (9.0, 6.0) };
            let x = cx + spread * ((f * 0.731).sin() + 0.3 * (f * 2.17).cos());
            let y = cy + spread * ((f * 0.419).cos() - 0.2 * (f * 1.33).sin());
            format!("{t} {x} {y}")
        })
        .collect()
}

/// What `examples/hypertime.rs` does with one file: read, then the bounds rule.
fn read(text: &str) -> (Vec<TimedPoint>, RowCounts) {
    let parsed = parse_detections(text.as_bytes(), &DetectionColumns::default()).unwrap();
    let kept = BoundsRule::default()
        .split("detections", parsed.records, |p| p.position)
        .unwrap();
    let mut rows = kept.skipped.counts;
    rows.non_finite += parsed.non_finite;
    (kept.rows, rows)
}

#[test]
fn a_far_detection_and_a_nan_one_leave_the_hypertime_scores_unchanged() {
    let train_lines = detection_lines(600, 1.5);
    let test_lines = detection_lines(300, 1.8);
    let (good, rows) = read(&with_bad_lines(&train_lines, &[]));
    assert_eq!(rows, RowCounts::default());
    let glitchy = with_bad_lines(
        &train_lines,
        &[
            (200, "1495690000 1e7 3.0".to_owned()),
            (400, "1495700000 nan 3.0".to_owned()),
        ],
    );
    let (kept, rows) = read(&glitchy);
    assert_eq!(
        rows,
        RowCounts {
            far: 1,
            non_finite: 1
        }
    );
    assert_eq!(kept, good);
    // Without the rule the far detection asks for a grid over the cell budget.
    let parsed = parse_detections(glitchy.as_bytes(), &DetectionColumns::default()).unwrap();
    let all = GridGeometry::bounding(parsed.records.iter().map(|p| p.position), 0.25, 1.0);
    assert!(
        matches!(all, Err(OccupancyError::GridTooLarge { .. })),
        "{all:?}"
    );

    // The same model and the same scores, bit for bit.
    let (test, _) = read(&with_bad_lines(&test_lines, &[]));
    let params = HypertimeParams::default().with_clusters(3);
    let score = |train: &[TimedPoint]| {
        let grid = GridGeometry::bounding(train.iter().map(|p| p.position), 0.25, 1.0).unwrap();
        let model = HypertimeModel::fit(train, &params).unwrap();
        evaluate(&model, &test, &grid, &EvaluationParams::default()).unwrap()
    };
    let (a, b) = (score(&good), score(&kept));
    assert_eq!(a, b);
    assert!(a.mean().unwrap().is_finite());
}

#[test]
fn a_test_day_over_a_much_wider_area_is_scored_and_its_strip_drawn_coarser() {
    let (train, _) = read(&with_bad_lines(&detection_lines(600, 1.5), &[]));
    // The test day's people walk up to 2.5 km away: the bulk itself is wide, so nothing is far.
    let wide: Vec<String> = detection_lines(300, 1.8)
        .into_iter()
        .enumerate()
        .map(|(i, line)| {
            let v: Vec<f64> = line.split(' ').map(|w| w.parse().unwrap()).collect();
            let k = (i % 10) as f64 * 250.0;
            format!("{} {} {}", v[0], v[1] + k, v[2] + k)
        })
        .collect();
    let (test, rows) = read(&with_bad_lines(&wide, &[]));
    assert_eq!((test.len(), rows.far), (300, 0));
    let grid = GridGeometry::bounding(train.iter().map(|p| p.position), 0.25, 1.0).unwrap();
    let model = HypertimeModel::fit(&train, &HypertimeParams::default().with_clusters(3)).unwrap();
    let e = evaluate(&model, &test, &grid, &EvaluationParams::default()).unwrap();
    assert_eq!(e.loglik.used + e.loglik.outside, 300);
    assert!(
        e.loglik.outside >= 250 && e.loglik.used > 0,
        "{:?}",
        e.loglik
    );
    assert!(e.mean().unwrap().is_finite());
    // The strip over training and test detections, as the example sizes it.
    let positions: Vec<_> = train.iter().chain(&test).map(|p| p.position).collect();
    let factors = [
        ("frames", 49.0),
        ("components", model.components().len() as f64 + 1.0),
        DENSITY_UNITS,
    ];
    // Whether a strip at `resolution` fits the cell and the work budgets.
    let fits = |resolution: f64| {
        GridGeometry::bounding(positions.iter().copied(), resolution, 1.0).is_ok_and(|g| {
            let mut all = factors.to_vec();
            all.push(("cells", g.len() as f64));
            budget::check_work("hourly strip", &all).is_ok()
        })
    };
    assert!(!fits(0.1));
    let strip = budget::fit_grid(&positions, 0.1, 1.0, "hourly strip", &factors).unwrap();
    assert!(strip.resolution() >= 0.2, "{}", strip.resolution());
    // The finest that fits: half its cell side would not.
    assert!(fits(strip.resolution()) && !fits(strip.resolution() / 2.0));
}

/// ETH `obsmat.txt` rows of `people` walkers crossing a square: `frame id x 0 y`.
fn obsmat_lines(people: u32) -> Vec<String> {
    let mut lines = Vec::new();
    for id in 1..=people {
        let (x0, y0) = (f64::from(id % 5) * 2.0, f64::from(id / 5) * 1.5);
        for k in 0..25u32 {
            let frame = 6 * (k + 10 * id);
            let (x, y) = (x0 + 0.5 * f64::from(k), y0 + 0.1 * f64::from(k));
            lines.push(format!("{frame} {id} {x} 0 {y} 0 0 0"));
        }
    }
    lines
}

#[test]
fn a_far_trajectory_sample_leaves_the_ta_map_unchanged() {
    let lines = obsmat_lines(20);
    let read = |text: &str| {
        let parsed = parse_eth(text.as_bytes(), &EthOptions::default()).unwrap();
        keep_near(parsed.records, &BoundsRule::default()).unwrap()
    };
    let good = read(&with_bad_lines(&lines, &[]));
    // A far sample inside walker 3's trajectory, and a far walker of its own.
    let bad = read(&with_bad_lines(
        &lines,
        &[
            (60, "438 3 1e7 0 2.0 0 0 0".to_owned()),
            (300, "600 99 -4e6 0 -4e6 0 0 0".to_owned()),
        ],
    ));
    assert_eq!(
        bad.skipped.counts,
        RowCounts {
            far: 2,
            non_finite: 0
        }
    );
    assert_eq!(bad.rows, good.rows);
    let points = |k: &[haunts::tracking::Trajectory]| -> Vec<_> {
        k.iter()
            .flat_map(|t| t.samples.iter().map(|s| s.1))
            .collect()
    };
    let geometry = GridGeometry::bounding(points(&good.rows), 0.5, 2.0).unwrap();
    let fit = |k: &[haunts::tracking::Trajectory]| {
        TaMap::fit(k, geometry, &TaParams::default())
            .unwrap()
            .raster()
            .clone()
    };
    assert_eq!(fit(&bad.rows), fit(&good.rows));
}

/// CARMEN `FLASER` lines of a robot driving along a corridor 3 m wide: 61 beams over 180°.
fn flaser_lines(n: u32) -> Vec<String> {
    (0..n)
        .map(|i| {
            let x = 0.1 * f64::from(i);
            let ranges: Vec<String> = (0..61)
                .map(|b| {
                    let a =
                        std::f64::consts::PI * f64::from(b) / 60.0 - std::f64::consts::FRAC_PI_2;
                    let wall = 1.5 / a.sin().abs().max(1e-3);
                    format!("{:.3}", wall.min(8.0))
                })
                .collect();
            let t = 100.0 + f64::from(i);
            format!(
                "FLASER 61 {} {x} 0 0 {x} 0 0 {t} host {t}",
                ranges.join(" ")
            )
        })
        .collect()
}

#[test]
fn a_far_carmen_laser_pose_leaves_the_map_unchanged() {
    let lines = flaser_lines(60);
    let build = |text: &str| {
        let mut log = parse_carmen(text.as_bytes(), &CarmenOptions::default()).unwrap();
        // What `examples/carmen_map.rs` does.
        let kept = BoundsRule::default()
            .split("laser poses", std::mem::take(&mut log.scans), |s| {
                s.laser_pose.translation.vector.into()
            })
            .unwrap();
        let mut rows = kept.skipped.counts;
        rows.non_finite += log.non_finite;
        let posed = || kept.rows.iter().map(|s| (s.scan.clone(), s.laser_pose));
        let (mapper, _) =
            OccupancyMapper::from_posed_scans(posed, 0.05, 1.0, MapperParams::default()).unwrap();
        (mapper.occupancy_grid(), rows, kept.skipped.first_far)
    };
    let (good, rows, _) = build(&with_bad_lines(&lines, &[]));
    assert_eq!(rows, RowCounts::default());
    let far = lines[30].replacen(" 3 0 0 3 0 0 ", " 100000 0 0 100000 0 0 ", 1);
    assert_ne!(far, lines[30]);
    let nan = lines[40].replacen(" 4 0 0 4 0 0 ", " nan 0 0 4 0 0 ", 1);
    assert_ne!(nan, lines[40]);
    let (bad, rows, first_far) = build(&with_bad_lines(&lines, &[(30, far), (40, nan)]));
    assert_eq!(
        rows,
        RowCounts {
            far: 1,
            non_finite: 1
        }
    );
    assert_eq!(first_far[0].index, 30);
    assert_eq!(bad, good);
}
