//! An MCAP of a run's results, for Foxglove, Lichtblick or RViz (through `ros2 bag play`):
//! per layout its composite map, costmaps and affordance density as `nav_msgs/OccupancyGrid`,
//! tracks and planned paths as `nav_msgs/Path`, and densities by hour as a time series of
//! grids (one message per hour, logged at that hour). Everything is in frame `map`.

use std::path::Path;

use haunts_bag::{McapWriter, convert};
use haunts_occupancy::{Grid, OccupancyGrid, Pose2};
use haunts_tracking::io::trajectory::Trajectory;
use nalgebra::{Point2, Vector2};

use super::Result;
use super::serve::{ServedLayout, percentile};

/// The frame of every message.
pub(crate) const FRAME: &str = "map";

/// Writes a run's results into one MCAP file; [`ResultsMcap::finish`] completes it (an
/// unfinished file has no summary, but its messages are still readable).
///
/// ```
/// use haunts::pipeline::results::ResultsMcap;
/// let path = std::env::temp_dir().join(format!("haunts-results-doc-{}.mcap", std::process::id()));
/// let mut mcap = ResultsMcap::create(&path).unwrap();
/// mcap.path("/plan", 0.0, &[nalgebra::Point2::new(0.0, 0.0), nalgebra::Point2::new(1.0, 0.0)]).unwrap();
/// mcap.finish().unwrap();
/// let bag = haunts::bag::Bag::open(&path).unwrap();
/// assert_eq!(bag.topics().iter().filter(|t| t.name == "/plan").count(), 1);
/// # std::fs::remove_file(path).ok();
/// ```
#[derive(Debug)]
pub struct ResultsMcap {
    writer: McapWriter,
}

impl ResultsMcap {
    /// Creates (or truncates) the file at `path`.
    ///
    /// # Errors
    /// [`super::PipelineError::Bag`] if the file cannot be created.
    pub fn create(path: impl AsRef<Path>) -> Result<Self> {
        Ok(Self {
            writer: McapWriter::create(path)?,
        })
    }

    /// A served layout at time `seconds`: `/layout_N/composite` (trinary),
    /// `/layout_N/costmap` (with the affordance layer, Nav2's translation to 0–100) and
    /// `/layout_N/affordance` (the density, 100 at its 99th percentile, −1 where unknown).
    ///
    /// # Errors
    /// [`super::PipelineError::Bag`] if writing fails.
    pub fn layout(&mut self, id: usize, served: &ServedLayout, seconds: f64) -> Result<()> {
        let costmap = served.with_layer.to_occupancy_grid();
        self.occupancy(&format!("/layout_{id}/composite"), seconds, &served.map)?;
        self.occupancy(&format!("/layout_{id}/costmap"), seconds, &costmap)?;
        let top = percentile(&served.density, 0.99).unwrap_or(f64::MIN_POSITIVE);
        self.scalar(
            &format!("/layout_{id}/affordance"),
            seconds,
            &served.density,
            top,
        )
    }

    /// An occupancy grid on `topic` at `seconds`.
    ///
    /// # Errors
    /// [`super::PipelineError::Bag`] if writing fails.
    pub(crate) fn occupancy(
        &mut self,
        topic: &str,
        seconds: f64,
        grid: &OccupancyGrid,
    ) -> Result<()> {
        let message = convert::occupancy_grid_msg(grid, seconds, FRAME);
        Ok(self.writer.write(topic, seconds, &message)?)
    }

    /// A scalar grid (a density) on `topic` at `seconds`, `top` drawn as 100
    /// ([`convert::scalar_grid_msg`]). Called once an hour with the same `top`, it is a time
    /// series a viewer plays back.
    ///
    /// # Errors
    /// [`super::PipelineError::Bag`] if writing fails.
    pub fn scalar(&mut self, topic: &str, seconds: f64, grid: &Grid<f64>, top: f64) -> Result<()> {
        let message = convert::scalar_grid_msg(grid, top, seconds, FRAME);
        Ok(self.writer.write(topic, seconds, &message)?)
    }

    /// A planned path on `topic` at `seconds` (poses heading along the path).
    ///
    /// # Errors
    /// [`super::PipelineError::Bag`] if writing fails.
    pub fn path(&mut self, topic: &str, seconds: f64, points: &[Point2<f64>]) -> Result<()> {
        let poses: Vec<(f64, Pose2)> = points
            .iter()
            .enumerate()
            .map(|(i, p)| {
                let along = match points.get(i + 1) {
                    Some(next) => next - p,
                    None => i.checked_sub(1).map_or(Vector2::zeros(), |j| p - points[j]),
                };
                (seconds, Pose2::new(p.coords, along.y.atan2(along.x)))
            })
            .collect();
        let message = convert::path_msg(&poses, FRAME);
        Ok(self.writer.write(topic, seconds, &message)?)
    }

    /// Tracks on `topic`: one `nav_msgs/Path` per track, logged at its first sample, each
    /// pose stamped with its sample's time. Tracks with no sample are skipped.
    ///
    /// # Errors
    /// [`super::PipelineError::Bag`] if writing fails (a track's time before 0 s among them).
    pub fn tracks(&mut self, topic: &str, tracks: &[Trajectory]) -> Result<()> {
        for track in tracks {
            let Some(&(first, _)) = track.samples.first() else {
                continue;
            };
            let poses: Vec<(f64, Pose2)> = track
                .samples
                .iter()
                .map(|(t, p)| (*t, Pose2::translation(p.x, p.y)))
                .collect();
            self.writer
                .write(topic, first, &convert::path_msg(&poses, FRAME))?;
        }
        Ok(())
    }

    /// A flow field on `topic` at `seconds`: one `visualization_msgs/MarkerArray` of arrows
    /// `(tail, head)`, each in the colour of its heading
    /// ([`heading_rgb`](super::flow::heading_rgb)).
    ///
    /// # Errors
    /// [`super::PipelineError::Bag`] if writing fails.
    pub fn flow(
        &mut self,
        topic: &str,
        seconds: f64,
        arrows: &[(Point2<f64>, Point2<f64>)],
    ) -> Result<()> {
        let coloured: Vec<_> = arrows
            .iter()
            .map(|&(t, h)| {
                let d = h - t;
                (
                    t,
                    h,
                    super::flow::heading_rgb(d.y.atan2(d.x)).map(|v| v as f32),
                )
            })
            .collect();
        let message = convert::flow_markers(seconds, FRAME, &coloured);
        Ok(self.writer.write(topic, seconds, &message)?)
    }

    /// Completes the file (its summary and index).
    ///
    /// # Errors
    /// [`super::PipelineError::Bag`] if writing fails.
    pub fn finish(self) -> Result<()> {
        Ok(self.writer.finish()?)
    }
}
