//! Activity at a time of day (`activity_at`): on synthetic days, the time-independent map
//! wherever no rhythm is validated, and its average over the observed times everywhere; on
//! the two real days of people detections (`../shared/data/people/`, skipped with a notice
//! when absent), trained on one day and scored hour by hour on the other against the
//! time-independent map and the uniform map.
#![allow(clippy::unwrap_used)]

use haunts_affordance::DensityMap;
use haunts_affordance::UniformDensity;
use haunts_affordance::activity_at::{
    ActivityAt, ActivityAtParams, HourlyParams, evaluate_hours, observation_windows,
};
use haunts_affordance::hypertime::{
    CycleValidation, DAY, GivenPeriods, HypertimeModel, HypertimeParams, TimedPoint,
};
use haunts_occupancy::GridGeometry;
use nalgebra::Point2;

mod common;
use common::stroll_day;

const H: f64 = 3600.0;

/// `days` days observed 8:00–17:00, one detection a minute at each of two places; with
/// `rhythm`, the second place is busy only 12:00–13:00 (ten detections a minute).
fn days(days: usize, rhythm: bool) -> Vec<TimedPoint> {
    let mut points = Vec::new();
    for day in 0..days {
        for i in 0..540 {
            let t = day as f64 * DAY + 8.0 * H + i as f64 * 60.0;
            let w = 0.1 * ((i * 7 + day) % 5) as f64;
            points.push(TimedPoint::new(t, w, -w));
            let busy = (240..300).contains(&i);
            let n = if !rhythm {
                1
            } else if busy {
                10
            } else {
                0
            };
            for k in 0..n {
                points.push(TimedPoint::new(t + k as f64, 5.0 + w, 0.05 * k as f64));
            }
        }
    }
    points
}

#[test]
fn without_a_validated_period_the_activity_is_the_time_independent_map() {
    // Four days without a rhythm: the daily period is validated on left-out days, loses,
    // and is dropped (`Validate`); the rate's rhythm is checked on held-out days and is
    // not better than a flat rate; the activity is then the base at every time.
    let points = days(4, false);
    let params = HypertimeParams::default()
        .with_clusters(4)
        .with_validation(CycleValidation::default().with_given(GivenPeriods::Validate));
    let model = HypertimeModel::fit(&points, &params).unwrap();
    assert!(model.periods().is_empty(), "{:?}", model.periods());
    let base = UniformDensity(Some(2.5));
    let activity = ActivityAt::new(base, model, &points, &ActivityAtParams::default()).unwrap();
    let check = activity.rate_check().unwrap();
    assert!(check.days == 4 && !check.accepted, "{check:?}");
    assert!(!activity.has_rhythm());
    for t in [3.0 * H, 8.5 * H, 12.5 * H, 16.0 * H] {
        for p in [
            Point2::new(0.1, 0.0),
            Point2::new(5.1, 0.0),
            Point2::new(40.0, 9.0),
        ] {
            assert_eq!(activity.at(t).density_at(p), Some(2.5));
        }
    }
}

#[test]
fn the_rhythm_redistributes_the_map_over_the_observed_hours() {
    let points = days(3, true);
    let model = HypertimeModel::fit(&points, &HypertimeParams::default().with_clusters(4)).unwrap();
    assert_eq!(model.periods(), &[DAY]);
    let base = UniformDensity(Some(1.0));
    let params = ActivityAtParams::default();
    let activity = ActivityAt::new(base, model, &points, &params).unwrap();
    assert!(activity.has_rhythm());
    // The exposure-weighted mean over the day's nodes is the base, at every place.
    let table = Point2::new(5.2, 0.1);
    for p in [Point2::new(0.2, -0.2), table, Point2::new(2.5, 0.0)] {
        let (mut num, mut den) = (0.0, 0.0);
        for k in 0..24 {
            let t = k as f64 * H;
            let x = activity.rate().exposure_near(t);
            num += x * activity.at(t).density_at(p).unwrap();
            den += x;
        }
        // Exactly 1 where c = 1 at every node; the nodes 4σ out, where c < 1, move it by < 10⁻³.
        approx::assert_relative_eq!(num / den, 1.0, max_relative = 1e-3);
    }
    // Lunch at the table, and nothing at night (never observed: the base, exactly).
    assert!(activity.at(12.5 * H).density_at(table).unwrap() > 2.0);
    assert!(activity.at(9.0 * H).density_at(table).unwrap() < 0.1);
    assert_eq!(activity.confidence(2.0 * H), 0.0);
    assert_eq!(activity.at(2.0 * H).density_at(table), Some(1.0));
    // The raster with the time-independent part precomputed is the pointwise map.
    let g = GridGeometry::new(0.5, Point2::new(-1.0, -2.0), 16, 8).unwrap();
    let raster = activity.on_grid(&g);
    for t in [2.0 * H, 9.0 * H, 12.5 * H] {
        let fast = raster.at(t);
        let slow = activity.at(t).rasterise(&g);
        for (a, b) in fast.data().iter().zip(slow.data()) {
            approx::assert_relative_eq!(a, b, max_relative = 1e-12);
        }
    }
}

#[test]
fn observation_windows_of_the_real_days_cover_their_working_hours() {
    let Some(d25) = stroll_day("25") else {
        return;
    };
    let d25 = d25.records;
    let windows = observation_windows(&d25, ActivityAtParams::default().max_gap);
    let seconds: f64 = windows.iter().map(|(a, b)| b - a).sum();
    // ≈ 9:50–17:10 UTC with quiet spells under 15 minutes (the longest is 9 minutes).
    assert!((6.0 * H..8.0 * H).contains(&seconds), "{seconds}");
}

#[test]
fn activity_at_the_hour_beats_the_time_independent_map_on_the_next_day() {
    let (Some(d25), Some(d26)) = (stroll_day("25"), stroll_day("26")) else {
        return;
    };
    let (d25, d26) = (d25.records, d26.records);
    for (name, train, test) in [("25 → 26", &d25, &d26), ("26 → 25", &d26, &d25)] {
        // Everything is fitted on the training day; the test day is only scored.
        let params = HypertimeParams::default();
        let model = HypertimeModel::fit(train, &params).unwrap();
        let baseline = HypertimeModel::fit(train, &params.clone().without_time()).unwrap();
        let base = baseline.at(0.0);
        let activity = ActivityAt::new(base, model, train, &ActivityAtParams::default()).unwrap();
        let grid = GridGeometry::bounding(train.iter().map(|p| p.position), 0.25, 1.0).unwrap();
        let eval = evaluate_hours(&activity, test, &grid, &HourlyParams::default()).unwrap();
        eprintln!(
            "train {name}: uniform {:.3} nats per detection",
            eval.uniform
        );
        eprintln!(
            "hour (UTC) | detections | at t | time-independent | seconds | predicted at t | predicted static"
        );
        for h in &eval.hours {
            eprintln!(
                "{:02} | {} | {:.3} | {:.3} | {:.0} | {:.0} | {:.0}",
                (h.start.rem_euclid(DAY) / H) as u32,
                h.observed,
                h.mean_at().unwrap_or(f64::NAN),
                h.mean_static().unwrap_or(f64::NAN),
                h.seconds,
                h.predicted_at,
                h.predicted_static
            );
        }
        let (at, st) = eval.mean().unwrap();
        let (rmse_at, rmse_st) = eval.count_rmse().unwrap();
        eprintln!(
            "all hours: at t {at:.4}, time-independent {st:.4}, uniform {:.4}; count RMSE per hour: at t {rmse_at:.0}, time-independent {rmse_st:.0}; unscored {}",
            eval.uniform, eval.unscored
        );
        assert!(at > st, "{name}: at t {at} <= time-independent {st}");
        assert!(st > eval.uniform);
        assert!(rmse_at < rmse_st, "{name}: {rmse_at} >= {rmse_st}");
    }
}
