//! Activity at a time of day on the simulated office (issue 18 item 6): the simulator's
//! morning coffee and lunch peaks learnt from the true people of training days, scored hour
//! by hour on held-out days against the time-independent map, and the same trip across the
//! room planned at 08:00 and at 12:30 with the layout's affordance modulated by the rhythm.
//!
//! The people are the simulator's truth, sampled every minute over the working day (the
//! robot's patrol is one second: what is learnt is the rhythm, not the tracker), and the
//! layout's affordance is their hits over a constant number of visits per cell.
#![allow(clippy::unwrap_used)]

use haunts::affordance::activity_at::{ActivityAt, ActivityAtParams, HourlyParams, evaluate_hours};
use haunts::affordance::density::{DailyDensity, HitCounter};
use haunts::affordance::hypertime::{HypertimeModel, HypertimeParams, TimedPoint};
use haunts::affordance::{LayoutLibrary, LayoutParams};
use haunts::occupancy::Grid;
use haunts::pipeline::serve::{ServeParams, activity_along, plan_at_times};
use haunts::planning::SearchParams;
use haunts::sim::{Day, PatrolParams, SimParams, Simulator};
use nalgebra::Point2;

const H: f64 = 3600.0;

/// The true people of `day`, every minute from 7:00 to 19:00.
fn people(day: &Day) -> Vec<TimedPoint> {
    (0..12 * 60)
        .flat_map(|m| {
            let t = day.midnight + 7.0 * H + m as f64 * 60.0;
            day.visits
                .iter()
                .filter_map(move |v| v.at(t))
                .map(move |p| TimedPoint::new(t, p.position.x, p.position.y))
        })
        .collect()
}

#[test]
fn the_same_trip_differs_at_eight_and_at_half_past_twelve() {
    let patrol = PatrolParams::sessions(7.0 * H, 1.0, H, 1);
    let sim = Simulator::new(SimParams::default().with_seed(3).with_patrol(patrol)).unwrap();
    let days = sim.days(0..16).unwrap();
    // The layout of most days; its first days train, its last two are held out.
    let mut count = [0usize; 8];
    days.iter().for_each(|d| count[d.layout] += 1);
    let layout = (0..8).max_by_key(|&l| count[l]).unwrap();
    let mine: Vec<&Day> = days.iter().filter(|d| d.layout == layout).collect();
    assert!(mine.len() >= 5, "{count:?}");
    let (train, test) = mine.split_at(mine.len() - 2);
    let geometry = sim.geometry();
    let mut library =
        LayoutLibrary::new(geometry, LayoutParams::default().with_min_visits(1)).unwrap();
    let mut points = Vec::new();
    let mut windows = Vec::new();
    for d in train {
        let day_points = people(d);
        let mut hits = HitCounter::new(geometry, 0.25).unwrap();
        hits.add_all(day_points.iter().map(|p| p.position));
        let visits = Grid::filled(geometry, 12 * 60u32);
        let density = DailyDensity::new(hits.into_counts(), visits, 1).unwrap();
        library
            .ingest(format!("day {}", d.index), &d.truth, &density)
            .unwrap();
        windows.push((d.midnight + 7.0 * H, d.midnight + 19.0 * H));
        points.extend(day_points);
    }
    let test_points: Vec<TimedPoint> = test.iter().flat_map(|d| people(d)).collect();
    let stride = points.len().div_ceil(8000);
    let thinned: Vec<TimedPoint> = points.iter().copied().step_by(stride).collect();
    let params = HypertimeParams::default();
    let model = HypertimeModel::fit(&thinned, &params).unwrap();
    let baseline = HypertimeModel::fit(&thinned, &params.clone().without_time()).unwrap();
    // The daily period loses on left-out training days here (the true people of one day's
    // lunch sit at other chairs than the next day's), so the model is time-independent and
    // the rhythm is the rate's alone: how many come at each hour.
    let step = &model.report().selection.period_steps[0];
    eprintln!("daily period: {step:?}");
    assert!(model.periods().is_empty());
    // The rate's rhythm is used: it predicts the hourly counts of held-out training days
    // better than a flat rate (checked below).
    let rhythm = ActivityAtParams::default();

    // (b) The rhythm on held-out days: where (per detection) and how many (per hour).
    let presence =
        ActivityAt::with_windows(baseline.at(0.0), model.clone(), &points, &windows, &rhythm)
            .unwrap();
    let eval =
        evaluate_hours(&presence, &test_points, &geometry, &HourlyParams::default()).unwrap();
    let check = presence.rate_check().unwrap();
    eprintln!("rate rhythm on held-out training days: {check:?}");
    assert!(check.accepted && check.days == train.len(), "{check:?}");
    let (at, st) = eval.mean().unwrap();
    let (rmse_at, rmse_st) = eval.count_rmse().unwrap();
    eprintln!(
        "simulated layout {layout}: {} training days, {} test days; at t {at:.3}, time-independent {st:.3}, uniform {:.3} nats per detection; count RMSE per hour {rmse_at:.0} vs {rmse_st:.0}",
        train.len(),
        test.len(),
        eval.uniform
    );
    for h in &eval.hours {
        eprintln!(
            "{:02} | {} | {:.3} | {:.3} | {:.0} | {:.0}",
            ((h.start - test[0].midnight).rem_euclid(86_400.0) / H) as u32,
            h.observed,
            h.mean_at().unwrap_or(f64::NAN),
            h.mean_static().unwrap_or(f64::NAN),
            h.predicted_at,
            h.predicted_static
        );
    }
    // Where: no period validated, so the map at t is the time-independent one up to a
    // factor, and its normalised likelihood is the same (within 10⁻⁶ nats); how many: the
    // rate's rhythm predicts each hour's detections better.
    assert!((at - st).abs() < 1e-6, "at t {at}, time-independent {st}");
    assert!(st > eval.uniform);
    assert!(rmse_at < rmse_st, "{rmse_at} >= {rmse_st}");

    // (3) The layout's affordance at 08:00 and at 12:30, and the same trip planned on both.
    assert_eq!(library.layouts().len(), 1);
    let served_layout = &library.layouts()[0];
    let activity = ActivityAt::with_windows(
        served_layout.affordance().clone(),
        model,
        &points,
        &windows,
        &rhythm,
    )
    .unwrap();
    let raster = activity.on_grid(&geometry);
    let midnight = test[0].midnight;
    let (from, to) = (Point2::new(1.0, 4.8), Point2::new(14.2, 5.0));
    let plans = plan_at_times(
        served_layout,
        &raster,
        &[midnight + 8.0 * H, midnight + 12.5 * H],
        from,
        to,
        &ServeParams::default(),
        SearchParams::default(),
    )
    .unwrap();
    let (eight, lunch) = (&plans[0], &plans[1]);
    for p in &plans {
        let m = &p.plans.with_layer;
        eprintln!(
            "{:.2} h: length {:.2} m, activity mean {:.4}, max {:.4} (without the layer: {:.2} m, mean {:.4}, max {:.4})",
            (p.time - midnight) / H,
            m.length,
            m.activity_mean,
            m.activity_max,
            p.plans.without_layer.length,
            p.plans.without_layer.activity_mean,
            p.plans.without_layer.activity_max
        );
    }
    // Activity differs by hour: lunch is busier along the plain path than eight o'clock.
    assert!(lunch.plans.without_layer.activity_max > 2.0 * eight.plans.without_layer.activity_max);
    // ... so the plans differ, and at lunch the lunch plan meets less activity than the
    // plan made at eight would.
    assert_ne!(eight.plans.with_path, lunch.plans.with_path);
    let (eight_at_lunch, _) = activity_along(&eight.plans.with_path, &lunch.served.density);
    let (lunch_at_lunch, _) = activity_along(&lunch.plans.with_path, &lunch.served.density);
    eprintln!(
        "at 12:30: the 08:00 plan meets {eight_at_lunch:.4} on average, the 12:30 plan {lunch_at_lunch:.4}"
    );
    assert!(lunch_at_lunch < eight_at_lunch);
}
