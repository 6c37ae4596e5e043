//! Figures: what is drawn where (walls, scalar colours, the colour bar, paths), the page of
//! a run, and the errors.
#![cfg(feature = "figures")]

use haunts::figure::{FigureError, MapFigure, PATH_COLOURS, RenderedFigure, Report};
use haunts::occupancy::picture::ColorMap;
use haunts::occupancy::{Grid, GridGeometry, OccupancyGrid};
use nalgebra::Point2;

/// A 10 m × 5 m room at 0.1 m: walls along y < 0.5, unknown for x > 8, free elsewhere.
fn room() -> OccupancyGrid {
    let g = GridGeometry::new(0.1, Point2::origin(), 100, 50).expect("geometry");
    let values = Grid::from_fn(g, |c| {
        let p = g.cell_center(c);
        if p.y < 0.5 {
            100
        } else if p.x > 8.0 {
            -1
        } else {
            0
        }
    });
    OccupancyGrid::from_values(g, values.data().to_vec()).expect("grid")
}

/// The pixel of `figure` at which the world point `(x, y)` is drawn.
fn pixel(figure: &RenderedFigure, x: f64, y: f64) -> [u8; 4] {
    let (px, py) = figure.pixel_of(Point2::new(x, y)).expect("inside");
    figure.picture().pixel(px, py).expect("pixel")
}

fn rgba([r, g, b]: [u8; 3]) -> [u8; 4] {
    [r, g, b, 255]
}

#[test]
fn walls_unknown_and_free_cells_are_drawn_where_the_axes_say() {
    let walls = room();
    let figure = MapFigure::new("room")
        .walls(&walls)
        .render()
        .expect("figure");
    let pic = figure.picture();
    assert!(pic.width() >= 800, "width {}", pic.width());
    let at = |x: f64, y: f64| pixel(&figure, x, y);
    assert_eq!(at(3.0, 0.2), [0, 0, 0, 255], "wall");
    assert_eq!(at(9.0, 3.0), [205, 205, 205, 255], "unknown");
    assert_eq!(at(4.0, 3.0), [255, 255, 255, 255], "free");
    assert_eq!(figure.pixel_of(Point2::new(10.5, 3.0)), None);
    // One metre is as long on both axes: 10 m across is twice 5 m up.
    let (x0, y0) = figure.pixel_of(Point2::new(0.0, 0.0)).expect("corner");
    let (x1, y1) = figure.pixel_of(Point2::new(9.99, 4.99)).expect("corner");
    let ratio = (x1 - x0) as f64 / (y0 - y1) as f64;
    assert!((ratio - 2.0).abs() < 0.02, "aspect {ratio}");
}

#[test]
fn scalar_cells_and_the_colour_bar_use_the_colour_map() {
    let walls = room();
    let g = *walls.geometry();
    // 0 on the left half, 2 on the right half of the free space; NaN (not drawn) below y = 2.
    let density = Grid::from_fn(g, |c| {
        let p = g.cell_center(c);
        if p.y < 2.0 {
            f64::NAN
        } else if p.x < 4.0 {
            0.0
        } else {
            2.0
        }
    });
    let figure = MapFigure::new("density")
        .walls(&walls)
        .scalar(&density, "people per visit", ColorMap::Viridis)
        .render()
        .expect("figure");
    let pic = figure.picture();
    let at = |x: f64, y: f64| pixel(&figure, x, y);
    assert_eq!(at(2.0, 3.5), rgba(ColorMap::Viridis.rgb(0.0)));
    assert_eq!(at(6.0, 3.5), rgba(ColorMap::Viridis.rgb(1.0)));
    assert_eq!(
        at(6.0, 1.0),
        [255, 255, 255, 255],
        "NaN over free space stays white"
    );
    assert_eq!(at(6.0, 0.2), [0, 0, 0, 255], "walls over the scalar");
    // The colour bar, right of the map, runs from the low colour to the high one.
    let (map_right, _) = figure.pixel_of(Point2::new(9.99, 2.5)).expect("inside");
    let bar_column = |colour: [u8; 4]| {
        (map_right + 1..pic.width())
            .find(|&x| (0..pic.height()).any(|y| pic.pixel(x, y) == Some(colour)))
    };
    let (low, high) = (
        bar_column(rgba(ColorMap::Viridis.rgb(0.0))),
        bar_column(rgba(ColorMap::Viridis.rgb(1.0))),
    );
    assert!(
        low.is_some() && high.is_some(),
        "colour bar {low:?} {high:?}"
    );
    let column = high.expect("bar");
    let rows = |colour: [u8; 4]| {
        (0..pic.height())
            .filter(|&y| pic.pixel(column, y) == Some(colour))
            .collect::<Vec<_>>()
    };
    let (top, bottom) = (
        rows(rgba(ColorMap::Viridis.rgb(1.0))),
        rows(rgba(ColorMap::Viridis.rgb(0.0))),
    );
    assert!(
        top.iter().max() < bottom.iter().min(),
        "high values at the top"
    );
}

#[test]
fn paths_are_drawn_in_their_colours_over_the_map() {
    let walls = room();
    let figure = MapFigure::new("plans")
        .walls(&walls)
        .path("plain", &[Point2::new(1.0, 2.0), Point2::new(7.0, 2.0)])
        .path("aware", &[Point2::new(1.0, 4.0), Point2::new(7.0, 4.0)])
        .tracks([vec![Point2::new(2.0, 1.0), Point2::new(2.0, 4.5)]])
        .render()
        .expect("figure");
    let at = |x: f64, y: f64| pixel(&figure, x, y);
    assert_eq!(at(5.0, 2.0), rgba(PATH_COLOURS[0]));
    assert_eq!(at(5.0, 4.0), rgba(PATH_COLOURS[1]));
    assert_eq!(at(5.0, 3.0), [255, 255, 255, 255], "between the paths");
    let track = at(2.0, 3.0);
    assert_ne!(track, [255, 255, 255, 255], "the track is drawn");
}

#[test]
fn arrows_are_drawn_in_the_colour_of_their_heading() {
    use haunts::figure::heading_colour;
    let walls = room();
    // East along y = 2, north along x = 6, west along y = 4.
    let arrows = [
        (Point2::new(1.0, 2.0), Point2::new(4.0, 2.0)),
        (Point2::new(6.0, 1.0), Point2::new(6.0, 4.5)),
        (Point2::new(5.0, 4.0), Point2::new(1.0, 4.0)),
    ];
    let figure = MapFigure::new("flow")
        .walls(&walls)
        .arrows("flow", &arrows)
        .render()
        .expect("figure");
    let at = |x: f64, y: f64| pixel(&figure, x, y);
    let colour = |h: f64| {
        let c = heading_colour(h);
        [c.0, c.1, c.2, 255]
    };
    assert_eq!(at(2.5, 2.0), colour(0.0));
    assert_eq!(at(6.0, 2.5), colour(std::f64::consts::FRAC_PI_2));
    assert_eq!(at(3.0, 4.0), colour(std::f64::consts::PI));
    assert_ne!(colour(0.0), colour(std::f64::consts::PI));
    // The head's wings lie behind the head, either side of the shaft.
    // Wings a third of the arrow (1 m) long, 0.44 rad either side of its back: halfway along
    // the upper one.
    let (wx, wy) = (4.0 - 0.5 * 0.44f64.cos(), 2.0 + 0.5 * 0.44f64.sin());
    assert_eq!(at(wx, wy), colour(0.0), "a wing of the east arrow");
    assert_eq!(at(2.5, 3.0), [255, 255, 255, 255], "between the arrows");
}

#[test]
fn bad_figures_are_typed_errors() {
    let walls = room();
    assert!(matches!(
        MapFigure::new("narrow")
            .walls(&walls)
            .with_width(500)
            .render(),
        Err(FigureError::TooNarrow { width: 500 })
    ));
    assert!(matches!(
        MapFigure::new("nothing").render(),
        Err(FigureError::Empty { .. })
    ));
    let flat = Grid::from_fn(*walls.geometry(), |_| 1.0);
    assert!(matches!(
        MapFigure::new("range")
            .scalar(&flat, "x", ColorMap::Turbo)
            .range(1.0, 1.0)
            .render(),
        Err(FigureError::Range { .. })
    ));
    assert!(matches!(
        MapFigure::new("range")
            .scalar(&flat, "x", ColorMap::Turbo)
            .range(0.0, f64::NAN)
            .render(),
        Err(FigureError::Range { .. })
    ));
    // Lines alone give an extent (a metre around them).
    let lines = MapFigure::new("lines")
        .path("p", &[Point2::new(0.0, 0.0), Point2::new(4.0, 2.0)])
        .render()
        .expect("lines");
    assert!(lines.pixel_of(Point2::new(-0.9, -0.9)).is_some());
    assert!(lines.pixel_of(Point2::new(-1.1, 0.0)).is_none());
}

#[test]
fn a_report_lists_every_figure_and_row_escaped() {
    let dir = std::env::temp_dir().join(format!("haunts-figure-report-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("dir");
    let page = Report::new("run <1>")
        .figure("a.png", "first & only")
        .row("mota", "0.876")
        .row("layouts", "5/5")
        .write(&dir)
        .expect("write");
    let html = std::fs::read_to_string(&page).expect("read");
    assert!(html.contains("<title>run &lt;1&gt;</title>"));
    assert!(html.contains("<img src=\"a.png\" alt=\"first &amp; only\">"));
    assert_eq!(html.matches("<tr><td>").count(), 2);
    let missing = Report::new("x").write(dir.join("no/such/dir"));
    assert!(matches!(missing, Err(FigureError::Io { path, .. }) if path.ends_with("index.html")));
    std::fs::remove_dir_all(&dir).ok();
}
