//! Which way people walk: a flow map per cell, scored on held-out directions (issue 48).
//!
//! `cargo run --release --example flow_map -- --trajectories <file> [--test <file>]
//!  [--format eth|txy] [--resolution M] [--min-samples N] [--min-speed V] [--hold-out S]`
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
//! The last line printed is one JSON object:
//! `{"flow":{"form":"histogram"|"mixture","loglik":..},"histogram":{"loglik":..},"mixture":{"loglik":..},
//! "uniform_direction":{"loglik":..},"observations":{"train":..,"test":..,"test_outside_grid":..,
//! "dropped_steps":..},"cells":{"own":..,"pooled":..,"uniform":..},"trajectories":{"read":..,
//! "kept":..},"skipped_rows":{..},"seconds":{"fit":..}}`, log-likelihoods in nats per
//! held-out observation of direction.

use std::path::{Path, PathBuf};
use std::time::Instant;

use haunts::affordance::flow::{
    FlowForm, FlowMap, FlowObservation, FlowParams, UNIFORM_DIRECTION_LOGLIK, hold_out_last,
    observations,
};
use haunts::occupancy::GridGeometry;
use haunts::occupancy::bounds::RowCounts;
use haunts::tracking::track::dummy::{DummyFilterParams, filter_dummies};

mod common;
use common::trajectories::{self, Format};

const USAGE: &str = "usage: flow_map --trajectories <file> [--test <file>] [--format eth|txy] \
                     [--resolution M] [--min-samples N] [--min-speed V] [--hold-out S]";

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
}

fn parse_args() -> Result<Args, Error> {
    let mut args = std::env::args().skip(1);
    let (mut trajectories, mut test, mut format) = (None, None, Format::Eth);
    let (mut resolution, mut min_samples) = (1.0, 5);
    let (mut min_speed, mut hold_out): (f64, f64) = (0.1, 0.2);
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
            _ => return Err(USAGE.into()),
        }
    }
    if !(hold_out > 0.0 && hold_out < 1.0) {
        return Err(format!("--hold-out must lie in (0, 1), found {hold_out}").into());
    }
    if !(min_speed.is_finite() && min_speed >= 0.0) {
        return Err(format!("--min-speed must be finite and ≥ 0, found {min_speed}").into());
    }
    Ok(Args {
        trajectories: trajectories.ok_or(USAGE)?,
        test,
        format,
        resolution,
        min_samples,
        min_speed,
        hold_out,
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
    let form = if inner_train.is_empty() || inner_test.is_empty() {
        FlowForm::default()
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
            FlowForm::Mixture
        } else {
            FlowForm::Histogram
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
    let (form_name, flow) = match form {
        FlowForm::Histogram => ("histogram", h),
        FlowForm::Mixture => ("mixture", m),
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
            "{{\"flow\":{{\"form\":\"{form_name}\",\"loglik\":{flow:.6}}},\"histogram\":{{\"loglik\":{h:.6}}},\
         \"mixture\":{{\"loglik\":{m:.6}}},\"uniform_direction\":{{\"loglik\":{UNIFORM_DIRECTION_LOGLIK:.6}}},\
         \"observations\":{{\"train\":{},\"test\":{},\"test_outside_grid\":{outside},\"dropped_steps\":{dropped}}},\
         \"cells\":{{\"own\":{own},\"pooled\":{pooled},\"uniform\":{uniform}}},\
         \"trajectories\":{{\"read\":{read_n},\"kept\":{kept_n}}},\"skipped_rows\":{},\
         \"seconds\":{{\"fit\":{seconds:.4}}}}}",
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
