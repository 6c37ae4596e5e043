//! The four commands. Each returns the JSON object it reports, or the error that stopped it.

use std::path::{Path, PathBuf};

use haunts::affordance::{LayoutLibrary, RegisterParams, Registration};
use haunts::bag::msg::{PoseArray, PoseStamped, TfMessage};
use haunts::bag::{Bag, MapFrame, McapWriter, RecordingOptions, convert};
use haunts::figure::Report;
use haunts::occupancy::bounds::{BoundsRule, RowCounts, SkipReport};
use haunts::occupancy::recording::Recording;
use haunts::occupancy::{GridGeometry, Pose2};
use haunts::pipeline::results::ResultsMcap;
use haunts::pipeline::serve::{ServeParams, serve_layout};
use haunts::pipeline::{DayProcessor, PipelineParams, moved_recording};
use haunts::sim::{PatrolParams, SimParams, Simulator};
use haunts::tracking::eval::sequence::Sequence;
use nalgebra::Point2;
use serde_json::{Value, json};

use haunts::artifact::{Aligned, DayArtifact, LibraryMergeError, merge_into_file};

/// Any error of a command, with its message.
type Error = Box<dyn std::error::Error>;

/// Which tracker settings a day is processed with.
#[derive(Debug, Clone, Copy, clap::ValueEnum)]
pub enum Tuning {
    /// The tracking crate's defaults (a real laser's clutter).
    Real,
    /// The settings chosen on the simulated office (`haunts sim` bags).
    Sim,
}

/// `haunts day`.
#[derive(Debug, clap::Args)]
pub struct DayArgs {
    /// The recording: a `.bag`, an `.mcap`, or a folder of `leg_tracker` text files.
    recording: PathBuf,
    /// The day artifact to write.
    #[arg(short, long)]
    output: PathBuf,
    /// The day's label in the library (default: the recording's file name).
    #[arg(long)]
    label: Option<String>,
    #[command(flatten)]
    topics: TopicArgs,
    /// The frame of the robot's poses: a localiser's fixed frame above the odometry's in the
    /// transforms (`map` → `odom`, as AMCL and slam_toolbox publish it), whose transform is
    /// composed with the odometry; naming the odometry frame keeps raw odometry. Default:
    /// `map` when the recording's transforms link it to the odometry frame, else the
    /// odometry frame. The JSON's `frame` says which was used.
    #[arg(long)]
    fixed_frame: Option<String>,
    /// Bring the day into this layout library's frame and onto its cells: the day is
    /// processed in its own frame, its map registered onto the library's layouts (global
    /// registration, then ICP), and the day processed again on the library's cells with its
    /// odometry moved by the transform found. A day that does not register (too few inliers, a large residual,
    /// another building) is refused with a note and written in its own frame.
    #[arg(long, conflicts_with = "grid")]
    like: Option<PathBuf>,
    /// With `--like`: force the transform `X,Y,YAW` (metres, metres, radians: the day's
    /// odometry frame at its first scan, as a pose in the library's frame) instead of
    /// registering; it is measured (inliers, residual) but not judged.
    #[arg(long, requires = "like", value_parser = parse_pose, allow_hyphen_values = true)]
    pose: Option<Pose2>,
    /// Put the day on the grid `X0,Y0,WIDTH,HEIGHT` (metres, in the frame of the first scan's
    /// odometry); default: the odometry's box grown by `--margin`.
    #[arg(long, value_parser = parse_grid, allow_hyphen_values = true)]
    grid: Option<[f64; 4]>,
    /// Cell size, metres.
    #[arg(long, default_value_t = 0.1)]
    resolution: f64,
    /// How far beyond the odometry's box the default grid reaches, metres.
    #[arg(long, default_value_t = 12.0)]
    margin: f64,
    /// The tracker settings.
    #[arg(long, value_enum, default_value_t = Tuning::Real)]
    tuning: Tuning,
}

fn parse_grid(s: &str) -> Result<[f64; 4], String> {
    let v: Vec<f64> = s
        .split(',')
        .map(|x| x.trim().parse::<f64>().map_err(|e| format!("{x:?}: {e}")))
        .collect::<Result<_, _>>()?;
    match v.as_slice() {
        [x, y, w, h] if v.iter().all(|c| c.is_finite()) && *w > 0.0 && *h > 0.0 => {
            Ok([*x, *y, *w, *h])
        }
        _ => Err("expected X0,Y0,WIDTH,HEIGHT, finite, with WIDTH and HEIGHT > 0".into()),
    }
}

fn parse_pose(s: &str) -> Result<Pose2, String> {
    let v: Vec<f64> = s
        .split(',')
        .map(|x| x.trim().parse::<f64>().map_err(|e| format!("{x:?}: {e}")))
        .collect::<Result<_, _>>()?;
    match v.as_slice() {
        [x, y, yaw] if v.iter().all(|c| c.is_finite()) => {
            Ok(Pose2::new(nalgebra::Vector2::new(*x, *y), *yaw))
        }
        _ => Err("expected X,Y,YAW, finite (metres, metres, radians)".into()),
    }
}

/// The recording at `path`, its notes and its skipped odometry poses printed.
fn open_recording(path: &Path, args: &DayArgs) -> Result<(Recording, RowCounts), Error> {
    let (recording, skipped) = read_recording(path, args)?;
    for note in recording.notes() {
        eprintln!("note: {note}");
    }
    for line in skipped.describe(|i| format!("odometry pose {i}")) {
        eprintln!("note: {line}");
    }
    let mut counts = skipped.counts;
    counts.non_finite += recording
        .odometry()
        .map_or(0, |odometry| odometry.skipped_non_finite());
    Ok((recording, counts))
}

/// The recording at `path`, as the options say, without its odometry poses far from the rest
/// (the bounds rule, `haunts::occupancy::bounds`): one glitch is skipped, not a day over the
/// cell budget.
fn read_recording(path: &Path, args: &DayArgs) -> Result<(Recording, SkipReport), Error> {
    let recording = if path.is_dir() {
        let base = args.topics.base_frame.as_deref().unwrap_or("base_link");
        Sequence::read(path)?.to_recording("odom", base)?
    } else {
        let mut options = args.topics.options();
        if let Some(f) = &args.fixed_frame {
            options = options.with_map_frame(MapFrame::Named(f.clone()));
        }
        Bag::open(path)?.recording(&options)?
    };
    Ok(recording.without_far_poses(&BoundsRule::default())?)
}

/// The topic and frame flags of the commands that read a recording.
#[derive(Debug, clap::Args)]
pub struct TopicArgs {
    /// The `LaserScan` topic (default: the only one, or `/scan`).
    #[arg(long)]
    scan_topic: Option<String>,
    /// The `Odometry` topic (default: the only one, or `/odom`).
    #[arg(long)]
    odom_topic: Option<String>,
    /// The robot's frame (default: the odometry's child frame).
    #[arg(long)]
    base_frame: Option<String>,
}

impl TopicArgs {
    /// The recording options of the flags (`None`: chosen automatically).
    fn options(&self) -> RecordingOptions {
        let mut options = RecordingOptions::default();
        if let Some(t) = &self.scan_topic {
            options = options.with_scan_topic(t);
        }
        if let Some(t) = &self.odom_topic {
            options = options.with_odom_topic(t);
        }
        if let Some(f) = &self.base_frame {
            options = options.with_base_frame(f);
        }
        options
    }
}

/// `haunts day`: one recording → a day artifact (with `--like`, aligned onto a library).
pub fn day(args: &DayArgs) -> Result<Value, Error> {
    let (recording, skipped_rows) = open_recording(&args.recording, args)?;
    // The frame of the poses: the odometry's, or the map frame composed with it.
    let frame = recording.odom_frame().to_owned();
    let library = args.like.as_deref().map(LayoutLibrary::load).transpose()?;
    let geometry = match (&library, args.grid) {
        // In its own frame first, at the library's resolution: registration moves it.
        (Some(library), _) => {
            DayProcessor::geometry_for(&recording, library.geometry().resolution(), args.margin)?
        }
        (None, Some([x, y, w, h])) => {
            let cells = |len: f64| (len / args.resolution).ceil().max(1.0) as usize;
            GridGeometry::new(args.resolution, Point2::new(x, y), cells(w), cells(h))?
        }
        (None, None) => DayProcessor::geometry_for(&recording, args.resolution, args.margin)?,
    };
    let mut params = match args.tuning {
        Tuning::Real => PipelineParams::real_laser(),
        Tuning::Sim => PipelineParams::default(),
    };
    // The daily loop draws at its own resolution: the library's, or `--resolution`.
    params.resolution = geometry.resolution();
    let processor = DayProcessor::new(geometry, params)?;
    let output = processor.process(&recording)?;
    for s in output.skipped.iter().take(5) {
        eprintln!("note: scan {} skipped: {}", s.index, s.reason);
    }
    let label = args.label.clone().unwrap_or_else(|| {
        args.recording
            .file_name()
            .map_or_else(|| "day".into(), |n| n.to_string_lossy().into_owned())
    });
    let mut artifact =
        DayArtifact::from_output(output, label, args.recording.display().to_string());
    let mut refused = None;
    if let Some(library) = &library {
        match artifact.align(library, &RegisterParams::default(), args.pose.as_ref())? {
            Aligned::Moved {
                day, registration, ..
            } => {
                artifact = match redraw(args, library, &registration, params, &artifact) {
                    Ok(drawn) => drawn,
                    Err(e) => {
                        let note = format!(
                            "the day could not be drawn again on the library's cells ({e}): \
                             resampled onto them instead"
                        );
                        eprintln!("note: {note}");
                        let mut day = *day;
                        day.notes.push(note);
                        day
                    }
                };
            }
            Aligned::Refused(refusal) => {
                let note = format!(
                    "not aligned onto {}: {refusal}; the day is kept in its own frame and \
                     `haunts merge` will refuse it (force a transform with --pose X,Y,YAW)",
                    args.like
                        .as_deref()
                        .map_or_else(String::new, |p| p.display().to_string())
                );
                eprintln!("note: {note}");
                artifact.notes.push(note);
                refused = Some(refusal.to_string());
            }
        }
    }
    artifact.save(&args.output)?;
    let mut report = json!({
        "day": artifact.label,
        "output": args.output.display().to_string(),
        "scans": artifact.counts.scans,
        "skipped": artifact.counts.skipped,
        "skipped_rows": {"far": skipped_rows.far, "non_finite": skipped_rows.non_finite},
        "keyframes": artifact.counts.keyframes,
        "refused_matches": artifact.counts.refused_matches,
        "trajectories": artifact.trajectories.len(),
        "tracked_points": artifact.tracked.len(),
        "density_cells_known": artifact.density.known_cells(),
        "grid": grid_text(artifact.map.geometry()),
        "span_s": [artifact.span.0, artifact.span.1],
        "frame": frame,
    });
    if library.is_some() {
        report["alignment"] = artifact
            .alignment
            .as_ref()
            .map_or(Value::Null, alignment_json);
        report["refused"] = refused.map_or(Value::Null, Value::String);
    }
    Ok(report)
}

/// The day drawn again on `library`'s cells: its recording read anew with the odometry moved
/// by `registration` (`pipeline::moved_recording`) and processed there, so that its map,
/// density and tracks are rasterised once in the library's frame instead of resampled (the
/// localiser matches in the frame of the odometry's first pose, so the corrections are the
/// same). Label, source and notes are `own`'s, the alignment is `registration`.
///
/// # Errors
/// A recording without odometry (nothing to move); the reader's and the daily loop's errors.
fn redraw(
    args: &DayArgs,
    library: &LayoutLibrary,
    registration: &Registration,
    params: PipelineParams,
    own: &DayArtifact,
) -> Result<DayArtifact, Error> {
    let (recording, _) = read_recording(&args.recording, args)?;
    let moved = moved_recording(recording, &registration.pose())?;
    let output = DayProcessor::new(*library.geometry(), params)?.process(&moved)?;
    let mut drawn = DayArtifact::from_output(output, own.label.clone(), own.source.clone());
    drawn.notes = own.notes.clone();
    drawn.notes.push(format!(
        "drawn on the library's cells with its odometry moved by ({:.3} m, {:.3} m, {:.4} rad)",
        registration.x, registration.y, registration.yaw
    ));
    drawn.alignment = Some(*registration);
    Ok(drawn)
}

/// `{"x", "y", "yaw", "inliers", "residual", "layout", "forced"}` of an alignment.
fn alignment_json(r: &Registration) -> Value {
    json!({
        "x": r.x,
        "y": r.y,
        "yaw": r.yaw,
        "inliers": r.inliers,
        "residual": r.residual,
        "layout": r.layout.0,
        "forced": r.forced,
    })
}

/// `X0,Y0,WIDTH,HEIGHT` of a geometry, as `--grid` reads it.
fn grid_text(g: &GridGeometry) -> String {
    let r = g.resolution();
    format!(
        "{},{},{},{}",
        g.origin().x,
        g.origin().y,
        g.width() as f64 * r,
        g.height() as f64 * r
    )
}

/// `haunts merge`.
#[derive(Debug, clap::Args)]
pub struct MergeArgs {
    /// The day artifacts.
    #[arg(required = true)]
    days: Vec<PathBuf>,
    /// The layout library: extended when it exists, created otherwise.
    #[arg(short, long)]
    output: PathBuf,
    /// How long to wait, in seconds, for another merge into the same library to finish
    /// before refusing (merges into one library run one at a time, so that none loses a day).
    #[arg(long, default_value_t = 60.0, value_name = "SECONDS")]
    wait: f64,
}

/// `haunts merge`: day artifacts → the layout library, saved once.
pub fn merge(args: &MergeArgs) -> Result<Value, Error> {
    // Every artifact is read before the library is touched: a corrupt one stops the merge
    // with the library as it was.
    let days = args
        .days
        .iter()
        .map(|p| DayArtifact::load(p).map(|a| (p.clone(), a)))
        .collect::<Result<Vec<_>, _>>()?;
    // One merge at a time into a library: the lock is held from before the load to after the
    // save (released when `_lock` drops, or when the process ends however it ends).
    if !(args.wait.is_finite() && (0.0..=1e6).contains(&args.wait)) {
        return Err(format!("--wait must be 0 to 1e6 seconds, found {}", args.wait).into());
    }
    let paths: Vec<PathBuf> = days.iter().map(|d| d.0.clone()).collect();
    let artifacts = days.into_iter().map(|d| d.1).collect();
    let merged = merge_into_file(
        &args.output,
        artifacts,
        haunts::artifact::library_params(),
        &RegisterParams::default(),
        std::time::Duration::from_secs_f64(args.wait),
    )
    .map_err(|e| -> Error {
        match e {
            LibraryMergeError::Busy { .. } => format!("{e} (give --wait SECONDS)").into(),
            e => e.into(),
        }
    })?;
    let (library, saved) = (merged.library, merged.saved);
    let merged = merged.report;
    let file = |index: usize| paths[index].display().to_string();
    for (index, label) in &merged.duplicates {
        eprintln!(
            "note: {}: day {label:?} is already in the library: skipped",
            file(*index)
        );
    }
    for r in &merged.refused {
        eprintln!("note: {}: refused: {}", file(r.index), r.reason);
    }
    for d in merged.ingested.iter().filter(|d| d.outside > 0) {
        eprintln!(
            "note: {}: {} occupied cells fell outside the library's grid",
            file(d.index),
            d.outside
        );
    }
    let ingested: Vec<Value> = merged
        .ingested
        .iter()
        .map(|d| {
            let mut day = json!({
                "day": d.label,
                "layout": d.layout.0,
                "new_layout": d.created,
            });
            // Only a day that was registered has an alignment (a day already on the
            // library's cells has none: the key is left out, never a null).
            if let Some(a) = &d.alignment {
                day["alignment"] = alignment_json(a);
            }
            day
        })
        .collect();
    let duplicates: Vec<&String> = merged.duplicates.iter().map(|d| &d.1).collect();
    let refused: Vec<Value> = merged
        .refused
        .iter()
        .map(|r| json!({"day": r.label, "file": file(r.index), "reason": r.reason}))
        .collect();
    Ok(json!({
        "library": args.output.display().to_string(),
        "saved": saved,
        "ingested": ingested,
        "duplicates": duplicates,
        "refused": refused,
        "layouts": library.layouts().len(),
        "days": library.layouts().iter().map(|l| l.days().len()).sum::<usize>(),
    }))
}

/// `haunts maps`.
#[derive(Debug, clap::Args)]
pub struct MapsArgs {
    /// The layout library.
    library: PathBuf,
    /// The folder of the maps (created).
    #[arg(short, long)]
    output: PathBuf,
    /// Day artifacts whose tracks draw each layout's flow (which way people walk): the days
    /// of the library (by label) that belong to it; days not in the library are skipped and
    /// counted.
    #[arg(long, num_args = 1.., value_name = "DAY")]
    days: Vec<PathBuf>,
}

/// `haunts maps`: per layout, `layout_N_composite.{yaml,pgm}` (trinary),
/// `layout_N_costmap.{yaml,pgm}` (raw: the costmap with the affordance layer, Nav2's
/// translation to occupancy values), the figure `layout_N_affordance.png` (axes in metres,
/// colour bar), `index.html` showing the figures with the library's figures as a table, and
/// `maps.mcap` with every layout's grids as `nav_msgs/OccupancyGrid` (topics
/// `/layout_N/composite`, `/layout_N/costmap` and `/layout_N/affordance`, frame `map`).
/// With `--days`, per layout the flow of its days' tracks too: a `FlowMap` of 1 m cells
/// over the library's grid (histogram, default parameters; steps under 0.1 m/s dropped), the
/// figure `layout_N_flow.png` (an arrow along the dominant direction of every cell standing
/// on its own observations with a tenth of the busiest cell's traffic, coloured by heading)
/// and `/layout_N/flow` (`visualization_msgs/MarkerArray`, the same arrows) in `maps.mcap`.
pub fn maps(args: &MapsArgs) -> Result<Value, Error> {
    let library = LayoutLibrary::load(&args.library)?;
    // The tracks of the days given, by label (every artifact read before anything is written).
    let mut tracks: std::collections::BTreeMap<String, Vec<haunts::tracking::Trajectory>> =
        std::collections::BTreeMap::new();
    for path in &args.days {
        let day = DayArtifact::load(path)?;
        tracks
            .entry(day.label)
            .or_default()
            .extend(day.trajectories);
    }
    let mut matched = 0;
    std::fs::create_dir_all(&args.output)?;
    let mut mcap = ResultsMcap::create(args.output.join("maps.mcap"))?;
    let mut report = Report::new(format!("haunts maps of {}", args.library.display()));
    let mut layouts = Vec::new();
    for layout in library.layouts() {
        let (id, days) = (layout.id().0, layout.days().len());
        let served = serve_layout(layout, &ServeParams::default())?;
        let file = |what: &str, ext: &str| format!("layout_{id}_{what}.{ext}");
        let path = |name: String| args.output.join(name);
        haunts::pipeline::serve::save_layout_maps(&args.output, id, &served)?;
        let figure = file("affordance", "png");
        served
            .figure(format!("Layout {id}: affordance ({days} days)"))
            .save(path(figure.clone()))?;
        mcap.layout(id, &served, 0.0)?;
        report = report
            .figure(figure, format!("Layout {id}'s affordance map (human hits / visits, colour to its 99th percentile) over its composite map"))
            .row(format!("layout {id} days"), days.to_string())
            .row(format!("layout {id} density scale"), format!("{:.4}", served.scale));
        let mut entry = json!({"layout": id, "days": days, "density_scale": served.scale});
        if !args.days.is_empty() {
            let mine: Vec<haunts::tracking::Trajectory> = layout
                .days()
                .iter()
                .filter_map(|d| tracks.get(&d.label))
                .inspect(|_| matched += 1)
                .flatten()
                .cloned()
                .collect();
            let (seen, _) = haunts::affordance::flow::observations(&mine, 0.1);
            let grid = library.geometry().with_resolution(1.0)?;
            let flow = haunts::affordance::flow::FlowMap::fit(
                &seen,
                grid,
                &haunts::affordance::flow::FlowParams::default().with_mixture(false),
            )?;
            let arrows = haunts::pipeline::flow::flow_arrows(&flow, 0.1);
            let figure = file("flow", "png");
            haunts::figure::MapFigure::new(format!("Layout {id}: which way people walk"))
                .walls(&served.map)
                .arrows(format!("flow ({} cells)", arrows.len()), &arrows)
                .save(path(figure.clone()))?;
            mcap.flow(&format!("/layout_{id}/flow"), 0.0, &arrows)?;
            report = report.figure(
                figure,
                format!("Layout {id}'s flow: the dominant direction of the people tracked on its days, per 1 m cell with a tenth of the busiest cell's traffic, coloured by heading"),
            );
            entry["flow"] = json!({"observations": flow.used(), "arrows": arrows.len()});
        }
        layouts.push(entry);
    }
    mcap.finish()?;
    report.write(&args.output)?;
    let mut out = json!({"output": args.output.display().to_string(), "layouts": layouts});
    if !args.days.is_empty() {
        // Days given whose label no layout holds.
        out["flow_days_not_in_library"] = json!(tracks.len().saturating_sub(matched));
    }
    Ok(out)
}

/// The most days `haunts sim` simulates in one run (as the `pipeline` example).
const MAX_SIM_DAYS: usize = 10_000;

/// `haunts sim`.
#[derive(Debug, clap::Args)]
pub struct SimArgs {
    /// Days to simulate (1 to 10 000).
    #[arg(long, default_value_t = 5)]
    days: usize,
    /// The folder of the bags (created).
    #[arg(short, long)]
    output: PathBuf,
    /// The simulation's seed.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Patrols a day (three minutes each, every two hours from 8:30).
    #[arg(long, default_value_t = 5)]
    patrols: usize,
    /// Start each day's odometry at a random pose, as a robot switched on somewhere else
    /// each day (the JSON lists each day's start: its odometry frame in the office's frame);
    /// `haunts day --like` or `haunts merge` then register the days onto one another.
    #[arg(long)]
    random_start: bool,
}

/// `haunts sim`: `day_NNN.mcap` per day: `/scan` (`sensor_msgs/LaserScan`, frame `laser`),
/// `/odom` (`nav_msgs/Odometry`, `odom` → `base_link`, drifting), `/tf_static` (`base_link`
/// → `laser`), and the ground truth on its own topics, frame `map`: `/ground_truth/pose`
/// (`geometry_msgs/PoseStamped`, the robot) and `/ground_truth/people`
/// (`geometry_msgs/PoseArray`, the people at each scan).
pub fn sim(args: &SimArgs) -> Result<Value, Error> {
    if !(1..=MAX_SIM_DAYS).contains(&args.days) {
        return Err(format!("--days {} must be from 1 to {MAX_SIM_DAYS}", args.days).into());
    }
    let patrol = PatrolParams::sessions(8.5 * 3600.0, 180.0, 7200.0, args.patrols);
    let sim = Simulator::new(
        SimParams::default()
            .with_seed(args.seed)
            .with_patrol(patrol)
            .with_random_start(args.random_start),
    )?;
    std::fs::create_dir_all(&args.output)?;
    let (mut files, mut starts) = (Vec::new(), Vec::new());
    for index in 0..args.days {
        let day = sim.day(index)?;
        let f = day.odometry_frame;
        starts.push(json!({"x": f.translation.x, "y": f.translation.y, "yaw": f.rotation.angle()}));
        let path = args.output.join(format!("day_{index:03}.mcap"));
        let mut bag = McapWriter::create(&path)?;
        let first = day.scans.first().map_or(day.midnight, |s| s.stamp);
        let mount = convert::transform_msg(first, "base_link", "laser", &Pose2::identity());
        bag.write(
            "/tf_static",
            first,
            &TfMessage {
                transforms: vec![mount],
            },
        )?;
        for (i, scan) in day.scans.iter().enumerate() {
            let t = scan.stamp;
            bag.write("/scan", t, &convert::laser_scan_msg(scan, "laser"))?;
            let odometry = convert::odometry_msg(t, "odom", "base_link", &day.odometry[i]);
            bag.write("/odom", t, &odometry)?;
            let truth = PoseStamped {
                header: convert::header(t, "map"),
                pose: convert::pose_msg(&day.poses[i]),
            };
            bag.write("/ground_truth/pose", t, &truth)?;
            let people = PoseArray {
                header: convert::header(t, "map"),
                poses: day.people[i]
                    .iter()
                    .map(|p| convert::pose_msg(&Pose2::new(p.position.coords, 0.0)))
                    .collect(),
            };
            bag.write("/ground_truth/people", t, &people)?;
        }
        bag.finish()?;
        files.push(path.display().to_string());
    }
    let note = if args.random_start {
        "each day starts at its own pose: process the days on their own grids and merge them \
         (or pass `--like LIBRARY` to `haunts day`); `starts` are the truth"
    } else {
        "pass the grid to `haunts day --grid` so that every day lies on the same cells"
    };
    Ok(json!({
        "bags": files,
        "grid": grid_text(&sim.geometry()),
        "starts": starts,
        "note": note,
    }))
}

/// `haunts replay`.
#[derive(Debug, clap::Args)]
pub struct ReplayArgs {
    /// The recording: a `.bag` or an `.mcap`.
    recording: PathBuf,
    /// The MCAP to write what a node would publish (not with `--dds`).
    #[arg(short, long, required_unless_present = "dds", conflicts_with = "dds")]
    output: Option<PathBuf>,
    /// Publish the recording onto its topics over DDS instead (ROS 2, domain
    /// `ROS_DOMAIN_ID`), with `/clock`, for a node to track: `haunts node --use-sim-time`.
    #[arg(long)]
    dds: bool,
    /// With `--dds`: log seconds per second (2: twice the recording's pace).
    #[arg(long, default_value_t = 1.0, requires = "dds")]
    rate: f64,
    /// With `--dds`: how long to wait, in seconds, for a subscriber on every topic first.
    #[arg(long, default_value_t = 10.0, value_name = "SECONDS", requires = "dds")]
    subscriber_wait: f64,
    /// A layout library whose layouts' costmaps are published first
    /// (`nav_msgs/OccupancyGrid` on `/haunts/costmap/layout_N`, frame `map`: the library's).
    #[arg(long)]
    library: Option<PathBuf>,
    /// The annotated people's topic (`leg_tracker/msg/Person`; default: the only one, if any).
    #[arg(long)]
    ground_truth_topic: Option<String>,
    #[command(flatten)]
    topics: TopicArgs,
    /// Seconds a scan waits for its odometry and transforms.
    #[arg(long, default_value_t = 0.5)]
    window: f64,
    /// At the end, close the day as a robot would: the messages the session accepted
    /// (spooled beside OUT as `OUT.day.mcap` while it ran) processed as `haunts day` does and
    /// merged into `--library` as `haunts merge` does (created when absent; the same lock and
    /// atomic save), and the new costmaps published.
    #[arg(long, requires = "library")]
    close_day: bool,
    /// With `--close-day`: how long to wait, in seconds, for another merge into the library.
    #[arg(long, default_value_t = 60.0, value_name = "SECONDS")]
    wait: f64,
    /// Play the recording this many times in a row (each pass later by its span), to watch a
    /// long session's memory.
    #[arg(long = "loop", default_value_t = 1, value_name = "N")]
    loops: usize,
}

/// The most passes `haunts replay --loop` plays.
const MAX_LOOPS: usize = 1000;

/// `haunts replay`: a recording through a live session message by message in log-time order
/// (`haunts::live`), and what a node would publish to an MCAP: per tracked scan the people as
/// `geometry_msgs/PoseArray` on `/haunts/people` and `visualization_msgs/MarkerArray` on
/// `/haunts/people_markers`, in the odometry frame (logged at the scan's arrival).
pub fn replay(args: &ReplayArgs) -> Result<Value, Error> {
    use haunts::live::replay::Replay;
    use haunts::live::{LiveParams, LiveSession};
    use haunts::tracking::detect::static_map::StaticMapParams;
    use haunts::tracking::eval::sequence::EvalParams;

    let options = args.topics.options();
    let output = match &args.output {
        Some(output) => output,
        None if args.dds => {
            return crate::ros2::replay_dds(
                &args.recording,
                &options,
                args.rate,
                args.subscriber_wait,
            );
        }
        None => return Err("replay needs --output or --dds".into()),
    };
    if !(1..=MAX_LOOPS).contains(&args.loops) {
        return Err(format!("--loop {} must be from 1 to {MAX_LOOPS}", args.loops).into());
    }
    let replay = Replay::new(
        Bag::open(&args.recording)?,
        &options,
        args.ground_truth_topic.as_deref(),
    )?;
    for note in replay.bag().notes().iter().chain(replay.notes()) {
        eprintln!("note: {note}");
    }
    let mut session =
        LiveSession::with_defaults(replay.params(LiveParams::default().with_window(args.window)))?;
    if args.close_day && !(args.wait.is_finite() && (0.0..=1e6).contains(&args.wait)) {
        return Err(format!("--wait must be 0 to 1e6 seconds, found {}", args.wait).into());
    }
    if args.close_day {
        session = session.with_spool(output.with_extension("day.mcap"))?;
    }
    let mut out = McapWriter::create(output)?;
    let mut costmaps = 0;
    if let Some(path) = args
        .library
        .as_ref()
        .filter(|p| !args.close_day || p.exists())
    {
        let library = LayoutLibrary::load(path)?;
        for layout in library.layouts() {
            let served = serve_layout(layout, &ServeParams::default())?;
            publish_costmap(&mut out, layout.id().0, &served, 0.0)?;
            costmaps += 1;
        }
    }
    let odometry = replay.topics().odom.is_some();
    let fixed = replay.fixed_frame().to_owned();
    let mut people_messages = 0;
    let start = std::time::Instant::now();
    let replayed = replay.run_looped(&mut session, args.loops, |scan| {
        let frame = if odometry {
            fixed.as_str()
        } else {
            scan.frame.as_str()
        };
        let (poses, markers) = haunts::live::messages::people(scan, frame);
        out.write("/haunts/people", scan.received, &poses)
            .and_then(|()| out.write("/haunts/people_markers", scan.received, &markers))
            .map_err(haunts::pipeline::PipelineError::from)?;
        people_messages += 1;
        Ok(())
    })?;
    let seconds = start.elapsed().as_secs_f64();
    let closed = match (&args.library, args.close_day) {
        (Some(library), true) => {
            let started = std::time::Instant::now();
            let wait = std::time::Duration::from_secs_f64(args.wait);
            let day = session.close_day(library, wait)?;
            let at = replayed.scan_times.last().copied().unwrap_or(0.0);
            for (id, served) in &day.maps {
                publish_costmap(&mut out, id.0, served, at)?;
            }
            let merged = &day.merge.report;
            Some(json!({
                "day": day.label,
                "messages": day.messages,
                "spool_failures": day.spool_failures,
                "layout": day.layout.map(|l| l.0),
                "new_layout": merged.ingested.first().map(|d| d.created),
                "refused": merged.refused.iter().map(|r| r.reason.clone()).collect::<Vec<_>>(),
                "saved": day.merge.saved,
                "layouts": day.merge.library.layouts().len(),
                "days": day.merge.library.layouts().iter().map(|l| l.days().len()).sum::<usize>(),
                "costmaps": day.maps.len(),
                "seconds": started.elapsed().as_secs_f64(),
            }))
        }
        _ => None,
    };
    out.finish()?;
    // The replay ends here: the next day's (empty) spool goes.
    let spool = session.spool_path().map(Path::to_path_buf);
    let (scans, tracked, dropped) = (session.scans(), session.tracked(), *session.dropped());
    drop(session);
    if let Some(spool) = spool {
        let _ = std::fs::remove_file(spool);
    }
    let mut report = json!({
        "recording": args.recording.display().to_string(),
        "output": output.display().to_string(),
        "loops": args.loops,
        "scans": scans,
        "tracked_scans": tracked,
        "people_messages": people_messages,
        "costmaps": costmaps,
        "dropped": dropped,
        "undecodable_messages": replayed.undecodable,
        "messages": replayed.messages,
        "latency_ms": latency_ms(&replayed.latency),
        "seconds": seconds,
        "real_time_factor": replayed.span / seconds.max(1e-9),
    });
    if let Some(closed) = closed {
        report["closed_day"] = closed;
    }
    let mut left_out = serde_json::Map::new();
    match peak_rss_mb() {
        Some(mb) => report["peak_rss_mb"] = json!(mb),
        None => {
            left_out.insert(
                "peak_rss_mb".into(),
                json!("no /proc/self/status VmHWM here"),
            );
        }
    }
    let protocol =
        EvalParams::leg_tracker_benchmarks().with_static_map(Some(StaticMapParams::default()));
    match replayed.scores(&protocol) {
        Ok(Some((every, annotated))) => {
            report["mota_every_scan"] = mot_json(&every.scores);
            report["mota_annotated"] = mot_json(&annotated.scores);
        }
        Ok(None) => {
            for key in ["mota_every_scan", "mota_annotated"] {
                left_out.insert(key.into(), json!("no ground truth in the recording"));
            }
        }
        Err(e) => {
            for key in ["mota_every_scan", "mota_annotated"] {
                left_out.insert(key.into(), json!(e.to_string()));
            }
        }
    }
    if !left_out.is_empty() {
        report["left_out"] = Value::Object(left_out);
    }
    Ok(report)
}

/// A layout's costmap (static map, inflation, affordance layer) on
/// `/haunts/costmap/layout_ID`, frame `map` (the library's), logged at `seconds`.
fn publish_costmap(
    out: &mut McapWriter,
    id: usize,
    served: &haunts::pipeline::serve::ServedLayout,
    seconds: f64,
) -> Result<(), Error> {
    let grid = served.with_layer.to_occupancy_grid();
    let topic = format!("/haunts/costmap/layout_{id}");
    out.write(
        &topic,
        seconds,
        &convert::occupancy_grid_msg(&grid, seconds, "map"),
    )?;
    Ok(())
}

/// CLEAR MOT as `eval_tracking` prints it: the same keys, MOTA and MOTP to four decimals.
fn mot_json(c: &haunts::tracking::eval::mot::ClearMot) -> Value {
    // `eval_tracking`'s `{:.4}`, read back: the same digits.
    let four = |v: f64| format!("{v:.4}").parse::<f64>().unwrap_or(v);
    json!({
        "mota": four(c.mota),
        "motp": four(c.motp),
        "misses": c.misses,
        "false_positives": c.false_positives,
        "id_switches": c.id_switches,
        "objects": c.ground_truth,
    })
}

/// The per-scan latencies' median, 99th percentile (nearest rank) and maximum, milliseconds;
/// `null` without a tracked scan.
fn latency_ms(seconds: &[f64]) -> Value {
    let mut ms: Vec<f64> = seconds.iter().map(|s| s * 1e3).collect();
    ms.sort_by(f64::total_cmp);
    let rank = |q: f64| {
        let k = ((q * ms.len() as f64).ceil() as usize).clamp(1, ms.len());
        ms[k - 1]
    };
    match ms.last() {
        Some(&max) => json!({"p50": rank(0.5), "p99": rank(0.99), "max": max}),
        None => Value::Null,
    }
}

/// The process's peak resident set, MiB (Linux: `VmHWM` of `/proc/self/status`).
fn peak_rss_mb() -> Option<f64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb / 1024.0)
}
