//! A [`Study`] written for people: its figures, `index.html` with the summary as a table,
//! the run's MCAP, the layout library and the hypertime points (feature `figures`).

use std::io::Write as _;
use std::path::Path;
use std::time::Instant;

use haunts_affordance::{DensityMap, TimedPoint};
use haunts_occupancy::picture::ColorMap;
use haunts_occupancy::{Grid, GridGeometry};
use serde_json::Value;

use super::summary::clock;
use super::{HypertimeStudy, Study, Summary};
use crate::figure::{MapFigure, Report};
use crate::pipeline::results::ResultsMcap;
use crate::pipeline::serve::{ServeParams, percentile, serve_layout};
use crate::pipeline::{PipelineError, Result};

/// The hours of the day (after [`HypertimeStudy::midnight`]) the hypertime density is
/// written for: every hour in the MCAP, every second hour as a figure.
const HOURS: std::ops::Range<u32> = 8..19;

/// A flow field to draw: its file, caption, MCAP topic, log time and arrows.
type FlowField = (String, String, String, f64, Vec<crate::figure::Arrow>);

impl Study {
    /// The flow fields of the run (see [`Study::write`]): one per plan time (`hours` after
    /// midnight, written `times` as `HH:MM`) when the days' tracks span more than a day and
    /// the flow at a time of day beats the static histogram on their last fifth in time, else
    /// one static field.
    fn flow_fields(
        &self,
        tracks: &[haunts_tracking::Trajectory],
        hours: &[f64],
        times: &[String],
    ) -> Result<Vec<FlowField>> {
        use haunts_affordance::flow::{
            FlowMap, FlowParams, TimedFlowMap, TimedFlowParams, choose_order, observations,
        };
        let (seen, _) = observations(tracks, 0.1);
        let grid = self.layouts.library.geometry().with_resolution(1.0)?;
        let params = FlowParams::default().with_mixture(false);
        let (first, last) = seen
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), o| {
                (a.min(o.time), b.max(o.time))
            });
        let span = last - first;
        // The first day's midnight (UTC), where the plans' hours count from.
        let midnight = if first.is_finite() {
            first - first.rem_euclid(haunts_affordance::hypertime::DAY)
        } else {
            0.0
        };
        if span > haunts_affordance::hypertime::DAY {
            let (order, _) = choose_order(
                &seen,
                grid,
                &params,
                &TimedFlowParams::default(),
                &[0, 1, 2, 3],
                0.2,
            )?;
            if order > 0 {
                let timed = TimedFlowMap::fit(
                    &seen,
                    grid,
                    &params,
                    &TimedFlowParams::default().with_order(order),
                )?;
                return Ok(hours
                    .iter()
                    .zip(times)
                    .map(|(&hour, time)| {
                        let t = midnight + hour * 3600.0;
                        let tag = time.replace(':', "h");
                        (
                            format!("flow_{tag}.png"),
                            format!("Which way people walk at {time} (every day's tracks, FreMEn order {order})"),
                            format!("/flow/at_{}", time.replace(':', "_")),
                            t,
                            super::super::flow::flow_arrows_at(&timed, t, 0.1),
                        )
                    })
                    .collect());
            }
        }
        let map = FlowMap::fit(&seen, grid, &params)?;
        Ok(vec![(
            "flow.png".to_owned(),
            "Which way people walk (every day's tracks; the time of day did not help on their last fifth)".to_owned(),
            "/flow".to_owned(),
            midnight,
            super::super::flow::flow_arrows(&map, 0.1),
        )])
    }

    /// Writes the study into `dir` (created if missing) and returns its [`Summary`] with
    /// `out` (`dir`) and `seconds` (since `started`, before the report is written) set:
    ///
    /// - `layouts.haunts`: the layout library;
    /// - figures (PNG): each layout's affordance map, hypertime at 08:00, 10:00, … 18:00
    ///   (one colour scale), the TA map with the plain and activity-aware plans, its
    ///   confidence, the busiest layout's plans without and with its affordance layer over
    ///   the first day's tracks, and the trip planned at each time of `timed`;
    /// - `index.html` ([`Report`] titled `title`): the figures with captions and the summary
    ///   as a table;
    /// - `run.mcap` ([`ResultsMcap`]): each layout served (`/layout_N/…`), hypertime every
    ///   hour from 08:00 to 18:00 (`/hypertime`), every track (`/tracks`), the plans
    ///   (`/plan/plain`, `/plan/activity_aware`, `/plan/without_layer`,
    ///   `/plan/with_layer`, `/plan/at_HH_MM`) and the TA map (`/ta/activity`);
    /// - `hypertime_train.txt`, `hypertime_test.txt`: the hypertime points, one `time x y`
    ///   line each (the `hypertime` example reads them with `--cols 0,1,2`).
    ///
    /// # Errors
    /// [`PipelineError::Io`] if the folder or a text file cannot be written,
    /// [`PipelineError::Figure`] for a figure or the report, [`PipelineError::Bag`] for the
    /// MCAP, [`PipelineError::Affordance`] for the library; the errors of serving a layout
    /// ([`serve_layout`]).
    pub fn write(
        &self,
        dir: impl AsRef<Path>,
        title: impl Into<String>,
        started: Instant,
    ) -> Result<Summary> {
        let dir = dir.as_ref();
        std::fs::create_dir_all(dir).map_err(|source| PipelineError::Io {
            path: dir.to_path_buf(),
            source,
        })?;
        let mut summary = self.summary();
        let save = |figure: MapFigure<'_>, file: &str| figure.save(dir.join(file)).map(drop);
        let mut report = Report::new(title);
        self.layouts.library.save(dir.join("layouts.haunts"))?;
        let mut mcap = ResultsMcap::create(dir.join("run.mcap"))?;
        for layout in self.layouts.library.layouts() {
            let (id, served) = (
                layout.id().0,
                serve_layout(layout, &ServeParams::default())?,
            );
            mcap.layout(id, &served, 0.0)?;
            let file = format!("layout_{id}_affordance.png");
            let title = format!("Layout {id}: affordance ({} days)", layout.days().len());
            save(served.figure(title), &file)?;
            report = report.figure(file, format!("Layout {id}'s affordance map (human hits / visits, colour to its 99th percentile) over its composite map"));
        }

        let hyper = &self.hypertime;
        write_points(dir.join("hypertime_train.txt"), &hyper.train)?;
        write_points(dir.join("hypertime_test.txt"), &hyper.test)?;
        let (plans, ta) = (&self.plans, &self.ta);
        let (hours, top) = hourly(hyper, self.layouts.library.geometry());
        for (hour, time, density) in &hours {
            mcap.scalar("/hypertime", *time, density, top)?;
            if hour % 2 == 0 {
                let file = format!("hypertime_{hour:02}h.png");
                save(
                    MapFigure::new(format!("Hypertime at {hour:02}:00"))
                        .walls(&plans.map)
                        .scalar(density, "people density (1/m²)", ColorMap::Turbo)
                        .range(0.0, top),
                    &file,
                )?;
                let caption = format!(
                    "Seed 001's hypertime density at {hour:02}:00, fitted on the training days"
                );
                report = report.figure(file, caption);
            }
        }

        let times: Vec<String> = summary.plan_hours().map(|h| clock(h, ':')).collect();
        let timed = self.timed.plans.iter().zip(&times);
        if let (Some(last), Some(last_time)) = (self.timed.plans.last(), times.last()) {
            let title = format!(
                "The same trip planned at {}, over the {last_time} activity",
                times.join(" and at ")
            );
            let figure = timed.clone().fold(last.served.figure(title), |f, (p, t)| {
                f.path(format!("planned at {t}"), &p.plans.with_path)
            });
            save(figure, "plans_at_times.png")?;
            report = report.figure("plans_at_times.png", format!("A* with the busiest layout's affordance at {} as a costmap layer (the affordance modulated by the daily rhythm validated on held-out training days)", times.join(" and at ")));
        }
        save(
            MapFigure::new("TA map and plans across the room")
                .walls(&plans.map)
                .scalar(&ta.activity, "distinct people per session", ColorMap::Turbo)
                .path("plain A*", &plans.plain.points)
                .path("activity-aware A*", &plans.aware.points),
            "ta_map.png",
        )?;
        save(
            MapFigure::new("TA confidence")
                .walls(&plans.map)
                .scalar(&ta.confidence, "confidence", ColorMap::Viridis)
                .range(0.0, 1.0),
            "ta_confidence.png",
        )?;
        let busiest = self.layouts.most_frequent().map_or(0, |l| l.id().0);
        let first_tracks = self.days.first().map(|d| &d.output.trajectories[..]);
        save(
            MapFigure::new(format!(
                "Layout {busiest}: plans with its affordance layer, and the day-0 tracks"
            ))
            .walls(&plans.map)
            .tracks(
                first_tracks
                    .unwrap_or_default()
                    .iter()
                    .map(|t| t.samples.iter().map(|s| s.1)),
            )
            .path("A* without the layer", &plans.layer.without_path)
            .path("A* with the layer", &plans.layer.with_path),
            "plans.png",
        )?;
        report = report
            .figure("ta_map.png", format!("Seed 002's TA map of the {} kept tracks, with plain and activity-aware A* (θ = {:.3})", ta.kept, plans.threshold))
            .figure("ta_confidence.png", "The TA map's confidence, from the robot's keyframes")
            .figure("plans.png", "Seed 000's use: A* on the busiest layout without and with its affordance map as a costmap layer");

        let tracks: Vec<_> = self
            .days
            .iter()
            .flat_map(|d| d.output.trajectories.iter().cloned())
            .collect();
        mcap.tracks("/tracks", &tracks)?;
        // Which way people walk, from every day's tracks (issue 53): at the plans' times of
        // day when the flow at a time of day scores better than the static flow on the
        // tracks' own last fifth, else the static flow.
        let hours: Vec<f64> = summary.plan_hours().collect();
        for (file, caption, topic, seconds, arrows) in self.flow_fields(&tracks, &hours, &times)? {
            mcap.flow(&topic, seconds, &arrows)?;
            save(
                MapFigure::new(caption.clone())
                    .walls(&plans.map)
                    .arrows(format!("flow ({} cells)", arrows.len()), &arrows),
                &file,
            )?;
            report = report.figure(file, caption);
        }
        for (topic, plan) in [
            ("/plan/plain", &plans.plain.points),
            ("/plan/activity_aware", &plans.aware.points),
            ("/plan/without_layer", &plans.layer.without_path),
            ("/plan/with_layer", &plans.layer.with_path),
        ] {
            mcap.path(topic, 0.0, plan)?;
        }
        for (p, time) in timed {
            let topic = format!("/plan/at_{}", time.replace(':', "_"));
            mcap.path(&topic, 0.0, &p.plans.with_path)?;
        }
        let top = percentile(&ta.activity, 0.99).unwrap_or(1.0);
        mcap.scalar("/ta/activity", 0.0, &ta.activity, top)?;
        mcap.finish()?;

        summary.out = dir.display().to_string();
        summary.seconds = started.elapsed().as_secs_f64();
        // Serialising the summary into a JSON value cannot fail (its keys are strings).
        let rows = serde_json::to_value(&summary).map_or_else(|_| Vec::new(), |v| rows("", &v));
        rows.into_iter()
            .fold(report, |r, (name, value)| r.row(name, value))
            .write(dir)?;
        Ok(summary)
    }
}

/// The hypertime model of all days rasterised on `geometry` at each of [`HOURS`] after
/// [`HypertimeStudy::midnight`] (its prediction for that hour of the first training day),
/// as `(hour, UNIX time, density per m²)`, and the top of their common colour scale: the
/// largest 99.9th percentile ([`percentile`]).
fn hourly(study: &HypertimeStudy, geometry: &GridGeometry) -> (Vec<(u32, f64, Grid<f64>)>, f64) {
    let midnight = study.midnight();
    let hours: Vec<(u32, f64, Grid<f64>)> = HOURS
        .map(|h| {
            let time = midnight + f64::from(h) * 3600.0;
            (h, time, study.all.hypertime.at(time).rasterise(geometry))
        })
        .collect();
    let top = hours
        .iter()
        .filter_map(|(_, _, g)| percentile(g, 0.999))
        .fold(f64::MIN_POSITIVE, f64::max);
    (hours, top)
}

/// Writes `points` as text, one `time x y` line each.
fn write_points(path: impl AsRef<Path>, points: &[TimedPoint]) -> Result<()> {
    let path = path.as_ref();
    let io = |source| PipelineError::Io {
        path: path.to_path_buf(),
        source,
    };
    let mut file = std::io::BufWriter::new(std::fs::File::create(path).map_err(io)?);
    for p in points {
        writeln!(
            file,
            "{:.3} {:.4} {:.4}",
            p.time, p.position.x, p.position.y
        )
        .map_err(io)?;
    }
    file.flush().map_err(io)
}

/// The scalars of a JSON value as `(dotted.name, value)` rows of a report: objects and
/// arrays flattened (`per_layout.0.test`), numbers that are not integers to four decimals.
fn rows(prefix: &str, value: &Value) -> Vec<(String, String)> {
    let name = |k: &str| {
        if prefix.is_empty() {
            k.to_string()
        } else {
            format!("{prefix}.{k}")
        }
    };
    match value {
        Value::Object(map) => map.iter().flat_map(|(k, v)| rows(&name(k), v)).collect(),
        Value::Array(items) => items
            .iter()
            .enumerate()
            .flat_map(|(i, v)| rows(&name(&i.to_string()), v))
            .collect(),
        Value::Number(n) if n.is_f64() => vec![(
            prefix.to_string(),
            n.as_f64().map_or(n.to_string(), |v| format!("{v:.4}")),
        )],
        Value::String(text) => vec![(prefix.to_string(), text.clone())],
        other => vec![(prefix.to_string(), other.to_string())],
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_flatten_objects_and_arrays_and_round_fractions() {
        let value = serde_json::json!({
            "mota": 0.912_345_6,
            "days": 70,
            "own": "2/2",
            "per_layout": [{"test": 3, "ll": null}],
            "validated": true,
        });
        let rows = rows("", &value);
        let expected = [
            ("days", "70"),
            ("mota", "0.9123"),
            ("own", "2/2"),
            ("per_layout.0.ll", "null"),
            ("per_layout.0.test", "3"),
            ("validated", "true"),
        ];
        assert_eq!(
            rows,
            expected
                .iter()
                .map(|(k, v)| (k.to_string(), v.to_string()))
                .collect::<Vec<_>>()
        );
    }
}
