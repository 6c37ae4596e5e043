//! ROS map_server map files (YAML + PGM): load and save, with the ROS 1 and Nav2 readings of
//! pixels as an explicit choice.

mod pgm;
#[cfg(feature = "png")]
pub(crate) mod png;
mod yaml;

use std::path::{Path, PathBuf};

use nalgebra::Point2;

use crate::{Grid, GridGeometry, OccupancyError, OccupancyGrid, Result, UNKNOWN};
pub(crate) use pgm::Raster;
pub use yaml::parse_map_yaml;

/// Which map server's reading of pixels to follow.
///
/// Both map servers read a pixel's occupancy `occ` from its shade and compare it with the
/// file's thresholds strictly (`occ > occupied_thresh` → 100, `occ < free_thresh` → 0; the
/// ROS 1 header comment says `>=`, its code says `>`). They differ in:
///
/// | | ROS 1 `map_server` | Nav2 `nav2_map_server` |
/// |---|---|---|
/// | shade | integer mean of the channels, `occ = (255 − mean) / 255` | real mean, `occ = 1 − mean / max` |
/// | `scale` mode, between thresholds | `1 + 98·ratio`, truncated (1–99) | `rint(100·ratio)` (0–100) |
/// | `scale` mode, alpha | unknown only when fully transparent | unknown unless fully opaque |
/// | `raw` mode | the shade after `negate`, as a signed byte | `round(255·shade)`, `negate` ignored, > 100 unknown |
///
/// In `raw` mode ROS 1 stores shades above 127 wrapped into negative numbers; here any raw
/// value outside 0–100 is unknown (−1), since an [`OccupancyGrid`] holds only −1..=100.
/// Images with more than 8 bits are read with their samples scaled to 0–255 for the ROS 1
/// reading (`round(255·v / maxval)`) and as `v / maxval` for Nav2.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Interpretation {
    /// ROS 1 `map_server` (`image_loader.cpp`).
    #[default]
    Ros1,
    /// ROS 2 Nav2 `nav2_map_server` (`map_io.cpp`).
    Nav2,
}

/// How pixels become occupancy values (the YAML `mode` field).
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum MapMode {
    /// Occupied, free or unknown (the default).
    #[default]
    Trinary,
    /// Occupied, free, or a value between them scaled from the shade.
    Scale,
    /// The pixel value is the occupancy value.
    Raw,
}

/// What a map YAML file says, after defaults.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Debug, Clone, PartialEq)]
pub struct MapMetadata {
    /// The image, resolved against the YAML file's folder when relative.
    pub image: PathBuf,
    /// Pixel reading mode.
    pub mode: MapMode,
    /// Metres per pixel.
    pub resolution: f64,
    /// World pose `[x, y, yaw]` of the lower-left pixel.
    pub origin: [f64; 3],
    /// Whether white means occupied.
    pub negate: bool,
    /// Occupancy above which a pixel is occupied.
    pub occupied_thresh: f64,
    /// Occupancy below which a pixel is free.
    pub free_thresh: f64,
}

/// How to load a map.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct MapLoadOptions {
    /// Which map server's pixel reading to follow.
    pub interpretation: Interpretation,
    /// Accept a non-zero origin yaw (kept in [`MapMetadata::origin`]; the grid itself stays
    /// axis aligned at the origin's x, y). Off by default: a rotated map is an error.
    pub keep_yaw: bool,
    /// `free_thresh` to use when the file has none (both map servers require it; many
    /// hand-made files omit it). `None` makes a missing `free_thresh` an error. Default
    /// 0.196, the value ROS `map_saver` writes.
    pub default_free_thresh: Option<f64>,
    /// `negate` to use when the file has none; `None` makes it an error. Default `false`.
    pub default_negate: Option<bool>,
}

impl Default for MapLoadOptions {
    fn default() -> Self {
        Self {
            interpretation: Interpretation::Ros1,
            keep_yaw: false,
            default_free_thresh: Some(0.196),
            default_negate: Some(false),
        }
    }
}

/// Something the loader did that the caller may want to know: nothing is dropped silently.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum LoadNote {
    /// A field was absent and its default was used.
    Defaulted {
        /// The field.
        field: &'static str,
        /// The value used.
        value: String,
    },
    /// A field appeared again with the same value (accepted, as ROS does).
    RepeatedField {
        /// The field.
        field: String,
        /// Line (1-based) of the repetition.
        line: usize,
    },
    /// A field this loader does not use.
    UnknownField {
        /// The field.
        field: String,
        /// Line (1-based).
        line: usize,
    },
}

/// A loaded map: the grid, what the YAML said, and notes on defaults and oddities.
#[derive(Debug, Clone, PartialEq)]
pub struct LoadedMap {
    /// The occupancy grid, row 0 at the bottom (the image is flipped on load).
    pub grid: OccupancyGrid,
    /// The YAML's content after defaults.
    pub metadata: MapMetadata,
    /// Defaults applied, repeated and unknown fields.
    pub notes: Vec<LoadNote>,
}

/// Loads a ROS map_server map (YAML + PGM/PNG image).
///
/// The image path resolves against the YAML file's folder when relative. Repeated fields
/// are accepted when their values agree (ROS files in the wild have them) and rejected when
/// they conflict.
///
/// # Errors
/// [`OccupancyError::Io`] for unreadable files, [`OccupancyError::YamlSyntax`],
/// [`OccupancyError::MissingField`], [`OccupancyError::InvalidField`],
/// [`OccupancyError::ConflictingField`] and [`OccupancyError::NonZeroYaw`] for the YAML,
/// [`OccupancyError::Pgm`] (or `Png`) for the image, each naming file and line or byte.
///
/// # Example
/// ```no_run
/// use haunts_occupancy::{load_map, MapLoadOptions};
/// let map = load_map("map.yaml", &MapLoadOptions::default())?;
/// println!("{} × {} cells", map.grid.geometry().width(), map.grid.geometry().height());
/// # Ok::<(), haunts_occupancy::OccupancyError>(())
/// ```
pub fn load_map(yaml_path: impl AsRef<Path>, options: &MapLoadOptions) -> Result<LoadedMap> {
    let yaml_path = yaml_path.as_ref();
    let text =
        std::fs::read_to_string(yaml_path).map_err(|e| crate::error::io_error(yaml_path, e))?;
    let (metadata, notes) = parse_map_yaml(&text, yaml_path, options)?;
    let grid = load_map_image(&metadata, options.interpretation)?;
    Ok(LoadedMap {
        grid,
        metadata,
        notes,
    })
}

/// Reads the image `metadata` names and turns it into a grid, for metadata obtained
/// elsewhere (a ROS parameter, a database).
///
/// # Errors
/// As [`load_map`] for the image; [`OccupancyError::InvalidGeometry`] for a bad resolution
/// or origin.
pub fn load_map_image(
    metadata: &MapMetadata,
    interpretation: Interpretation,
) -> Result<OccupancyGrid> {
    let path = &metadata.image;
    let bytes = std::fs::read(path).map_err(|e| crate::error::io_error(path, e))?;
    decode_map_image(&bytes, metadata, interpretation)
}

/// Turns the bytes of a map image (PGM, or PNG with the `png` feature) into a grid under
/// `metadata`, for images that do not come from a file; `metadata.image` only names the
/// image in errors.
///
/// # Errors
/// [`OccupancyError::Pgm`], `Png` or [`OccupancyError::UnsupportedImage`] for the image;
/// [`OccupancyError::InvalidGeometry`] for a bad resolution or origin.
pub fn decode_map_image(
    bytes: &[u8],
    metadata: &MapMetadata,
    interpretation: Interpretation,
) -> Result<OccupancyGrid> {
    check_thresholds(metadata)?;
    let raster = decode_image(bytes, &metadata.image)?;
    let geometry = GridGeometry::new(
        metadata.resolution,
        Point2::new(metadata.origin[0], metadata.origin[1]),
        raster.width,
        raster.height,
    )?;
    let reader = PixelReader::new(metadata, interpretation, &raster);
    let n = raster.channels;
    // A grey pixel's value depends on its sample alone: read each possible sample once.
    // (When the image has more pixels than possible samples; 16-bit images may not.)
    let table: Option<Vec<i8>> = (n == 1 && raster.samples.len() > usize::from(raster.maxval))
        .then(|| (0..=raster.maxval).map(|s| reader.value(&[s])).collect());
    let mut values = vec![UNKNOWN; geometry.len()];
    for (image_row, pixels) in raster.samples.chunks_exact(raster.width * n).enumerate() {
        let row = raster.height - 1 - image_row;
        let out = &mut values[row * raster.width..(row + 1) * raster.width];
        if let Some(table) = &table {
            for (v, &s) in out.iter_mut().zip(pixels) {
                *v = table[usize::from(s)];
            }
        } else {
            for (v, px) in out.iter_mut().zip(pixels.chunks_exact(n)) {
                *v = reader.value(px);
            }
        }
    }
    OccupancyGrid::from_grid(Grid::from_vec(geometry, values)?)
}

/// The thresholds of metadata given by a caller obey the rules the YAML reader enforces.
fn check_thresholds(m: &MapMetadata) -> Result<()> {
    if !(0.0..=1.0).contains(&m.occupied_thresh) {
        return Err(OccupancyError::InvalidParameter(
            haunts_core::InvalidParameter {
                name: "occupied_thresh",
                value: m.occupied_thresh,
                rule: "must be in [0, 1]",
            },
        ));
    }
    if !(0.0..m.occupied_thresh).contains(&m.free_thresh) {
        return Err(OccupancyError::InvalidParameter(
            haunts_core::InvalidParameter {
                name: "free_thresh",
                value: m.free_thresh,
                rule: "must be in [0, occupied_thresh)",
            },
        ));
    }
    Ok(())
}

fn decode_image(bytes: &[u8], path: &Path) -> Result<Raster> {
    if bytes.starts_with(b"P5") || bytes.starts_with(b"P2") {
        return pgm::parse_pgm(bytes, path);
    }
    #[cfg(feature = "png")]
    if bytes.starts_with(b"\x89PNG") {
        return png::decode_png_raster(bytes, path);
    }
    Err(OccupancyError::UnsupportedImage {
        path: path.to_path_buf(),
    })
}

/// The per-pixel rule of one map server for one file.
struct PixelReader {
    interpretation: Interpretation,
    mode: MapMode,
    negate: bool,
    occupied: f64,
    free: f64,
    maxval: f64,
    has_alpha: bool,
}

impl PixelReader {
    fn new(m: &MapMetadata, interpretation: Interpretation, raster: &Raster) -> Self {
        Self {
            interpretation,
            mode: m.mode,
            negate: m.negate,
            occupied: m.occupied_thresh,
            free: m.free_thresh,
            maxval: f64::from(raster.maxval),
            has_alpha: raster.channels == 2 || raster.channels == 4,
        }
    }

    /// Occupancy value (−1 or 0..=100) of one pixel's samples.
    fn value(&self, px: &[u16]) -> i8 {
        match self.interpretation {
            Interpretation::Ros1 => self.ros1(px),
            Interpretation::Nav2 => self.nav2(px),
        }
    }

    fn threshold(&self, occ: f64) -> Option<i8> {
        if occ > self.occupied {
            Some(100)
        } else if occ < self.free {
            Some(0)
        } else {
            None
        }
    }

    fn ros1(&self, px: &[u16]) -> i8 {
        let to8 = |s: u16| {
            if self.maxval == 255.0 {
                i64::from(s)
            } else {
                (f64::from(s) * 255.0 / self.maxval).round() as i64
            }
        };
        let n = px.len();
        let averaged = if self.mode == MapMode::Trinary || !self.has_alpha {
            n
        } else {
            n - 1
        };
        let mut avg = px[..averaged].iter().map(|&s| to8(s)).sum::<i64>() / averaged as i64;
        let alpha = if self.has_alpha { to8(px[n - 1]) } else { 255 };
        if self.negate {
            avg = 255 - avg;
        }
        if self.mode == MapMode::Raw {
            return if (0..=100).contains(&avg) {
                avg as i8
            } else {
                UNKNOWN
            };
        }
        let occ = (255 - avg) as f64 / 255.0;
        match self.threshold(occ) {
            Some(v) => v,
            None if self.mode == MapMode::Trinary || alpha < 1 => UNKNOWN,
            None => (1.0 + 98.0 * (occ - self.free) / (self.occupied - self.free)) as i8,
        }
    }

    fn nav2(&self, px: &[u16]) -> i8 {
        let n = px.len();
        // ImageMagick reads grey pixels as R = G = B; the mean of the colour channels is the
        // grey value. In trinary mode the alpha (opacity) joins the mean.
        let colour = if n >= 3 { &px[..3] } else { &px[..1] };
        let mut sum: f64 = colour.iter().map(|&s| f64::from(s)).sum();
        let mut count = colour.len() as f64;
        let alpha = self.has_alpha.then(|| f64::from(px[n - 1]));
        if let (MapMode::Trinary, Some(a)) = (self.mode, alpha) {
            sum += a;
            count += 1.0;
        }
        let shade = sum / count / self.maxval;
        let occ = if self.negate { shade } else { 1.0 - shade };
        match self.mode {
            MapMode::Trinary => self.threshold(occ).unwrap_or(UNKNOWN),
            MapMode::Scale if alpha.is_some_and(|a| a != self.maxval) => UNKNOWN,
            MapMode::Scale => self.threshold(occ).unwrap_or_else(|| {
                ((occ - self.free) / (self.occupied - self.free) * 100.0).round_ties_even() as i8
            }),
            MapMode::Raw => {
                let v = (shade * 255.0).round();
                if (0.0..=100.0).contains(&v) {
                    v as i8
                } else {
                    UNKNOWN
                }
            }
        }
    }
}

/// How to save a map.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct MapSaveOptions {
    /// `Trinary` (occupied black, free white, unknown grey) or `Raw` (pixel = value, unknown
    /// 255). `Scale` cannot be inverted exactly and is refused.
    pub mode: MapMode,
    /// Written to the YAML; trinary pixels are chosen so that they read back as saved.
    pub occupied_thresh: f64,
    /// Written to the YAML.
    pub free_thresh: f64,
}

impl Default for MapSaveOptions {
    /// Trinary with the ROS 1 `map_saver` thresholds (0.65, 0.196).
    fn default() -> Self {
        Self {
            mode: MapMode::Trinary,
            occupied_thresh: 0.65,
            free_thresh: 0.196,
        }
    }
}

/// Saves `grid` as `yaml_path` and an 8-bit PGM beside it (same stem, `.pgm`).
///
/// In trinary mode cells are classified by the grid's [`crate::StateThresholds`]; unknown
/// cells get the conventional grey 205 when it reads back as unknown under both map
/// servers' readings with the chosen thresholds, else the middle of the unknown band.
/// Loading the files back with either [`Interpretation`] gives the same grid (trinary: the
/// same states; raw: the same values).
///
/// # Errors
/// [`OccupancyError::InvalidParameter`] for thresholds that cannot round-trip or a
/// `Scale` mode; [`OccupancyError::Io`] when a file cannot be written.
pub fn save_map(
    yaml_path: impl AsRef<Path>,
    grid: &OccupancyGrid,
    options: &MapSaveOptions,
) -> Result<()> {
    let yaml_path = yaml_path.as_ref();
    let image_path = yaml_path.with_extension("pgm");
    let image_name = image_path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let metadata = MapMetadata {
        image: image_path.clone(),
        mode: options.mode,
        resolution: grid.geometry().resolution(),
        origin: [grid.geometry().origin().x, grid.geometry().origin().y, 0.0],
        negate: false,
        occupied_thresh: options.occupied_thresh,
        free_thresh: options.free_thresh,
    };
    let pixel_of: Box<dyn Fn(i8) -> u8> = match options.mode {
        MapMode::Trinary => {
            let (free_px, occupied_px, unknown_px) = trinary_pixels(&metadata)?;
            let t = grid.thresholds();
            Box::new(move |v| match t.state(v) {
                crate::CellState::Free => free_px,
                crate::CellState::Occupied => occupied_px,
                crate::CellState::Unknown => unknown_px,
            })
        }
        MapMode::Raw => Box::new(|v| if v < 0 { 255 } else { v as u8 }),
        MapMode::Scale => {
            return Err(OccupancyError::InvalidParameter(
                haunts_core::InvalidParameter {
                    name: "mode",
                    value: f64::NAN,
                    rule: "scale mode cannot be saved exactly; use trinary or raw",
                },
            ));
        }
    };
    let g = grid.geometry();
    let mut pixels = Vec::with_capacity(g.len());
    for row in (0..g.height()).rev() {
        pixels.extend(grid.values().row(row).iter().map(|&v| pixel_of(v)));
    }
    let mode = if options.mode == MapMode::Raw {
        "raw"
    } else {
        "trinary"
    };
    let yaml = format!(
        "image: {image_name}\nmode: {mode}\nresolution: {}\norigin: [{}, {}, 0.0]\nnegate: 0\noccupied_thresh: {}\nfree_thresh: {}\n",
        g.resolution(),
        g.origin().x,
        g.origin().y,
        options.occupied_thresh,
        options.free_thresh
    );
    std::fs::write(&image_path, pgm::encode_pgm(g.width(), g.height(), &pixels))
        .map_err(|e| crate::error::io_error(&image_path, e))?;
    std::fs::write(yaml_path, yaml).map_err(|e| crate::error::io_error(yaml_path, e))
}

/// Pixels for (free, occupied, unknown) that both readings decode as such, or an error.
fn trinary_pixels(m: &MapMetadata) -> Result<(u8, u8, u8)> {
    let raster = Raster {
        width: 1,
        height: 1,
        maxval: 255,
        channels: 1,
        samples: vec![],
    };
    let readers =
        [Interpretation::Ros1, Interpretation::Nav2].map(|i| PixelReader::new(m, i, &raster));
    let reads_as = |px: u8, want: i8| readers.iter().all(|r| r.value(&[u16::from(px)]) == want);
    let unknown = std::iter::once(205u8)
        .chain({
            let mid = (255.0 * (1.0 - (m.free_thresh + m.occupied_thresh) / 2.0)).round() as u8;
            std::iter::once(mid)
        })
        .chain(1..=253)
        .find(|&px| reads_as(px, UNKNOWN));
    match unknown {
        Some(u) if reads_as(254, 0) && reads_as(0, 100) => Ok((254, 0, u)),
        _ => Err(OccupancyError::InvalidParameter(
            haunts_core::InvalidParameter {
                name: "free_thresh",
                value: m.free_thresh,
                rule: "thresholds must leave room for free (254), occupied (0) and unknown pixels: 1/255 < free_thresh < occupied_thresh < 1",
            },
        )),
    }
}

#[cfg(test)]
mod tests;
