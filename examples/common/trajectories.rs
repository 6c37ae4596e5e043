//! Reading a pedestrian trajectory file as `ta_map` and `flow_map` do.

use std::path::Path;

use haunts::occupancy::bounds::{BoundsRule, RowCounts};
use haunts::occupancy::{FREE, GridGeometry, OCCUPIED, OccupancyGrid};
use haunts::tracking::{
    DelimitedOptions, EthOptions, Parsed, Trajectory, keep_near, read_delimited, read_eth,
};
use nalgebra::Point2;

type Error = Box<dyn std::error::Error>;

/// The trajectory file formats.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Format {
    /// An ETH/OpenTraj `obsmat.txt`.
    Eth,
    /// Whitespace columns `time id x y`.
    Txy,
}

impl Format {
    /// `eth` or `txy`.
    pub fn parse(name: &str) -> Result<Self, Error> {
        match name {
            "eth" => Ok(Self::Eth),
            "txy" => Ok(Self::Txy),
            other => Err(format!("unknown format `{other}`: eth or txy").into()),
        }
    }
}

/// The trajectories of the file: malformed lines skipped and counted, then samples far from
/// the bulk of all samples (or not finite) removed by the bounds rule, each reported on
/// standard error. Returns them with the samples skipped by reason.
pub fn read(path: &Path, format: Format) -> Result<(Parsed<Trajectory>, RowCounts), Error> {
    let mut parsed = match format {
        Format::Eth => read_eth(path, &EthOptions::default())?,
        Format::Txy => read_delimited(path, &DelimitedOptions::default())?,
    };
    super::report_malformed(path, &parsed);
    let kept = keep_near(std::mem::take(&mut parsed.records), &BoundsRule::default())?;
    for line in kept.skipped.describe(|i| format!("sample {i}")) {
        eprintln!("{}: {line}", path.display());
    }
    let mut rows = kept.skipped.counts;
    rows.non_finite += parsed.non_finite;
    parsed.records = kept.rows;
    Ok((parsed, rows))
}

/// The occupancy map on `geometry` from a ROS map (`yaml`, as `map_server` reads it): each
/// cell occupied where the map's cell at its centre is, free elsewhere (unknown and outside
/// included).
pub fn ros_map_occupancy(geometry: GridGeometry, yaml: &Path) -> Result<OccupancyGrid, Error> {
    let loaded = haunts::occupancy::load_map(yaml, &haunts::occupancy::MapLoadOptions::default())?;
    let values = (0..geometry.len())
        .filter_map(|i| geometry.cell_at(i))
        .map(|c| {
            let occupied = loaded
                .grid
                .geometry()
                .world_to_cell(geometry.cell_center(c))
                .and_then(|m| loaded.grid.state(m))
                == Some(haunts::occupancy::CellState::Occupied);
            if occupied { OCCUPIED } else { FREE }
        })
        .collect();
    eprintln!("{}: the walls and furniture of a ROS map", yaml.display());
    Ok(OccupancyGrid::from_values(geometry, values)?)
}

/// `map.xml` beside the trajectory file, unless `--map-xml` named one (`given`) or
/// `--no-map-xml` (`none`) asked for none.
pub fn map_xml_beside(
    trajectories: &Path,
    given: Option<std::path::PathBuf>,
    none: bool,
) -> Option<std::path::PathBuf> {
    match (none, given) {
        (true, _) => None,
        (false, Some(p)) => Some(p),
        (false, None) => trajectories
            .parent()
            .map(|d| d.join("map.xml"))
            .filter(|p| p.exists()),
    }
}

/// The occupancy map on `geometry`: free, with the walls and poles of `map_xml` (OpenTraj's
/// `map.xml`) drawn in when given; reported on standard error with how many of `samples` lie
/// on them.
pub fn scene_occupancy(
    geometry: GridGeometry,
    map_xml: Option<&Path>,
    samples: &[Point2<f64>],
) -> Result<OccupancyGrid, Error> {
    let mut map = OccupancyGrid::from_values(geometry, vec![FREE; geometry.len()])?;
    if let Some(path) = map_xml {
        let xml = std::fs::read_to_string(path)?;
        let scene = haunts::tracking::parse_scene_map(&xml)?;
        scene.draw(&mut map)?;
        let (lines, circles) = (scene.lines.len(), scene.circles.len());
        let blocked = samples
            .iter()
            .filter(|p| map.values().at_world(**p).is_some_and(|v| *v == OCCUPIED))
            .count();
        eprintln!(
            "{}: {lines} walls, {circles} poles; {blocked} kept samples lie on them",
            path.display()
        );
    } else {
        eprintln!("no map.xml: the map is all free");
    }
    Ok(map)
}
