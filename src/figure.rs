//! Figures for people: maps with axes in metres, a colour bar with its unit, walls, planned
//! paths and tracks drawn over them, and an `index.html` that shows a run's figures with
//! their captions and its figures as a table (feature `figures`, on by default).
//!
//! Drawing is done by [`plotters`] on its bitmap backend with a font embedded in the binary
//! (no system font, no C library); the pixels are written by occupancy's PNG encoder.
//!
//! ```
//! use haunts::figure::MapFigure;
//! use haunts::occupancy::picture::ColorMap;
//! use haunts::occupancy::{Grid, GridGeometry, OccupancyGrid};
//! use nalgebra::Point2;
//!
//! let geometry = GridGeometry::new(0.1, Point2::origin(), 100, 60).unwrap();
//! // A room 10 m × 6 m with a wall along its bottom edge, and a density peaked at (5, 3).
//! let walls = OccupancyGrid::from_values(
//!     geometry,
//!     (0..6000).map(|i| if i < 100 { 100 } else { 0 }).collect(),
//! )
//! .unwrap();
//! let density = Grid::from_fn(geometry, |c| {
//!     let p = geometry.cell_center(c);
//!     (-((p.x - 5.0).powi(2) + (p.y - 3.0).powi(2))).exp()
//! });
//! let figure = MapFigure::new("Where people were")
//!     .walls(&walls)
//!     .scalar(&density, "people per visit", ColorMap::Turbo)
//!     .path("A*", &[Point2::new(1.0, 1.0), Point2::new(9.0, 5.0)])
//!     .render()
//!     .unwrap();
//! assert!(figure.picture().width() >= 800);
//! // The wall is black where the figure says (1 m, 0.05 m) is drawn.
//! let (x, y) = figure.pixel_of(Point2::new(1.0, 0.05)).unwrap();
//! assert_eq!(figure.picture().pixel(x, y).unwrap(), [0, 0, 0, 255]);
//! ```

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use haunts_occupancy::picture::{ColorMap, Picture};
use haunts_occupancy::{Grid, GridGeometry, OccupancyError, OccupancyGrid};
use nalgebra::Point2;
use plotters::coord::ReverseCoordTranslate;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

/// What went wrong making a figure or a report.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum FigureError {
    /// The figure has no map, no scalar layer and no line, so it has no extent.
    #[error("the figure {title:?} has nothing to draw (no walls, no scalar layer, no path)")]
    Empty {
        /// The figure's title.
        title: String,
    },
    /// A width below 800 pixels, the narrowest figure drawn.
    #[error("a figure must be at least {MIN_WIDTH} px wide, not {width}")]
    TooNarrow {
        /// The width asked for.
        width: u32,
    },
    /// A colour range that is not finite or not increasing.
    #[error("the colour range {lo}..{hi} is not a finite increasing range")]
    Range {
        /// Low end.
        lo: f64,
        /// High end.
        hi: f64,
    },
    /// The embedded font could not be registered with the font rasteriser.
    #[error("the embedded figure font could not be read")]
    Font,
    /// The drawing library failed.
    #[error("drawing {title:?} failed: {message}")]
    Draw {
        /// The figure's title.
        title: String,
        /// The drawing library's message.
        message: String,
    },
    /// Encoding or writing the PNG failed.
    #[error(transparent)]
    Occupancy(#[from] OccupancyError),
    /// Writing a report file failed.
    #[error("could not write {path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
}

/// A result with [`FigureError`].
pub type Result<T, E = FigureError> = std::result::Result<T, E>;

/// The narrowest figure drawn: below this the axis labels and the colour bar do not fit.
pub(crate) const MIN_WIDTH: u32 = 800;

/// Margin around the plots, pixels.
const MARGIN: u32 = 16;
/// Room for the y axis's tick labels and description, pixels.
const Y_LABELS: u32 = 72;
/// Room for the x axis's tick labels and description, pixels.
const X_LABELS: u32 = 56;
/// Width of the colour bar's area with its labels, pixels.
const BAR_AREA: u32 = 130;
/// Height taken by the title, pixels.
const TITLE: u32 = 44;

/// Grey of unknown cells, as in ROS map images.
const UNKNOWN: RGBColor = RGBColor(205, 205, 205);
/// Cells at or above this occupancy value (0–100) are drawn as walls: ROS `map_server`'s
/// default `occupied_thresh` (0.65).
const WALL_VALUE: i8 = 65;
/// Colours of the paths, in the order they are added (Tableau 10's red, blue, orange, then
/// white), each over a black casing so that it shows on any colour.
pub const PATH_COLOURS: [[u8; 3]; 4] = [
    [214, 39, 40],
    [31, 119, 180],
    [255, 127, 14],
    [255, 255, 255],
];
/// An arrow of a figure: tail, head.
pub type Arrow = (Point2<f64>, Point2<f64>);

/// The colour of `heading` (radians) on a colour wheel
/// ([`heading_rgb`](crate::pipeline::flow::heading_rgb): east red, a third of a turn on
/// green, two thirds blue).
pub fn heading_colour(heading: f64) -> RGBColor {
    let [r, g, b] = crate::pipeline::flow::heading_rgb(heading).map(|v| (v * 255.0).round() as u8);
    RGBColor(r, g, b)
}

/// Colour of the tracks (drawn thin and half transparent, under the paths).
const TRACK_COLOUR: RGBColor = RGBColor(148, 103, 189);

/// A map figure: optional walls (an occupancy grid), an optional scalar layer with its colour
/// bar, planned paths and tracks, with axes in metres and a title.
///
/// Built with chained calls, then [`MapFigure::render`]ed or [`MapFigure::save`]d. The
/// extent is the walls' grid, else the scalar layer's, else the lines' bounding box; the
/// plot keeps one metre the same length on both axes.
#[derive(Debug, Clone)]
pub struct MapFigure<'a> {
    title: String,
    width: u32,
    walls: Option<&'a OccupancyGrid>,
    scalar: Option<Scalar<'a>>,
    paths: Vec<(String, Vec<Point2<f64>>)>,
    tracks: Vec<Vec<Point2<f64>>>,
    /// Arrows and their legend label.
    arrows: Option<(String, Vec<Arrow>)>,
}

#[derive(Debug, Clone)]
struct Scalar<'a> {
    grid: &'a Grid<f64>,
    unit: String,
    colours: ColorMap,
    range: Option<(f64, f64)>,
}

impl<'a> MapFigure<'a> {
    /// An empty figure titled `title`, 1000 px wide.
    pub fn new(title: impl Into<String>) -> Self {
        Self {
            title: title.into(),
            width: 1000,
            walls: None,
            scalar: None,
            paths: Vec::new(),
            tracks: Vec::new(),
            arrows: None,
        }
    }

    /// The figure's width in pixels (at least 800; checked when rendering). The
    /// height follows from the extent's aspect ratio.
    #[must_use]
    pub fn with_width(mut self, pixels: u32) -> Self {
        self.width = pixels;
        self
    }

    /// Walls and unknown space from an occupancy grid: occupied cells (value ≥ 65) black,
    /// unknown cells grey, free cells white (or the scalar layer's colour).
    #[must_use]
    pub fn walls(mut self, grid: &'a OccupancyGrid) -> Self {
        self.walls = Some(grid);
        self
    }

    /// A scalar layer coloured by `colours`, with a colour bar labelled `unit`; NaN cells
    /// are not drawn. The colour range is the finite values' range unless [`Self::range`]
    /// sets it.
    #[must_use]
    pub fn scalar(
        mut self,
        grid: &'a Grid<f64>,
        unit: impl Into<String>,
        colours: ColorMap,
    ) -> Self {
        self.scalar = Some(Scalar {
            grid,
            unit: unit.into(),
            colours,
            range: None,
        });
        self
    }

    /// The colour bar's range (values outside are clamped to its ends). Ignored without a
    /// scalar layer.
    #[must_use]
    pub fn range(mut self, lo: f64, hi: f64) -> Self {
        if let Some(s) = &mut self.scalar {
            s.range = Some((lo, hi));
        }
        self
    }

    /// A planned path, drawn thick, with `label` in the legend (up to four colours, then they
    /// repeat).
    #[must_use]
    pub fn path(mut self, label: impl Into<String>, points: &[Point2<f64>]) -> Self {
        self.paths.push((label.into(), points.to_vec()));
        self
    }

    /// Tracks (one polyline each), drawn thin under the paths; counted in the legend.
    #[must_use]
    pub fn tracks<I, T>(mut self, tracks: I) -> Self
    where
        I: IntoIterator<Item = T>,
        T: IntoIterator<Item = Point2<f64>>,
    {
        self.tracks.extend(
            tracks
                .into_iter()
                .map(|t| t.into_iter().collect::<Vec<_>>()),
        );
        self
    }

    /// Arrows from tail to head (a flow field: which way people walk), each coloured by its
    /// heading on a colour wheel (east red, north yellow-green, west cyan, south blue-violet),
    /// with `label` in the legend; drawn over the tracks, under the paths.
    #[must_use]
    pub fn arrows(
        mut self,
        label: impl Into<String>,
        arrows: &[(Point2<f64>, Point2<f64>)],
    ) -> Self {
        self.arrows = Some((label.into(), arrows.to_vec()));
        self
    }

    /// Draws the figure.
    ///
    /// # Errors
    /// [`FigureError::TooNarrow`], [`FigureError::Empty`], [`FigureError::Range`] for a bad
    /// colour range, [`FigureError::Draw`] if the drawing library fails.
    pub fn render(&self) -> Result<RenderedFigure> {
        if self.width < MIN_WIDTH {
            return Err(FigureError::TooNarrow { width: self.width });
        }
        register_font()?;
        let extent = self.extent()?;
        let range = match &self.scalar {
            Some(s) => Some(colour_range(s)?),
            None => None,
        };
        let main_width = self.width - if range.is_some() { BAR_AREA } else { 0 };
        let plot_width = main_width - 2 * MARGIN - Y_LABELS;
        let aspect = extent.height / extent.width;
        let plot_height =
            (f64::from(plot_width) * aspect).clamp(240.0, 3.0 * f64::from(self.width));
        let height = plot_height as u32 + TITLE + X_LABELS + 2 * MARGIN;
        let (w, h) = (self.width as usize, height as usize);
        let mut buffer = vec![255u8; w * h * 3];
        let plot = self
            .draw(&mut buffer, (self.width, height), main_width, extent, range)
            .map_err(|message| FigureError::Draw {
                title: self.title.clone(),
                message,
            })?;
        let rgba = buffer
            .chunks_exact(3)
            .map(|p| [p[0], p[1], p[2], 255])
            .collect();
        Ok(RenderedFigure {
            picture: Picture::from_rgba(w, h, rgba)?,
            plot,
        })
    }

    /// Draws the figure and writes it as a PNG file.
    ///
    /// # Errors
    /// As [`Self::render`], and [`FigureError::Occupancy`] if the file cannot be written.
    pub fn save(&self, path: impl AsRef<Path>) -> Result<RenderedFigure> {
        let figure = self.render()?;
        figure.picture.save_png(path)?;
        Ok(figure)
    }

    /// The world rectangle shown.
    fn extent(&self) -> Result<Extent> {
        let geometry = self
            .walls
            .map(|w| *w.geometry())
            .or(self.scalar.as_ref().map(|s| *s.grid.geometry()));
        if let Some(g) = geometry {
            return Ok(Extent::of(&g));
        }
        let points = self
            .paths
            .iter()
            .flat_map(|p| &p.1)
            .chain(self.tracks.iter().flatten())
            .chain(
                self.arrows
                    .iter()
                    .flat_map(|a| a.1.iter().flat_map(|(t, h)| [t, h])),
            );
        let (mut lo, mut hi) = (
            Point2::new(f64::INFINITY, f64::INFINITY),
            Point2::new(f64::NEG_INFINITY, f64::NEG_INFINITY),
        );
        for p in points.filter(|p| p.x.is_finite() && p.y.is_finite()) {
            lo = Point2::new(lo.x.min(p.x), lo.y.min(p.y));
            hi = Point2::new(hi.x.max(p.x), hi.y.max(p.y));
        }
        if lo.x > hi.x {
            return Err(FigureError::Empty {
                title: self.title.clone(),
            });
        }
        // A metre of room around the lines, so that a single point still has an extent.
        Ok(Extent {
            x0: lo.x - 1.0,
            y0: lo.y - 1.0,
            width: hi.x - lo.x + 2.0,
            height: hi.y - lo.y + 2.0,
        })
    }

    /// Draws into `buffer` (RGB, `size`), returning the plotting area's pixel box.
    fn draw(
        &self,
        buffer: &mut [u8],
        size: (u32, u32),
        main_width: u32,
        extent: Extent,
        range: Option<(f64, f64)>,
    ) -> std::result::Result<PlotBox, String> {
        let err = |e: &dyn std::fmt::Display| e.to_string();
        let root = BitMapBackend::with_buffer(buffer, size).into_drawing_area();
        root.fill(&WHITE).map_err(|e| err(&e))?;
        // The title in a band of its own, so that the plot below has exactly the size the
        // aspect ratio asked for.
        let (band, root) = root.split_vertically(TITLE);
        let (band_width, band_height) = band.dim_in_pixel();
        band.draw(&Text::new(
            self.title.as_str(),
            (band_width as i32 / 2, band_height as i32 / 2),
            ("sans-serif", 26)
                .into_font()
                .color(&BLACK)
                .pos(Pos::new(HPos::Center, VPos::Center)),
        ))
        .map_err(|e| err(&e))?;
        let (main, bar) = root.split_horizontally(main_width);
        let mut chart = ChartBuilder::on(&main)
            .margin(MARGIN)
            .x_label_area_size(X_LABELS)
            .y_label_area_size(Y_LABELS)
            .build_cartesian_2d(
                extent.x0..extent.x0 + extent.width,
                extent.y0..extent.y0 + extent.height,
            )
            .map_err(|e| err(&e))?;
        chart
            .configure_mesh()
            .disable_mesh()
            .x_desc("x (m)")
            .y_desc("y (m)")
            .label_style(("sans-serif", 16))
            .axis_desc_style(("sans-serif", 18))
            .draw()
            .map_err(|e| err(&e))?;

        // The cells, one pixel at a time: each pixel takes the colour of the cell under its
        // centre, so the picture is exact at any zoom.
        let area = chart.plotting_area();
        let (xs, ys) = area.get_pixel_range();
        let flat = area.strip_coord_spec();
        for py in ys.clone() {
            for px in xs.clone() {
                let Some((x, y)) = area.as_coord_spec().reverse_translate((px, py)) else {
                    continue;
                };
                if let Some(colour) = self.cell_colour(Point2::new(x, y), range) {
                    flat.draw_pixel((px - xs.start, py - ys.start), &colour)
                        .map_err(|e| err(&e))?;
                }
            }
        }

        let track_style = TRACK_COLOUR.mix(0.45).stroke_width(1);
        for (i, track) in self.tracks.iter().enumerate() {
            let series = chart
                .draw_series(LineSeries::new(
                    track.iter().map(|p| (p.x, p.y)),
                    track_style,
                ))
                .map_err(|e| err(&e))?;
            if i == 0 {
                series
                    .label(format!("tracks ({})", self.tracks.len()))
                    .legend(move |(x, y)| {
                        PathElement::new(vec![(x, y), (x + 20, y)], TRACK_COLOUR.stroke_width(2))
                    });
            }
        }
        if let Some((label, arrows)) = &self.arrows {
            for (i, &(tail, head)) in arrows.iter().enumerate() {
                let colour = heading_colour((head - tail).y.atan2((head - tail).x));
                let d = head - tail;
                // Two wings a third of the arrow long, 25° either side of its back.
                let wing = |turn: f64| {
                    let (s, c) = (std::f64::consts::PI + turn).sin_cos();
                    head + nalgebra::Vector2::new(c * d.x - s * d.y, s * d.x + c * d.y) / 3.0
                };
                let lines = [vec![tail, head], vec![wing(0.44), head, wing(-0.44)]];
                for line in lines {
                    let series = chart
                        .draw_series(LineSeries::new(
                            line.iter().map(|p| (p.x, p.y)),
                            colour.stroke_width(2),
                        ))
                        .map_err(|e| err(&e))?;
                    if i == 0 && line.len() == 2 {
                        series.label(label.as_str()).legend(move |(x, y)| {
                            PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(2))
                        });
                    }
                }
            }
        }
        for (i, (label, points)) in self.paths.iter().enumerate() {
            let [r, g, b] = PATH_COLOURS[i % PATH_COLOURS.len()];
            let colour = RGBColor(r, g, b);
            // A dark casing under each path keeps a white or light path visible on any colour.
            chart
                .draw_series(LineSeries::new(
                    points.iter().map(|p| (p.x, p.y)),
                    BLACK.stroke_width(6),
                ))
                .map_err(|e| err(&e))?;
            chart
                .draw_series(LineSeries::new(
                    points.iter().map(|p| (p.x, p.y)),
                    colour.stroke_width(3),
                ))
                .map_err(|e| err(&e))?
                .label(label.as_str())
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(3))
                });
        }
        if !self.paths.is_empty() || !self.tracks.is_empty() || self.arrows.is_some() {
            chart
                .configure_series_labels()
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK)
                .label_font(("sans-serif", 16))
                .position(SeriesLabelPosition::UpperRight)
                .draw()
                .map_err(|e| err(&e))?;
        }

        if let (Some(scalar), Some((lo, hi))) = (&self.scalar, range) {
            let mut colour_bar = ChartBuilder::on(&bar)
                .margin(MARGIN)
                .margin_left(8)
                .x_label_area_size(X_LABELS)
                .y_label_area_size(84)
                .build_cartesian_2d(0f64..1f64, lo..hi)
                .map_err(|e| err(&e))?;
            colour_bar
                .configure_mesh()
                .disable_mesh()
                .disable_x_axis()
                .y_desc(scalar.unit.as_str())
                .y_labels(6)
                .label_style(("sans-serif", 14))
                .axis_desc_style(("sans-serif", 16))
                .draw()
                .map_err(|e| err(&e))?;
            let area = colour_bar.plotting_area();
            let (xs, ys) = area.get_pixel_range();
            let flat = area.strip_coord_spec();
            for py in ys.clone() {
                let Some((_, v)) = area.as_coord_spec().reverse_translate((xs.start, py)) else {
                    continue;
                };
                let [r, g, b] = scalar.colours.rgb((v - lo) / (hi - lo));
                for px in xs.clone() {
                    flat.draw_pixel((px - xs.start, py - ys.start), &RGBColor(r, g, b))
                        .map_err(|e| err(&e))?;
                }
            }
        }
        root.present().map_err(|e| err(&e))?;
        let (xs, ys) = chart.plotting_area().get_pixel_range();
        Ok(PlotBox {
            x: xs.start..xs.end,
            y: ys.start..ys.end,
            extent,
        })
    }

    /// The colour of the cells under `p`: a wall, unknown grey, the scalar's colour, or
    /// `None` (white background).
    fn cell_colour(&self, p: Point2<f64>, range: Option<(f64, f64)>) -> Option<RGBColor> {
        let wall = self
            .walls
            .and_then(|w| w.geometry().world_to_cell(p).and_then(|c| w.value(c)));
        match wall {
            Some(v) if v >= WALL_VALUE => return Some(BLACK),
            _ => {}
        }
        if let (Some(s), Some((lo, hi))) = (&self.scalar, range) {
            if let Some(v) = s
                .grid
                .geometry()
                .world_to_cell(p)
                .and_then(|c| s.grid.get(c))
            {
                if v.is_finite() {
                    let [r, g, b] = s.colours.rgb((v - lo) / (hi - lo));
                    return Some(RGBColor(r, g, b));
                }
            }
        }
        match wall {
            Some(v) if v < 0 => Some(UNKNOWN),
            _ => None,
        }
    }
}

/// The colour bar's range of a scalar layer: the one set, else the finite values' range
/// (widened when flat, `0..1` when there are none).
fn colour_range(s: &Scalar<'_>) -> Result<(f64, f64)> {
    let (lo, hi) = match s.range {
        Some(r) => r,
        None => {
            let (lo, hi) = s
                .grid
                .data()
                .iter()
                .filter(|v| v.is_finite())
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
                    (lo.min(v), hi.max(v))
                });
            if lo > hi {
                (0.0, 1.0)
            } else if lo == hi {
                (lo - 0.5, hi + 0.5)
            } else {
                (lo, hi)
            }
        }
    };
    if lo.is_finite() && hi.is_finite() && lo < hi {
        Ok((lo, hi))
    } else {
        Err(FigureError::Range { lo, hi })
    }
}

/// Registers the embedded font as plotters' `sans-serif` once per process.
fn register_font() -> Result<()> {
    static REGISTERED: OnceLock<bool> = OnceLock::new();
    let ok = *REGISTERED.get_or_init(|| {
        plotters::style::register_font(
            "sans-serif",
            FontStyle::Normal,
            epaint_default_fonts::UBUNTU_LIGHT,
        )
        .is_ok()
    });
    if ok { Ok(()) } else { Err(FigureError::Font) }
}

/// The world rectangle of a figure, metres.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Extent {
    x0: f64,
    y0: f64,
    width: f64,
    height: f64,
}

impl Extent {
    fn of(g: &GridGeometry) -> Self {
        Self {
            x0: g.origin().x,
            y0: g.origin().y,
            width: g.width() as f64 * g.resolution(),
            height: g.height() as f64 * g.resolution(),
        }
    }
}

/// Where the plot sits in the picture.
#[derive(Debug, Clone, PartialEq)]
struct PlotBox {
    x: std::ops::Range<i32>,
    y: std::ops::Range<i32>,
    extent: Extent,
}

/// A drawn figure: its picture, and where a world point lands in it.
#[derive(Debug, Clone)]
pub struct RenderedFigure {
    picture: Picture,
    plot: PlotBox,
}

impl RenderedFigure {
    /// The picture.
    pub fn picture(&self) -> &Picture {
        &self.picture
    }

    /// The pixel `(column, row from the top)` at which the world point `p` is drawn, or
    /// `None` outside the plot.
    pub fn pixel_of(&self, p: Point2<f64>) -> Option<(usize, usize)> {
        let b = &self.plot;
        let (w, h) = (
            f64::from(b.x.end - b.x.start),
            f64::from(b.y.end - b.y.start),
        );
        let fx = (p.x - b.extent.x0) / b.extent.width;
        let fy = (p.y - b.extent.y0) / b.extent.height;
        if !(0.0..1.0).contains(&fx) || !(0.0..1.0).contains(&fy) {
            return None;
        }
        let x = f64::from(b.x.start) + fx * w;
        let y = f64::from(b.y.end) - fy * h;
        Some((x as usize, (y as usize).min(b.y.end as usize - 1)))
    }
}

/// An `index.html` of a run: its figures with their captions, and its numbers as a table.
///
/// ```
/// let dir = std::env::temp_dir().join(format!("haunts-report-doc-{}", std::process::id()));
/// std::fs::create_dir_all(&dir).unwrap();
/// let page = haunts::figure::Report::new("A day")
///     .figure("map.png", "The day's map <with walls>")
///     .row("MOTA", "0.876")
///     .write(&dir)
///     .unwrap();
/// let html = std::fs::read_to_string(page).unwrap();
/// assert!(html.contains("&lt;with walls&gt;") && html.contains("<td>0.876</td>"));
/// ```
#[derive(Debug, Clone, Default)]
pub struct Report {
    title: String,
    figures: Vec<(String, String)>,
    rows: Vec<(String, String)>,
}

impl Report {
    /// An empty report titled `title`.
    pub fn new(title: impl Into<String>) -> Self {
        Self {
            title: title.into(),
            ..Self::default()
        }
    }

    /// A figure: its file (relative to the report's folder) and its caption.
    #[must_use]
    pub fn figure(mut self, file: impl Into<String>, caption: impl Into<String>) -> Self {
        self.figures.push((file.into(), caption.into()));
        self
    }

    /// A row of the table of figures.
    #[must_use]
    pub fn row(mut self, name: impl Into<String>, value: impl Into<String>) -> Self {
        self.rows.push((name.into(), value.into()));
        self
    }

    /// The report as HTML: one self-contained page (no script, no external resource).
    pub(crate) fn html(&self) -> String {
        let mut page = String::new();
        let title = escape(&self.title);
        // Writing to a String cannot fail.
        let _ = write!(
            page,
            "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n\
             <title>{title}</title>\n<style>\nbody {{ font-family: sans-serif; margin: 2em; \
             max-width: 1100px; }}\nfigure {{ margin: 2em 0; }}\nimg {{ max-width: 100%; \
             border: 1px solid #ccc; }}\ntable {{ border-collapse: collapse; }}\ntd, th {{ \
             border: 1px solid #ccc; padding: 0.2em 0.6em; text-align: left; }}\n\
             td:nth-child(2) {{ font-family: monospace; }}\n</style>\n</head>\n<body>\n\
             <h1>{title}</h1>\n"
        );
        if !self.rows.is_empty() {
            page.push_str("<h2>Figures</h2>\n<table>\n<tr><th>name</th><th>value</th></tr>\n");
            for (name, value) in &self.rows {
                let _ = writeln!(
                    page,
                    "<tr><td>{}</td><td>{}</td></tr>",
                    escape(name),
                    escape(value)
                );
            }
            page.push_str("</table>\n");
        }
        for (file, caption) in &self.figures {
            let _ = writeln!(
                page,
                "<figure>\n<img src=\"{}\" alt=\"{}\">\n<figcaption>{}</figcaption>\n</figure>",
                escape(file),
                escape(caption),
                escape(caption)
            );
        }
        page.push_str("</body>\n</html>\n");
        page
    }

    /// Writes `index.html` into `dir` and returns its path.
    ///
    /// # Errors
    /// [`FigureError::Io`] naming the file.
    pub fn write(&self, dir: impl AsRef<Path>) -> Result<PathBuf> {
        let path = dir.as_ref().join("index.html");
        std::fs::write(&path, self.html()).map_err(|source| FigureError::Io {
            path: path.clone(),
            source,
        })?;
        Ok(path)
    }
}

/// `text` with HTML's special characters escaped.
fn escape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            c => out.push(c),
        }
    }
    out
}
