//! Which way people walk: a flow map per cell, scored on held-out directions (issue 48).
//!
//! `cargo run --release --example flow_map -- --trajectories <file> [--test <file>]
//!  [--format eth|txy] [--resolution M] [--min-samples N] [--min-speed V] [--hold-out S]
//!  [--map-xml <file>|--no-map-xml|--map <ros.yaml>] [--plan-resolution M] [--crossings N]
//!  [--crossing-radius M] [--flow-weight W|auto]`
//!
//! Steps: read the trajectories as `ta_map` does (`eth`: an ETH/OpenTraj `obsmat.txt`;
//! `txy`: whitespace columns `time id x y`; malformed lines skipped and counted, and one bad
//! row is skipped, not fatal: samples far from the bulk of the file's samples or not finite
//! are skipped by the bounds rule every reader of coordinates uses,
//! `haunts::occupancy::bounds`, and counted in `"skipped_rows"`); seed 002's dummy filter
//! with α = `--min-samples` (5); observations by finite differences of consecutive samples
//! (`haunts::affordance::flow::observations`; steps slower than `--min-speed`, 0.1 m/s, have
//! no direction and are dropped). Without `--test` the last `--hold-out` share in time (0.2)
//! is held out; with it, the test file is read the same way and all of its observations are
//! scored. The flow map (`FlowMap`, default parameters: 8 bins, cells pooling up to two rings
//! when they hold fewer than 5 observations) is fitted over the training observations' box
//! grown by 1 m at `--resolution` (1 m), and every held-out observation's heading is scored
//! by each form: the histogram, the semi-wrapped mixture, and the uniform direction `−ln 2π`.
//! `flow` is the form chosen on the training observations alone (fitted on their first part,
//! scored on their last `--hold-out` share in time; the better of the two); nothing is chosen
//! on the held-out data.
//!
//! **Over more than a day** of training observations, `timed_flow` is the flow at the time of
//! day (`TimedFlowMap`: each cell's direction bins' rates as FreMEn models over the day's
//! harmonics, STeF-map's reading, modulating the static form chosen above; its order 1–3
//! chosen on the training observations' own last `--hold-out` share), each held-out
//! observation scored at its time; `static_flow` is the
//! static form chosen as above, and `flow` whichever of the two scored better on the training
//! data's own last part (never chosen on the held-out data).
//!
//! **Plans** (issue 53): on a costmap of `--plan-resolution` (0.25 m) over the same box, free
//! but for the walls and poles of `map.xml` (beside the trajectory file unless `--map-xml`
//! names another or `--no-map-xml`; `--map` takes the occupied cells of a ROS map instead, as
//! `sim_people` writes the simulated office's), `--crossings` trips (12) across the cell of most
//! training traffic, one per direction over half a turn, `--crossing-radius` (5 m) either side
//! (`haunts::planning::crossings`), each planned by plain A* and by the flow-aware A*
//! (`FlowCostAStar`, no activity term, so that only the flow differs) on the training map's
//! opposing traffic (`FlowMap::against` over `max_traffic`, in `[0, 1]`: a metre head-on
//! against the busiest cell's people costs `1 + w` metres). The weight `w` is
//! `--flow-weight`, or with `auto` (the default) chosen on the training observations alone:
//! planned on the map of their first part and scored on their last `--hold-out` share, the
//! weight of 0.5, 1, 2, 4, 8, 16 with the least against-flow share whose plans are at most
//! 10 % longer on average. Each plan is scored
//! **on the held-out observations** (a flow map fitted on them alone, histogram only):
//! `against_flow_share`, the share of its length moving at more than 90° from the dominant
//! flow of the cells it enters, and `activity_mean`, the held-out traffic (observations per
//! cell of the flow grid) along it; `against_flow_share_train`, the same share on the map it
//! was planned on, is the lenient figure. `plans` holds the means over the trips with a path.
//!
//! The last line printed is one JSON object:
//! `{"flow":{"form":"histogram"|"mixture"|"timed histogram"|"timed mixture"[,"order":..],"loglik":..}
//! [,"static_flow":{"form":..,"loglik":..},"timed_flow":{"order":..,"loglik":..}],"histogram":{"loglik":..},"mixture":{"loglik":..},
//! "uniform_direction":{"loglik":..},"observations":{"train":..,"test":..,"test_outside_grid":..,
//! "dropped_steps":..},"cells":{"own":..,"pooled":..,"uniform":..},"trajectories":{"read":..,
//! "kept":..},"skipped_rows":{..},"seconds":{"fit":..},"plans":{"trips":..,"no_path":..,
//! "radius":..,"flow_weight":..,"flow_weight_chosen":..,"busiest":[x,y],"plain":{"length":..,"against_flow_share":..,
//! "against_flow_share_train":..,"activity_mean":..},"flow_aware":{..},"length_ratio":..,
//! "against_ratio":..}}`, log-likelihoods in nats per held-out observation of direction;
//! the ratios are flow-aware over plain.

use std::path::{Path, PathBuf};
use std::time::Instant;

use haunts::affordance::flow::{
    FlowForm, FlowMap, FlowObservation, FlowParams, TimedFlowMap, TimedFlowParams,
    UNIFORM_DIRECTION_LOGLIK, choose_order, hold_out_last, observations,
};
use haunts::affordance::hypertime::DAY;
use haunts::occupancy::GridGeometry;
use haunts::occupancy::bounds::RowCounts;
use haunts::pipeline::flow::{
    FLOW_WEIGHTS, FlowPlanParams, PlanFigures, choose_flow_weight, flow_plans,
};
use haunts::planning::{LayeredCostmap, StaticLayer};
use haunts::tracking::track::dummy::{DummyFilterParams, filter_dummies};

mod common;
use common::trajectories::{self, Format};

const USAGE: &str = "usage: flow_map --trajectories <file> [--test <file>] [--format eth|txy] \
                     [--resolution M] [--min-samples N] [--min-speed V] [--hold-out S] \
                     [--map-xml <file>|--no-map-xml|--map <ros.yaml>] [--plan-resolution M] [--crossings N] \
                     [--crossing-radius M] [--flow-weight W|auto]";

type Error = Box<dyn std::error::Error>;

#[derive(Debug)]
struct Args {
    trajectories: PathBuf,
    test: Option<PathBuf>,
    format: Format,
    resolution: f64,
    min_samples: usize,
    min_speed: f64,
    hold_out: f64,
    map_xml: Option<PathBuf>,
    /// A ROS map of the obstacles (`--map`), in place of `map.xml`.
    ros_map: Option<PathBuf>,
    plan_resolution: f64,
    crossings: usize,
    crossing_radius: f64,
    /// `None`: chosen on the training data (`auto`).
    flow_weight: Option<f64>,
}

fn parse_args() -> Result<Args, Error> {
    let mut args = std::env::args().skip(1);
    let (mut trajectories, mut test, mut format) = (None, None, Format::Eth);
    let (mut resolution, mut min_samples) = (1.0, 5);
    let (mut min_speed, mut hold_out): (f64, f64) = (0.1, 0.2);
    let (mut map_xml, mut no_map_xml, mut plan_resolution) = (None, false, 0.25);
    let mut ros_map = None;
    let (mut crossings, mut crossing_radius, mut flow_weight) = (12, 5.0, None);
    while let Some(a) = args.next() {
        let mut value = || args.next().ok_or(USAGE);
        match a.as_str() {
            "--trajectories" => trajectories = Some(PathBuf::from(value()?)),
            "--test" => test = Some(PathBuf::from(value()?)),
            "--format" => format = Format::parse(&value()?)?,
            "--resolution" => resolution = value()?.parse()?,
            "--min-samples" => min_samples = value()?.parse()?,
            "--min-speed" => min_speed = value()?.parse()?,
            "--hold-out" => hold_out = value()?.parse()?,
            "--map-xml" => map_xml = Some(PathBuf::from(value()?)),
            "--no-map-xml" => no_map_xml = true,
            "--map" => ros_map = Some(PathBuf::from(value()?)),
            "--plan-resolution" => plan_resolution = value()?.parse()?,
            "--crossings" => crossings = value()?.parse()?,
            "--crossing-radius" => crossing_radius = value()?.parse()?,
            "--flow-weight" => {
                flow_weight = match value()?.as_str() {
                    "auto" => None,
                    w => Some(w.parse::<f64>()?),
                }
            }
            _ => return Err(USAGE.into()),
        }
    }
    if !(hold_out > 0.0 && hold_out < 1.0) {
        return Err(format!("--hold-out must lie in (0, 1), found {hold_out}").into());
    }
    if !(min_speed.is_finite() && min_speed >= 0.0) {
        return Err(format!("--min-speed must be finite and ≥ 0, found {min_speed}").into());
    }
    let trajectories: PathBuf = trajectories.ok_or(USAGE)?;
    let map_xml = trajectories::map_xml_beside(&trajectories, map_xml, no_map_xml);
    Ok(Args {
        trajectories,
        test,
        format,
        resolution,
        min_samples,
        min_speed,
        hold_out,
        map_xml,
        ros_map,
        plan_resolution,
        crossings,
        crossing_radius,
        flow_weight,
    })
}

/// What one file gives: its observations, the trajectories read and kept, the steps dropped
/// and the rows skipped.
struct Read {
    observations: Vec<FlowObservation>,
    read: usize,
    kept: usize,
    dropped: usize,
    rows: RowCounts,
}

fn read(path: &Path, args: &Args) -> Result<Read, Error> {
    let (parsed, rows) = trajectories::read(path, args.format)?;
    let read = parsed.records.len();
    let filter = DummyFilterParams::default().with_min_samples(args.min_samples);
    let kept = filter_dummies(parsed.records, &filter)?.kept;
    let (observations, dropped) = observations(&kept, args.min_speed);
    Ok(Read {
        observations,
        read,
        kept: kept.len(),
        dropped,
        rows,
    })
}

fn loglik(map: &FlowMap, form: FlowForm, test: &[FlowObservation]) -> Result<f64, Error> {
    Ok(map
        .mean_log_likelihood(form, test)
        .ok_or("no held-out observation to score")?
        .0)
}

fn figures_json(f: &PlanFigures) -> String {
    format!(
        "{{\"length\":{:.4},\"against_flow_share\":{:.4},\"against_flow_share_train\":{:.4},\
         \"activity_mean\":{:.4}}}",
        f.length, f.against_flow_share, f.against_flow_share_planned, f.activity_mean
    )
}

/// Plain and flow-aware A* on trips across the busiest cell (see the module docs,
/// `haunts::pipeline::flow`): the `plans` object of the JSON line.
fn plans(
    args: &Args,
    train_map: &FlowMap,
    train: &[FlowObservation],
    test: &[FlowObservation],
) -> Result<String, Error> {
    // The costmap: the training observations' box grown by 1 m, free but for map.xml.
    let points: Vec<_> = train.iter().map(|o| o.position).collect();
    let geometry = GridGeometry::bounding(points.iter().copied(), args.plan_resolution, 1.0)?;
    let occupancy = match &args.ros_map {
        Some(yaml) => trajectories::ros_map_occupancy(geometry, yaml)?,
        None => trajectories::scene_occupancy(geometry, args.map_xml.as_deref(), &points)?,
    };
    let costmap = LayeredCostmap::new(geometry)
        .with_layer(StaticLayer::new(&occupancy, false))
        .build()?;
    let histogram = |seen: &[FlowObservation]| -> Result<FlowMap, Error> {
        let grid = GridGeometry::bounding(seen.iter().map(|o| o.position), args.resolution, 1.0)?;
        Ok(FlowMap::fit(
            seen,
            grid,
            &FlowParams::default().with_mixture(false),
        )?)
    };
    let params = FlowPlanParams::default().with_crossings(args.crossings, args.crossing_radius);
    let weight = match args.flow_weight {
        Some(w) => w,
        None => {
            // On the training observations alone: planned on their first part's map, scored
            // on their last `--hold-out` share's.
            let (inner_train, inner_test) = hold_out_last(train, args.hold_out);
            let (plan_map, score_map) = (histogram(&inner_train)?, histogram(&inner_test)?);
            let (w, tried) =
                choose_flow_weight(&costmap, &plan_map, &score_map, &FLOW_WEIGHTS, &params)?;
            for t in &tried {
                eprintln!(
                    "choosing the flow weight on the training data: {}: {:.1} % longer, \
                     {:.1} % against (plain {:.1} %)",
                    t.weight,
                    100.0 * (t.plans.length_ratio() - 1.0),
                    100.0 * t.plans.flow_aware.against_flow_share,
                    100.0 * t.plans.plain.against_flow_share
                );
            }
            w
        }
    };
    // Scored on the held-out observations alone.
    let p = flow_plans(&costmap, train_map, &histogram(test)?, weight, &params)?;
    eprintln!(
        "{} trips across {:.2}: plain {:.2} m, {:.1} % against; flow-aware (weight {weight}) \
         {:.2} m, {:.1} % against the held-out flow",
        p.trips,
        p.busiest,
        p.plain.length,
        100.0 * p.plain.against_flow_share,
        p.flow_aware.length,
        100.0 * p.flow_aware.against_flow_share
    );
    Ok(format!(
        "{{\"trips\":{},\"no_path\":{},\"radius\":{:.2},\"flow_weight\":{weight},\
         \"flow_weight_chosen\":{},\"busiest\":[{:.2},{:.2}],\"plain\":{},\"flow_aware\":{},\
         \"length_ratio\":{:.4},\"against_ratio\":{:.4}}}",
        p.trips,
        p.no_path,
        args.crossing_radius,
        args.flow_weight.is_none(),
        p.busiest.x,
        p.busiest.y,
        figures_json(&p.plain),
        figures_json(&p.flow_aware),
        p.length_ratio(),
        p.against_ratio()
    ))
}

fn run(args: &Args) -> Result<(), Error> {
    let train_file = read(&args.trajectories, args)?;
    let (mut rows, mut dropped) = (train_file.rows, train_file.dropped);
    let (mut read_n, mut kept_n) = (train_file.read, train_file.kept);
    let (train, test) = match &args.test {
        None => hold_out_last(&train_file.observations, args.hold_out),
        Some(path) => {
            let t = read(path, args)?;
            rows.far += t.rows.far;
            rows.non_finite += t.rows.non_finite;
            dropped += t.dropped;
            read_n += t.read;
            kept_n += t.kept;
            (train_file.observations, t.observations)
        }
    };
    if train.is_empty() || test.is_empty() {
        return Err(format!(
            "{} training and {} held-out observations: need some of each",
            train.len(),
            test.len()
        )
        .into());
    }
    // The form, chosen on the training observations alone: fitted on their first part and
    // scored on their last `--hold-out` share in time.
    let (inner_train, inner_test) = hold_out_last(&train, args.hold_out);
    let (form, inner_static) = if inner_train.is_empty() || inner_test.is_empty() {
        (FlowForm::default(), None)
    } else {
        let grid =
            GridGeometry::bounding(inner_train.iter().map(|o| o.position), args.resolution, 1.0)?;
        let inner = FlowMap::fit(&inner_train, grid, &FlowParams::default())?;
        let (h, m) = (
            loglik(&inner, FlowForm::Histogram, &inner_test)?,
            loglik(&inner, FlowForm::Mixture, &inner_test)?,
        );
        eprintln!("choosing the form on the training data: histogram {h:.4}, mixture {m:.4}");
        if m > h {
            (FlowForm::Mixture, Some(m))
        } else {
            (FlowForm::Histogram, Some(h))
        }
    };
    let clock = Instant::now();
    let grid = GridGeometry::bounding(train.iter().map(|o| o.position), args.resolution, 1.0)?;
    let map = FlowMap::fit(&train, grid, &FlowParams::default())?;
    let seconds = clock.elapsed().as_secs_f64();
    let outside = test
        .iter()
        .filter(|o| {
            grid.world_to_cell(o.position)
                .and_then(|c| grid.index(c))
                .is_none()
        })
        .count();
    let (h, m) = (
        loglik(&map, FlowForm::Histogram, &test)?,
        loglik(&map, FlowForm::Mixture, &test)?,
    );
    let (own, pooled, uniform) = map.source_counts();
    let plans = plans(args, &map, &train, &test)?;
    let (form_name, static_loglik) = match form {
        FlowForm::Histogram => ("histogram", h),
        FlowForm::Mixture => ("mixture", m),
    };
    // Over more than a day of training data, the flow at the time of day (its order chosen
    // on the training data's own last part), beside the static flow.
    let times = train.iter().map(|o| o.time);
    let span =
        times.clone().fold(f64::NEG_INFINITY, f64::max) - times.fold(f64::INFINITY, f64::min);
    let flow_json = match inner_static {
        Some(inner_static) if span > DAY => {
            // The rhythm modulates the static form chosen above.
            let params = TimedFlowParams::default().with_form(form);
            let (order, scores) = choose_order(
                &train,
                grid,
                &FlowParams::default(),
                &params,
                &[1, 2, 3],
                args.hold_out,
            )?;
            let inner_timed = scores.iter().map(|s| s.1).fold(f64::NEG_INFINITY, f64::max);
            eprintln!(
                "{:.1} days of training data: the flow at the time of day on their own last part \
                 (order, mean log-likelihood): {scores:?}; static {form_name} {inner_static:.4}",
                span / DAY
            );
            let timed = TimedFlowMap::fit(
                &train,
                grid,
                &FlowParams::default(),
                &params.with_order(order),
            )?;
            let (timed_loglik, _) = timed
                .mean_log_likelihood(&test)
                .ok_or("no held-out observation to score")?;
            eprintln!(
                "held out: flow at the time of day (order {order}) {timed_loglik:.4}, static \
                 ({form_name}) {static_loglik:.4} nats per observation"
            );
            // `flow` is the one the training data chose; `timed` is reported either way.
            let flow = if inner_timed > inner_static {
                format!(
                    "{{\"form\":\"timed {form_name}\",\"order\":{order},\"loglik\":{timed_loglik:.6}}}"
                )
            } else {
                format!("{{\"form\":\"{form_name}\",\"loglik\":{static_loglik:.6}}}")
            };
            format!(
                "\"flow\":{flow},\"static_flow\":{{\"form\":\"{form_name}\",\"loglik\":{static_loglik:.6}}},\
                 \"timed_flow\":{{\"order\":{order},\"loglik\":{timed_loglik:.6}}}"
            )
        }
        _ => format!("\"flow\":{{\"form\":\"{form_name}\",\"loglik\":{static_loglik:.6}}}"),
    };
    eprintln!(
        "{} training and {} held-out observations on {}×{} cells of {} m: histogram {h:.4}, \
         mixture {m:.4}, uniform {UNIFORM_DIRECTION_LOGLIK:.4} nats per observation",
        train.len(),
        test.len(),
        grid.width(),
        grid.height(),
        args.resolution
    );
    println!(
        "{}",
        haunts::json::finite_line(&format!(
            "{{{flow_json},\"histogram\":{{\"loglik\":{h:.6}}},\
         \"mixture\":{{\"loglik\":{m:.6}}},\"uniform_direction\":{{\"loglik\":{UNIFORM_DIRECTION_LOGLIK:.6}}},\
         \"observations\":{{\"train\":{},\"test\":{},\"test_outside_grid\":{outside},\"dropped_steps\":{dropped}}},\
         \"cells\":{{\"own\":{own},\"pooled\":{pooled},\"uniform\":{uniform}}},\
         \"trajectories\":{{\"read\":{read_n},\"kept\":{kept_n}}},\"skipped_rows\":{},\
         \"seconds\":{{\"fit\":{seconds:.4}}},\"plans\":{plans}}}",
            train.len(),
            test.len(),
            rows.json()
        ))
    );
    Ok(())
}

fn main() -> std::process::ExitCode {
    common::report(parse_args().and_then(|a| run(&a)))
}
