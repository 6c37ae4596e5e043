//! Pictures of grids: PNG export with perceptual colour maps, and PNG map images on load.

use std::path::Path;

use crate::{CellState, Grid, OccupancyError, OccupancyGrid, Result};

/// A perceptual colour map, from low (0) to high (1).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ColorMap {
    /// Viridis (matplotlib's default): perceptually uniform, readable in greyscale.
    #[default]
    Viridis,
    /// Turbo: a perceptual rainbow with more contrast.
    Turbo,
}

impl ColorMap {
    /// RGB colour of `t` in `[0, 1]` (clamped; NaN maps to 0).
    pub fn rgb(self, t: f64) -> [u8; 3] {
        let t = if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) };
        let c = match self {
            Self::Viridis => colorous::VIRIDIS.eval_continuous(t),
            Self::Turbo => colorous::TURBO.eval_continuous(t),
        };
        [c.r, c.g, c.b]
    }
}

/// An RGBA picture, top row first (north up: the grid's last row is the picture's first).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Picture {
    width: usize,
    height: usize,
    rgba: Vec<[u8; 4]>,
}

/// Grey of unknown cells, as in ROS map images.
const UNKNOWN_GREY: [u8; 4] = [205, 205, 205, 255];

impl Picture {
    /// A picture of `grid` with one pixel per cell coloured by `f`.
    fn from_grid<T>(grid: &Grid<T>, mut f: impl FnMut(&T) -> [u8; 4]) -> Self {
        let rgba = grid
            .rows()
            .rev()
            .flat_map(|row| row.iter().map(&mut f).collect::<Vec<_>>())
            .collect();
        Self {
            width: grid.width(),
            height: grid.height(),
            rgba,
        }
    }
    /// A picture of `width` × `height` RGBA pixels, top row first.
    ///
    /// # Errors
    /// [`OccupancyError::Picture`] if `rgba` does not hold `width × height` pixels.
    pub fn from_rgba(width: usize, height: usize, rgba: Vec<[u8; 4]>) -> Result<Self> {
        if width.checked_mul(height) != Some(rgba.len()) {
            return Err(OccupancyError::Picture {
                width,
                height,
                pixels: rgba.len(),
            });
        }
        Ok(Self {
            width,
            height,
            rgba,
        })
    }

    /// Width in pixels.
    pub fn width(&self) -> usize {
        self.width
    }
    /// Height in pixels.
    pub fn height(&self) -> usize {
        self.height
    }
    /// The pixel at column `x` and row `y` counted from the top, or `None` outside.
    pub fn pixel(&self, x: usize, y: usize) -> Option<[u8; 4]> {
        (x < self.width && y < self.height).then(|| self.rgba[y * self.width + x])
    }

    /// The picture as PNG bytes.
    ///
    /// # Errors
    /// [`OccupancyError::Png`] if the encoder fails.
    pub fn encode_png(&self) -> Result<Vec<u8>> {
        let png_err = |e: png::EncodingError| OccupancyError::Png {
            path: "(memory)".into(),
            message: e.to_string(),
        };
        let mut out = Vec::new();
        let mut enc = png::Encoder::new(&mut out, self.width as u32, self.height as u32);
        enc.set_color(png::ColorType::Rgba);
        enc.set_depth(png::BitDepth::Eight);
        let mut writer = enc.write_header().map_err(png_err)?;
        writer
            .write_image_data(self.rgba.as_flattened())
            .map_err(png_err)?;
        writer.finish().map_err(png_err)?;
        Ok(out)
    }

    /// Writes the picture as a PNG file.
    ///
    /// # Errors
    /// [`OccupancyError::Io`] or [`OccupancyError::Png`].
    pub fn save_png(&self, path: impl AsRef<Path>) -> Result<()> {
        let path = path.as_ref();
        let bytes = self.encode_png().map_err(|e| match e {
            OccupancyError::Png { message, .. } => OccupancyError::Png {
                path: path.to_path_buf(),
                message,
            },
            other => other,
        })?;
        std::fs::write(path, bytes).map_err(|e| crate::error::io_error(path, e))
    }
}

/// The range of the finite values of a grid, or `(0, 1)` if there are none.
fn finite_range(grid: &Grid<f64>) -> (f64, f64) {
    let (lo, hi) = grid
        .data()
        .iter()
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
            (lo.min(v), hi.max(v))
        });
    if lo <= hi { (lo, hi) } else { (0.0, 1.0) }
}

fn scale(v: f64, (lo, hi): (f64, f64)) -> f64 {
    if hi > lo { (v - lo) / (hi - lo) } else { 0.5 }
}

/// A picture of a scalar grid: each finite value coloured by `map` over `range` (the finite
/// values' own range when `None`); NaN and infinite values are transparent.
///
/// ```
/// use haunts_occupancy::{picture::{render_scalar, ColorMap}, Grid, GridGeometry};
/// let g = GridGeometry::new(1.0, nalgebra::Point2::origin(), 2, 1).unwrap();
/// let pic = render_scalar(&Grid::from_vec(g, vec![0.0, f64::NAN]).unwrap(), ColorMap::Viridis, None);
/// assert_eq!(pic.pixel(1, 0).unwrap()[3], 0);
/// ```
pub fn render_scalar(grid: &Grid<f64>, map: ColorMap, range: Option<(f64, f64)>) -> Picture {
    let range = range.unwrap_or_else(|| finite_range(grid));
    Picture::from_grid(grid, |&v| {
        if v.is_finite() {
            let [r, g, b] = map.rgb(scale(v, range));
            [r, g, b, 255]
        } else {
            [0, 0, 0, 0]
        }
    })
}

/// A picture of an occupancy grid as map_server draws it: free white, occupied black,
/// unknown grey; values between the thresholds in shades of grey.
pub fn render_occupancy(grid: &OccupancyGrid) -> Picture {
    let t = grid.thresholds();
    Picture::from_grid(grid.values(), |&v| match t.state(v) {
        CellState::Free => [254, 254, 254, 255],
        CellState::Occupied => [0, 0, 0, 255],
        CellState::Unknown if v < 0 => UNKNOWN_GREY,
        CellState::Unknown => {
            let s = (255.0 * (1.0 - f64::from(v) / 100.0)).round() as u8;
            [s, s, s, 255]
        }
    })
}

/// A scalar layer drawn over an occupancy map: free cells coloured by the layer (NaN layer
/// values stay white), walls black, unknown grey.
///
/// # Errors
/// [`OccupancyError::GeometryMismatch`] when the layer does not lie on the map's cells.
pub fn render_overlay(
    map: &OccupancyGrid,
    layer: &Grid<f64>,
    colors: ColorMap,
    range: Option<(f64, f64)>,
) -> Result<Picture> {
    if !map
        .geometry()
        .same_cells(layer.geometry(), crate::GridGeometry::SAME_CELLS_TOLERANCE)
    {
        return Err(OccupancyError::GeometryMismatch {
            expected: Box::new(*map.geometry()),
            found: Box::new(*layer.geometry()),
        });
    }
    let range = range.unwrap_or_else(|| finite_range(layer));
    let t = map.thresholds();
    let cells = Grid::from_vec(
        *map.geometry(),
        map.values()
            .data()
            .iter()
            .zip(layer.data())
            .map(|(&o, &l)| (o, l))
            .collect(),
    )?;
    Ok(Picture::from_grid(&cells, |&(o, l)| match t.state(o) {
        CellState::Occupied => [0, 0, 0, 255],
        CellState::Unknown => UNKNOWN_GREY,
        CellState::Free if l.is_finite() => {
            let [r, g, b] = colors.rgb(scale(l, range));
            [r, g, b, 255]
        }
        CellState::Free => [254, 254, 254, 255],
    }))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::GridGeometry;
    use nalgebra::Point2;

    #[test]
    fn pictures_are_north_up_and_round_trip_through_png() {
        let g = GridGeometry::new(1.0, Point2::origin(), 2, 2).unwrap();
        let occ = OccupancyGrid::from_values(g, vec![100, 0, -1, 50]).unwrap();
        let pic = render_occupancy(&occ);
        // Grid row 0 (bottom) is the picture's last row.
        assert_eq!(pic.pixel(0, 1), Some([0, 0, 0, 255]));
        assert_eq!(pic.pixel(1, 1), Some([254, 254, 254, 255]));
        assert_eq!(pic.pixel(0, 0), Some(UNKNOWN_GREY));
        let bytes = pic.encode_png().unwrap();
        let raster = crate::map_io::png::decode_png_raster(&bytes, Path::new("x.png")).unwrap();
        assert_eq!((raster.width, raster.height, raster.channels), (2, 2, 4));
        assert_eq!(
            &raster.samples[..8],
            &[205, 205, 205, 255, 128, 128, 128, 255]
        );

        let layer = Grid::from_vec(g, vec![0.0, 1.0, 2.0, 3.0]).unwrap();
        let over = render_overlay(&occ, &layer, ColorMap::Turbo, Some((0.0, 1.0))).unwrap();
        let [r, g2, b] = ColorMap::Turbo.rgb(1.0);
        assert_eq!(over.pixel(1, 1), Some([r, g2, b, 255]));
        assert_eq!(over.pixel(0, 1), Some([0, 0, 0, 255]));
        let other = Grid::filled(GridGeometry::new(2.0, Point2::origin(), 2, 2).unwrap(), 0.0);
        assert!(render_overlay(&occ, &other, ColorMap::Viridis, None).is_err());
    }

    #[test]
    fn colour_maps_run_from_dark_to_bright() {
        let lum = |c: [u8; 3]| {
            0.2126 * f64::from(c[0]) + 0.7152 * f64::from(c[1]) + 0.0722 * f64::from(c[2])
        };
        let v: Vec<f64> = (0..=10)
            .map(|i| lum(ColorMap::Viridis.rgb(f64::from(i) / 10.0)))
            .collect();
        assert!(
            v.windows(2).all(|w| w[1] > w[0]),
            "viridis luminance is monotone: {v:?}"
        );
        assert_eq!(ColorMap::Viridis.rgb(f64::NAN), ColorMap::Viridis.rgb(0.0));
    }
}
