//! [`MapFrame`]: the robot's poses in a localiser's map frame (AMCL, slam_toolbox), by the
//! recording's map → odom transform composed with its odometry.

use std::path::Path;

use haunts_occupancy::{Link, Pose2, PoseHistory, TransformTree, frame_name};

use crate::{BagError, Result};

/// The frame the robot's poses of a [`Bag::recording`](crate::Bag::recording) are in.
///
/// A localiser (AMCL, slam_toolbox) publishes map → odom on `/tf`: the correction of the
/// odometry's drift. When the recording's transforms link a map frame to the odometry frame,
/// each odometry pose `odom ← base` becomes `map ← base = (map ← odom)(t) · (odom ← base)(t)`,
/// map → odom interpolated at the odometry's stamp `t` (held at its first or last transform
/// outside its time span; the notes count those stamps).
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub enum MapFrame {
    /// The frame `map` when the transforms link it to the odometry frame; raw odometry
    /// otherwise.
    #[default]
    Auto,
    /// This frame; a recording whose transforms do not link it to the odometry frame is
    /// [`BagError::NoMapFrame`](crate::BagError::NoMapFrame).
    Named(String),
    /// Raw odometry, whatever the transforms hold.
    Off,
}

impl MapFrame {
    /// The frame to look for: `map` for [`MapFrame::Auto`], none for [`MapFrame::Off`].
    pub(crate) fn frame(&self) -> Option<&str> {
        match self {
            Self::Auto => Some("map"),
            Self::Named(f) => Some(frame_name(f)),
            Self::Off => None,
        }
    }
}

/// The odometry (in `odom_frame`) placed in the map frame `choice` asks for, and the frame
/// its poses are then in; raw odometry and `odom_frame` when there is no map frame. The notes
/// say which frame was used and count the stamps held outside the map → odom span.
///
/// # Errors
/// [`BagError::NoMapFrame`] when a [`MapFrame::Named`] frame is not above `odom_frame` in
/// `tree`.
pub(crate) fn apply(
    choice: &MapFrame,
    tree: &TransformTree,
    odom_frame: &str,
    odometry: Option<PoseHistory>,
    path: &Path,
    notes: &mut Vec<String>,
) -> Result<(Option<PoseHistory>, String)> {
    let odom_frame = frame_name(odom_frame).to_owned();
    let Some(wanted) = choice.frame().filter(|f| *f != odom_frame) else {
        return Ok((odometry, odom_frame));
    };
    let link = format!("{wanted} → {odom_frame}");
    let Some(chain) = chain_up(tree, &odom_frame, wanted) else {
        if let MapFrame::Named(_) = choice {
            return Err(BagError::NoMapFrame {
                path: path.to_path_buf(),
                frame: wanted.to_owned(),
                odom_frame,
                seen: tree.frames().into_iter().map(str::to_owned).collect(),
            });
        }
        if tree.frames().contains(&wanted) {
            notes.push(format!(
                "frame {wanted} is in the transforms but not above {odom_frame}: poses stay in \
                 {odom_frame}"
            ));
        }
        return Ok((odometry, odom_frame));
    };
    let Some(raw) = odometry else {
        notes.push(format!(
            "{link} in the transforms, but no odometry to place"
        ));
        return Ok((None, odom_frame));
    };
    let Some(placed) = place(&raw, &chain) else {
        notes.push(format!(
            "{link}: no odometry pose composes; poses stay in {odom_frame}"
        ));
        return Ok((Some(raw), odom_frame));
    };
    let how = match choice {
        MapFrame::Auto => " (chosen automatically)",
        _ => "",
    };
    notes.push(format!(
        "poses in {wanted}: {link} of the transforms{how} composed with the odometry"
    ));
    let held = placed.held_before + placed.held_after;
    if let (Some((start, end)), true) = (placed.span, held > 0) {
        notes.push(format!(
            "{held} of {} odometry stamps outside the {link} span [{start:.3}, {end:.3}] s \
             ({} before, {} after): held at its first or last transform",
            raw.len(),
            placed.held_before,
            placed.held_after
        ));
    }
    if placed.skipped > 0 {
        notes.push(format!(
            "{link}: {} odometry poses skipped (did not compose)",
            placed.skipped
        ));
    }
    Ok((Some(placed.odometry), wanted.to_owned()))
}

/// The links from a frame up to one of its ancestors (child → parent, nearest first), or
/// `None` when the ancestor is not above it.
fn chain_up<'a>(tree: &'a TransformTree, from: &str, to: &str) -> Option<Vec<&'a Link>> {
    let (mut frame, to) = (frame_name(from), frame_name(to));
    let mut links = Vec::new();
    while frame != to {
        let (parent, link) = tree.parent(frame)?;
        links.push(link);
        frame = parent;
        // A tree has no cycle; the bound keeps a broken one finite.
        if links.len() > tree.frames().len() {
            return None;
        }
    }
    Some(links)
}

/// Odometry placed in a map frame.
#[derive(Debug)]
struct InMap {
    /// The base frame's poses in the map frame, at the odometry's stamps.
    odometry: PoseHistory,
    /// Odometry stamps before the span of the map → odom transform (held at its first one).
    held_before: usize,
    /// Odometry stamps after it (held at its last one).
    held_after: usize,
    /// The span of the moving links from odom to map (`None` when they are all static).
    span: Option<(f64, f64)>,
    /// Odometry samples whose map pose could not be composed (none expected: every stamp is
    /// held inside the span).
    skipped: usize,
}

/// `odometry` (odom ← base) composed with the links `chain` (odom up to map): the pose of the
/// base in the map frame at each odometry stamp. `None` when no sample composes.
fn place(odometry: &PoseHistory, chain: &[&Link]) -> Option<InMap> {
    let histories: Vec<&PoseHistory> = chain
        .iter()
        .filter_map(|l| match l {
            Link::Moving(h) => Some(h),
            Link::Static(_) => None,
        })
        .collect();
    let span = histories
        .iter()
        .map(|h| h.span())
        .reduce(|(a0, a1), (b0, b1)| (a0.max(b0), a1.min(b1)));
    let (mut held_before, mut held_after, mut skipped) = (0, 0, 0);
    let mut samples = Vec::with_capacity(odometry.len());
    for (t, pose) in odometry.samples() {
        match span {
            Some((start, _)) if t < start => held_before += 1,
            Some((_, end)) if t > end => held_after += 1,
            _ => {}
        }
        let map_from_odom = chain.iter().try_fold(Pose2::identity(), |acc, link| {
            let step = match link {
                Link::Static(s) => *s,
                Link::Moving(h) => {
                    let (start, end) = h.span();
                    h.pose_at(t.max(start).min(end)).ok()?
                }
            };
            Some(step * acc)
        });
        match map_from_odom {
            Some(m) => samples.push((t, m * pose)),
            None => skipped += 1,
        }
    }
    let odometry = PoseHistory::new(samples).ok()?;
    Some(InMap {
        odometry,
        held_before,
        held_after,
        span,
        skipped,
    })
}
