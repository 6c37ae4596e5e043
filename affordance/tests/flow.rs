//! The flow map (issue 48): two synthetic lanes recovered by both forms, the mixture's heading
//! density integrating to one over the circle, the histogram and its pooling against a plain
//! slow implementation, and bad input.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::f64::consts::{PI, TAU};

use haunts_affordance::AffordanceError;
use haunts_affordance::flow::{
    CellSource, FlowForm, FlowMap, FlowObservation, FlowParams, UNIFORM_DIRECTION_LOGLIK, bin_of,
    hold_out_last, observations,
};
use haunts_occupancy::GridGeometry;
use nalgebra::Point2;
use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};

mod common;
use common::walk;

fn gaussian(rng: &mut StdRng) -> f64 {
    let u1: f64 = rng.random::<f64>().max(1e-300);
    let u2: f64 = rng.random();
    (-2.0 * u1.ln()).sqrt() * (TAU * u2).cos()
}

/// Two lanes 20 m long: eastwards at 1.3 m/s over y ∈ [0, 2], westwards at 0.9 m/s over
/// y ∈ [4, 6], headings with 0.1 rad of noise, speeds with 0.1 m/s.
fn two_lanes(n: usize, seed: u64) -> Vec<FlowObservation> {
    let mut rng = StdRng::seed_from_u64(seed);
    (0..n)
        .map(|i| {
            let east = i % 2 == 0;
            let x = 20.0 * rng.random::<f64>();
            let (y, heading, speed) = if east {
                (2.0 * rng.random::<f64>(), 0.0, 1.3)
            } else {
                (4.0 + 2.0 * rng.random::<f64>(), PI, 0.9)
            };
            FlowObservation::new(
                i as f64,
                Point2::new(x, y),
                heading + 0.1 * gaussian(&mut rng),
                speed + 0.1 * gaussian(&mut rng),
            )
        })
        .collect()
}

fn lanes_grid() -> GridGeometry {
    GridGeometry::new(1.0, Point2::new(0.0, 0.0), 20, 6).unwrap()
}

#[test]
fn two_lanes_are_recovered_by_both_forms() {
    let map = FlowMap::fit(&two_lanes(4000, 1), lanes_grid(), &FlowParams::default()).unwrap();
    assert_eq!((map.used(), map.outside()), (4000, 0));
    // Against: walking east in the westbound lane meets nearly all of its traffic head-on,
    // walking west in it nobody; across, next to nobody.
    let max = map.max_traffic();
    assert!(max > 0.0);
    for x in [2.5, 10.5, 17.5] {
        let west_lane = Point2::new(x, 5.0);
        let t = map.traffic_at(west_lane);
        assert!(t > 0.5 * max, "{t} of {max}");
        assert!(map.against(west_lane, 0.0) > 0.9 * t);
        assert!(map.against(west_lane, PI) < 0.02 * t);
        assert!(map.against(west_lane, PI / 2.0) < 0.1 * t);
        assert!(map.against(Point2::new(x, 1.0), PI) > 0.9 * map.traffic_at(Point2::new(x, 1.0)));
    }
    assert_eq!(map.against(Point2::new(50.0, 1.0), 0.0), 0.0);
    assert_eq!(map.against(Point2::new(2.5, 5.0), f64::NAN), 0.0);
    for x in [0.5, 7.5, 19.5] {
        let (east, west) = (Point2::new(x, 1.0), Point2::new(x, 5.0));
        assert_eq!(map.dominant(east), Some(0.0));
        assert_eq!(map.dominant(west), Some(-PI));
        assert_eq!(map.source_at(east).unwrap().0, CellSource::Own);
        for (p, heading, speed) in [(east, 0.0, 1.3), (west, PI, 0.9)] {
            let mixture = map.mixture_at(p).unwrap();
            let main = mixture
                .iter()
                .max_by(|a, b| a.weight.total_cmp(&b.weight))
                .unwrap();
            let off = (main.heading - heading + PI).rem_euclid(TAU) - PI;
            assert!(off.abs() < 0.05, "{p}: heading {}", main.heading);
            assert!(
                (main.speed - speed).abs() < 0.05,
                "{p}: speed {}",
                main.speed
            );
            assert!((main.covariance[0].sqrt() - 0.1).abs() < 0.04, "{main:?}");
            assert!(main.weight > 0.9, "{mixture:?}");
        }
    }
    // The empty row between the lanes (y ∈ [2, 4]) pools the lanes one ring away.
    for y in [2.5, 3.5] {
        assert_eq!(
            map.source_at(Point2::new(10.5, y)).unwrap().0,
            CellSource::Rings(1)
        );
    }
    // Held-out observations of the same lanes: both forms far above the uniform direction,
    // the mixture (which resolves the 0.1 rad spread inside a 45° bin) above the histogram.
    let test = two_lanes(2000, 2);
    let h = map.mean_log_likelihood(FlowForm::Histogram, &test).unwrap();
    let m = map.mean_log_likelihood(FlowForm::Mixture, &test).unwrap();
    assert_eq!((h.1, m.1), (2000, 2000));
    assert!(h.0 > UNIFORM_DIRECTION_LOGLIK + 1.5, "histogram {h:?}");
    assert!(m.0 > h.0 + 0.3, "mixture {m:?} histogram {h:?}");
    // Against the flow: a westward walker in the eastward lane is unlikely.
    let p = Point2::new(5.5, 1.0);
    for form in [FlowForm::Histogram, FlowForm::Mixture] {
        assert!(map.log_density(form, p, 0.0) > map.log_density(form, p, PI) + 3.0);
    }
}

#[test]
fn the_heading_densities_integrate_to_one_over_the_circle() {
    let map = FlowMap::fit(&two_lanes(600, 3), lanes_grid(), &FlowParams::default()).unwrap();
    let steps = 20_000;
    for p in [
        Point2::new(3.5, 0.5),
        Point2::new(3.5, 2.5),
        Point2::new(12.5, 5.5),
        Point2::new(-5.0, 0.0), // outside: uniform
    ] {
        for form in [FlowForm::Histogram, FlowForm::Mixture] {
            // The midpoint rule on a periodic function converges geometrically; bins' edges
            // fall between midpoints.
            let mass: f64 = (0..steps)
                .map(|i| map.density(form, p, -PI + (i as f64 + 0.5) * TAU / steps as f64))
                .sum::<f64>()
                * TAU
                / steps as f64;
            assert!((mass - 1.0).abs() < 1e-9, "{form:?} at {p}: {mass}");
        }
        // Any heading, read modulo 2π.
        let d = map.density(FlowForm::Mixture, p, 0.3);
        assert!((map.density(FlowForm::Mixture, p, 0.3 + 2.0 * TAU) - d).abs() < 1e-12);
    }
    // Each component alone, wide or narrow.
    for c in map.mixture_at(Point2::new(3.5, 0.5)).unwrap() {
        let mass: f64 = (0..steps)
            .map(|i| c.heading_density(-PI + (i as f64 + 0.5) * TAU / steps as f64))
            .sum::<f64>()
            * TAU
            / steps as f64;
        assert!((mass - 1.0).abs() < 1e-9, "{c:?}: {mass}");
    }
}

/// The plain slow histogram: for each cell, the smallest ring radius whose square of cells
/// holds at least `min` observations, by looping over every observation; its counts per bin.
fn slow_counts(
    seen: &[FlowObservation],
    g: &GridGeometry,
    params: &FlowParams,
    cell: (usize, usize),
) -> Option<(usize, Vec<f64>)> {
    for r in 0..=params.rings {
        let mut counts = vec![0.0; params.bins];
        for o in seen {
            let Some(c) = g.world_to_cell(o.position) else {
                continue;
            };
            let (dx, dy) = (c.col.abs_diff(cell.0), c.row.abs_diff(cell.1));
            if dx.max(dy) <= r {
                // Bins centred on multiples of 2π/B, by angle arithmetic rather than rounding.
                let w = TAU / params.bins as f64;
                let b = (0..params.bins)
                    .min_by(|&a, &b| {
                        let da = ((o.heading - a as f64 * w + PI).rem_euclid(TAU) - PI).abs();
                        let db = ((o.heading - b as f64 * w + PI).rem_euclid(TAU) - PI).abs();
                        da.total_cmp(&db)
                    })
                    .unwrap();
                counts[b] += 1.0;
            }
        }
        if counts.iter().sum::<f64>() >= params.min_observations as f64 {
            return Some((r, counts));
        }
    }
    None
}

#[test]
fn the_histogram_matches_a_plain_slow_implementation() {
    let mut rng = StdRng::seed_from_u64(4);
    let g = GridGeometry::new(0.5, Point2::new(-2.0, 1.0), 13, 9).unwrap();
    for (bins, min, rings) in [(8, 5, 2), (12, 3, 1), (6, 8, 3), (8, 1, 0)] {
        // Clumps, so that some cells stand alone, some pool and some stay uniform; some
        // observations outside the grid.
        let seen: Vec<FlowObservation> = (0..300)
            .map(|i| {
                let (cx, cy) = [(-1.0, 2.0), (3.5, 4.5), (0.5, 4.0)][i % 3];
                FlowObservation::new(
                    0.0,
                    Point2::new(cx + 0.8 * gaussian(&mut rng), cy + 0.6 * gaussian(&mut rng)),
                    // Headings avoiding exact bin edges by a margin of rounding.
                    TAU * rng.random::<f64>() - PI,
                    1.0,
                )
            })
            .collect();
        let params = FlowParams::default()
            .with_bins(bins)
            .with_pooling(min, rings)
            .with_mixture(false);
        let map = FlowMap::fit(&seen, g, &params).unwrap();
        let mut kinds = [0; 3];
        for y in 0..g.height() {
            for x in 0..g.width() {
                let p = g.cell_center(haunts_occupancy::Cell::new(x, y));
                let (source, n) = map.source_at(p).unwrap();
                match slow_counts(&seen, &g, &params, (x, y)) {
                    None => {
                        assert_eq!((source, n), (CellSource::Uniform, 0));
                        kinds[2] += 1;
                        for h in [-3.0, 0.0, 2.0] {
                            assert_eq!(map.density(FlowForm::Histogram, p, h), 1.0 / TAU);
                            assert_eq!(map.against(p, h), 0.0);
                        }
                        assert_eq!(map.traffic_at(p), 0.0);
                    }
                    Some((r, counts)) => {
                        let expected = if r == 0 {
                            CellSource::Own
                        } else {
                            CellSource::Rings(r)
                        };
                        assert_eq!(source, expected, "cell ({x}, {y})");
                        kinds[usize::from(r > 0)] += 1;
                        let got: Vec<f64> = map
                            .counts_at(p)
                            .unwrap()
                            .iter()
                            .map(|&c| f64::from(c))
                            .collect();
                        assert_eq!(got, counts, "cell ({x}, {y})");
                        let total: f64 = counts.iter().sum();
                        assert_eq!(n as f64, total);
                        // The traffic: the pool's observations per cell of its window (clipped
                        // to the grid); against a heading: the bins' shares met head-on.
                        let side =
                            |c: usize, n: usize| (c + r).min(n - 1) + 1 - c.saturating_sub(r);
                        let window = (side(x, g.width()) * side(y, g.height())) as f64;
                        let traffic = total / window;
                        let got = map.traffic_at(p);
                        assert!(
                            (got - traffic).abs() <= 1e-6 * traffic,
                            "{got} vs {traffic}"
                        );
                        for h in [-3.0, -0.2, 0.0, 1.0, 2.9] {
                            let w = TAU / bins as f64;
                            let slow: f64 = counts
                                .iter()
                                .enumerate()
                                .map(|(b, c)| c / total * (-(b as f64 * w - h).cos()).max(0.0))
                                .sum::<f64>()
                                * traffic;
                            let fast = map.against(p, h);
                            assert!(
                                (fast - slow).abs() <= 1e-6 * slow.max(1e-9),
                                "{fast} vs {slow}"
                            );
                        }
                        for h in [-3.0, -0.2, 0.0, 1.0, 2.9] {
                            let a = bins as f64 * params.prior;
                            let b = bin_of(h, bins);
                            let slow = (counts[b] + params.prior) / (total + a) * bins as f64 / TAU;
                            let fast = map.density(FlowForm::Histogram, p, h);
                            assert!((fast - slow).abs() <= 1e-12 * slow, "{fast} vs {slow}");
                        }
                    }
                }
            }
        }
        if rings > 0 {
            assert!(
                kinds.iter().all(|&k| k > 0),
                "{bins} {min} {rings}: {kinds:?}"
            );
        }
    }
}

#[test]
fn observations_are_finite_differences_of_trajectories() {
    // 1 m in 0.4 s steps along x: 2.5 m/s east; then a standing person and a broken pair.
    let east = walk(1, (0.0, 0.0), (4.0, 0.0), 5);
    let north = walk(2, (1.0, 1.0), (1.0, 3.0), 3);
    let mut standing = walk(3, (2.0, 2.0), (2.0, 2.0), 4);
    standing.samples[2].1.x = f64::NAN;
    let (seen, dropped) = observations(&[east, north, standing], 0.1);
    assert_eq!((seen.len(), dropped), (4 + 2, 3));
    let first = seen[0];
    assert_eq!(first.position, Point2::new(0.5, 0.0));
    assert!((first.time - 0.2).abs() < 1e-12);
    assert!((first.speed - 2.5).abs() < 1e-12);
    assert_eq!(first.heading, 0.0);
    assert!((seen[4].heading - PI / 2.0).abs() < 1e-12);
    // Time not moving forward gives none.
    let mut back = walk(4, (0.0, 0.0), (1.0, 0.0), 3);
    back.samples[2].0 = back.samples[1].0;
    let (seen, dropped) = observations(&[back], 0.1);
    assert_eq!(dropped, 1);
    assert_eq!(
        seen,
        [FlowObservation::new(0.2, Point2::new(0.25, 0.0), 0.0, 1.25)]
    );
}

#[test]
fn bad_input_is_counted_or_a_typed_error() {
    let g = lanes_grid();
    let mut seen = two_lanes(200, 5);
    seen[0].position.x = f64::NAN;
    seen[1].heading = f64::INFINITY;
    seen[2].position = Point2::new(1e9, 0.0);
    let map = FlowMap::fit(&seen, g, &FlowParams::default()).unwrap();
    assert_eq!((map.used(), map.outside()), (197, 3));
    assert_eq!(
        map.density(FlowForm::Histogram, Point2::new(1.0, 1.0), f64::NAN),
        1.0 / TAU
    );
    // Nothing at all: every cell uniform, every score −ln 2π.
    let empty = FlowMap::fit(&[], g, &FlowParams::default()).unwrap();
    let (m, n) = empty
        .mean_log_likelihood(FlowForm::Mixture, &two_lanes(10, 6))
        .unwrap();
    assert_eq!(n, 10);
    assert!((m - UNIFORM_DIRECTION_LOGLIK).abs() < 1e-15);
    assert_eq!(empty.dominant(Point2::new(1.0, 1.0)), None);
    assert!(
        empty
            .mean_log_likelihood(FlowForm::Histogram, &[])
            .is_none()
    );
    for bad in [
        FlowParams::default().with_bins(1),
        FlowParams::default().with_pooling(0, 2),
        FlowParams::default().with_prior(f64::NAN),
        FlowParams::default().with_prior(0.0),
        FlowParams::default().with_max_components(0),
    ] {
        assert!(matches!(
            FlowMap::fit(&seen, g, &bad),
            Err(AffordanceError::InvalidParameter(_))
        ));
    }
}

#[test]
fn the_last_share_in_time_is_held_out() {
    let mut seen = two_lanes(100, 7);
    seen.reverse(); // given order kept, whatever it is
    seen[5].time = f64::NAN;
    let (train, test) = hold_out_last(&seen, 0.2);
    assert_eq!((train.len(), test.len()), (79, 20));
    let last_train = train.iter().map(|o| o.time).fold(f64::MIN, f64::max);
    assert!(test.iter().all(|o| o.time > last_train));
    assert!(train.windows(2).all(|w| w[0].time > w[1].time));
    assert_eq!(hold_out_last(&seen, 0.0).1.len(), 0);
    assert_eq!(hold_out_last(&seen, 1.0).0.len(), 0);
}

/// Issue 48's bar on the shared ETH sequences (skipped with a notice when absent), through the
/// calls `examples/flow_map.rs` makes: the dummy filter (α = 5), observations by finite
/// differences (0.1 m/s floor), the last 20 % in time held out, a 1 m grid over the training
/// observations' box + 1 m. Both forms beat the uniform direction by more than half a nat per
/// held-out observation.
#[test]
fn eth_directions_held_out_in_time_beat_the_uniform_direction() {
    use haunts_tracking::track::dummy::{DummyFilterParams, filter_dummies};
    use haunts_tracking::{EthOptions, read_eth};
    for sequence in ["seq_eth", "seq_hotel"] {
        let Some(path) = common::shared_data(&format!("trajectories/eth/{sequence}/obsmat.txt"))
        else {
            return;
        };
        let parsed = read_eth(path, &EthOptions::default()).unwrap();
        let filter = DummyFilterParams::default().with_min_samples(5);
        let kept = filter_dummies(parsed.records, &filter).unwrap().kept;
        let (seen, _) = observations(&kept, 0.1);
        let (train, test) = hold_out_last(&seen, 0.2);
        let grid = GridGeometry::bounding(train.iter().map(|o| o.position), 1.0, 1.0).unwrap();
        let map = FlowMap::fit(&train, grid, &FlowParams::default()).unwrap();
        for form in [FlowForm::Histogram, FlowForm::Mixture] {
            let (mean, n) = map.mean_log_likelihood(form, &test).unwrap();
            eprintln!("{sequence} {form:?}: {mean:.4} nats per observation over {n}");
            assert!(
                mean >= UNIFORM_DIRECTION_LOGLIK + 0.5,
                "{sequence} {form:?}: {mean}"
            );
        }
    }
}

/// Five days of a corridor 10 m long whose walkers go east in the morning (8–12 h) and west
/// in the afternoon (13–17 h), with heading noise; `per_hour` observations per hour.
fn rush_hours(days: usize, per_hour: usize, seed: u64) -> Vec<FlowObservation> {
    let mut rng = StdRng::seed_from_u64(seed);
    let mut seen = Vec::new();
    for day in 0..days {
        for hour in (8..12).chain(13..17) {
            for _ in 0..per_hour {
                let t = day as f64 * 86_400.0 + (hour as f64 + rng.random::<f64>()) * 3600.0;
                let heading = if hour < 12 { 0.0 } else { PI } + 0.2 * gaussian(&mut rng);
                let p = Point2::new(10.0 * rng.random::<f64>(), 2.0 * rng.random::<f64>());
                seen.push(FlowObservation::new(t, p, heading, 1.2));
            }
        }
    }
    seen.sort_by(|a, b| a.time.total_cmp(&b.time));
    seen
}

#[test]
fn flow_at_the_time_of_day_beats_the_static_flow_on_a_held_out_day() {
    use haunts_affordance::flow::{TimedFlowMap, TimedFlowParams, choose_order};
    let seen = rush_hours(5, 60, 53);
    let g = GridGeometry::new(1.0, Point2::origin(), 10, 2).unwrap();
    let flow = FlowParams::default().with_mixture(false);
    // The last day held out; the order chosen on the four days before it alone.
    let (train, test) = hold_out_last(&seen, 0.2);
    assert!(test.iter().all(|o| o.time >= 4.0 * 86_400.0));
    let (order, scores) = choose_order(
        &train,
        g,
        &flow,
        &TimedFlowParams::default(),
        &[0, 1, 2, 3],
        0.25,
    )
    .unwrap();
    assert_eq!(scores.len(), 4);
    assert!(order > 0, "{scores:?}");
    let timed = TimedFlowMap::fit(
        &train,
        g,
        &flow,
        &TimedFlowParams::default().with_order(order),
    )
    .unwrap();
    let static_map = FlowMap::fit(&train, g, &flow).unwrap();
    let (t, n) = timed.mean_log_likelihood(&test).unwrap();
    let (s, _) = static_map
        .mean_log_likelihood(FlowForm::Histogram, &test)
        .unwrap();
    assert_eq!(n, test.len());
    // Static: east or west, half and half, ≈ −ln 2 + the lane's noise; at the time of day
    // the map knows which.
    assert!(t > s + 0.4, "timed {t}, static {s}");
    // At 10:00 east is likely, at 15:00 west.
    let p = Point2::new(5.0, 1.0);
    let (morning, afternoon) = (
        4.0 * 86_400.0 + 10.0 * 3600.0,
        4.0 * 86_400.0 + 15.0 * 3600.0,
    );
    assert!(timed.density(p, 0.0, morning) > 5.0 * timed.density(p, PI, morning));
    assert!(timed.density(p, PI, afternoon) > 5.0 * timed.density(p, 0.0, afternoon));
}

#[test]
fn the_timed_rates_match_a_plain_slow_implementation() {
    use haunts_affordance::flow::{TimedFlowMap, TimedFlowParams};
    let seen = rush_hours(3, 20, 8);
    let g = GridGeometry::new(2.0, Point2::origin(), 5, 1).unwrap();
    // Every harmonic kept, so that nothing is chosen: the formula alone.
    let params = TimedFlowParams::default().with_harmonics(4).with_order(4);
    let flow = FlowParams::default().with_mixture(false).with_pooling(1, 0);
    let map = TimedFlowMap::fit(&seen, g, &flow, &params).unwrap();
    let span = seen.last().unwrap().time - seen[0].time;
    assert_eq!(map.span(), span);
    let bins = 8;
    for cell in 0..5 {
        let centre = Point2::new(2.0 * cell as f64 + 1.0, 1.0);
        let mine: Vec<&FlowObservation> = seen
            .iter()
            .filter(|o| (o.position.x / 2.0).floor() as usize == cell)
            .collect();
        let n = mine.len() as f64;
        for t in [
            3600.0 * 9.5,
            86_400.0 + 3600.0 * 14.2,
            2.0 * 86_400.0 + 3600.0 * 20.0,
        ] {
            let rate = |b: usize| {
                let of_bin: Vec<f64> = mine
                    .iter()
                    .filter(|o| bin_of(o.heading, bins) == b)
                    .map(|o| o.time)
                    .collect();
                let wave: f64 = (1..=4)
                    .map(|k| {
                        let w = TAU * k as f64 / 86_400.0;
                        let (c, s) = of_bin.iter().fold((0.0, 0.0), |(c, s), tj| {
                            (c + (w * tj).cos(), s + (w * tj).sin())
                        });
                        c * (w * t).cos() + s * (w * t).sin()
                    })
                    .sum();
                ((of_bin.len() as f64 + 2.0 * wave) / span).max(0.0)
            };
            let total: f64 = (0..bins).map(rate).sum();
            for h in [0.0, 1.0, PI] {
                let share = rate(bin_of(h, bins)) / total;
                let a = bins as f64 * 0.5;
                let slow = (n * share * bins as f64 / TAU + a / TAU) / (n + a);
                let fast = map.density(centre, h, t);
                assert!(
                    (fast - slow).abs() <= 1e-9 * slow,
                    "cell {cell} t {t} h {h}: {fast} vs {slow}"
                );
            }
        }
    }
}

#[test]
fn the_mixture_at_the_time_of_day_beats_the_static_mixture_and_integrates_to_one() {
    use haunts_affordance::flow::{TimedFlowMap, TimedFlowParams, choose_order};
    let seen = rush_hours(5, 60, 54);
    let g = GridGeometry::new(1.0, Point2::origin(), 10, 2).unwrap();
    let flow = FlowParams::default();
    let (train, test) = hold_out_last(&seen, 0.2);
    let params = TimedFlowParams::default().with_form(FlowForm::Mixture);
    let (order, scores) = choose_order(&train, g, &flow, &params, &[0, 1, 2], 0.25).unwrap();
    assert!(order > 0, "{scores:?}");
    let timed = TimedFlowMap::fit(&train, g, &flow, &params.with_order(order)).unwrap();
    let static_map = FlowMap::fit(&train, g, &flow).unwrap();
    let (t, _) = timed.mean_log_likelihood(&test).unwrap();
    let (s, _) = static_map
        .mean_log_likelihood(FlowForm::Mixture, &test)
        .unwrap();
    assert!(t > s + 0.3, "timed {t}, static {s}");
    // A density over the circle at any time: ∫ = 1 (trapezoids on 3 600 points).
    let p = Point2::new(4.5, 0.5);
    for hour in [9.0, 12.5, 15.0, 22.0] {
        let at = 4.0 * 86_400.0 + hour * 3600.0;
        let n = 3600;
        let integral: f64 = (0..n)
            .map(|k| timed.density(p, -PI + TAU * k as f64 / n as f64, at))
            .sum::<f64>()
            * TAU
            / n as f64;
        assert!((integral - 1.0).abs() < 2e-3, "{hour} h: {integral}");
    }
    // Order 0 is the static mixture, exactly.
    let zero = TimedFlowMap::fit(&train, g, &flow, &params.with_order(0)).unwrap();
    for o in &test[..40] {
        assert_eq!(
            zero.density(o.position, o.heading, o.time),
            static_map.density(FlowForm::Mixture, o.position, o.heading)
        );
    }
}
