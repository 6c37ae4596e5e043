//! A run's `index.html` as a browser shows it: headless Chromium takes a screenshot of a
//! report, and its figures must be on it (strongly coloured pixels of their colour maps),
//! while the same page with its figure files missing shows none.
//!
//! Chromium is found as `chromium` (Debian's package) or `chromium-browser`, or named by
//! `HAUNTS_CHROMIUM`. Without one the test says so and passes, unless
//! `HAUNTS_REQUIRE_CHROMIUM=1` (set by `.ci/run`, which installs Debian's package).
//! `scripts/screenshot.sh DIR` takes the same screenshot of any run's folder.
#![cfg(feature = "figures")]

use std::path::{Path, PathBuf};
use std::process::Command;

use haunts::figure::{MapFigure, Report};
use haunts::occupancy::picture::ColorMap;
use haunts::occupancy::{Grid, GridGeometry, OccupancyGrid};
use nalgebra::Point2;

/// The browser to use, if there is one.
fn chromium() -> Option<PathBuf> {
    if let Some(named) = std::env::var_os("HAUNTS_CHROMIUM") {
        return Some(named.into());
    }
    ["chromium", "chromium-browser"].iter().find_map(|name| {
        let found = Command::new("which").arg(name).output().ok()?;
        found
            .status
            .success()
            .then(|| PathBuf::from(String::from_utf8_lossy(&found.stdout).trim()))
    })
}

/// A screenshot of `page`, `width` × `height` pixels, as RGBA rows.
fn screenshot(browser: &Path, page: &Path, width: u32, height: u32) -> (usize, Vec<u8>) {
    let shot = page.with_file_name("screenshot.png");
    let _ = std::fs::remove_file(&shot);
    let status = Command::new(browser)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--hide-scrollbars",
            &format!("--window-size={width},{height}"),
            &format!("--screenshot={}", shot.display()),
        ])
        .arg(format!("file://{}", page.display()))
        .output()
        .expect("chromium runs");
    assert!(
        shot.exists(),
        "no screenshot; chromium said: {}",
        String::from_utf8_lossy(&status.stderr)
    );
    let mut decoder = png::Decoder::new(std::io::BufReader::new(
        std::fs::File::open(&shot).expect("screenshot"),
    ));
    decoder.set_transformations(png::Transformations::EXPAND | png::Transformations::ALPHA);
    let mut reader = decoder.read_info().expect("png header");
    let mut buffer = vec![0; reader.output_buffer_size().expect("size")];
    let frame = reader.next_frame(&mut buffer).expect("png data");
    buffer.truncate(frame.buffer_size());
    (frame.color_type.samples(), buffer)
}

/// Pixels whose channels differ by more than 80: the colour maps' hues, never text on white,
/// grey walls or a broken-image icon.
fn coloured(samples: usize, pixels: &[u8]) -> usize {
    pixels
        .chunks_exact(samples)
        .filter(|p| {
            let (lo, hi) = (p[..3].iter().min(), p[..3].iter().max());
            matches!((lo, hi), (Some(lo), Some(hi)) if hi - lo > 80)
        })
        .count()
}

/// A report of two figures (a ramp in turbo and one in viridis over a walled room) and a
/// table, written to `dir`: the page, and the coloured pixels of the two figures' own PNGs.
fn write_report(dir: &Path) -> (PathBuf, usize) {
    let g = GridGeometry::new(0.1, Point2::origin(), 100, 50).expect("geometry");
    let walls = OccupancyGrid::from_values(
        g,
        Grid::from_fn(g, |c| if c.row < 3 { 100 } else { 0 })
            .data()
            .to_vec(),
    )
    .expect("walls");
    let ramp = Grid::from_fn(g, |c| c.col as f64);
    let mut in_figures = 0;
    for (file, map) in [
        ("turbo.png", ColorMap::Turbo),
        ("viridis.png", ColorMap::Viridis),
    ] {
        let figure = MapFigure::new(file)
            .walls(&walls)
            .scalar(&ramp, "cells", map)
            .save(dir.join(file))
            .expect("figure");
        let picture = figure.picture();
        let pixels: Vec<u8> = (0..picture.height())
            .flat_map(|y| (0..picture.width()).filter_map(move |x| picture.pixel(x, y)))
            .flatten()
            .collect();
        in_figures += coloured(4, &pixels);
    }
    let page = Report::new("two figures")
        .figure("turbo.png", "a ramp in turbo")
        .figure("viridis.png", "a ramp in viridis")
        .row("MOTA", "0.876")
        .write(dir)
        .expect("report");
    (page, in_figures)
}

#[test]
fn chromium_shows_the_figures_of_a_report_and_not_those_that_are_missing() {
    let Some(browser) = chromium() else {
        assert!(
            std::env::var("HAUNTS_REQUIRE_CHROMIUM").as_deref() != Ok("1"),
            "HAUNTS_REQUIRE_CHROMIUM=1 but no chromium was found"
        );
        eprintln!("note: no chromium; the report's rendering is not checked");
        return;
    };
    let dir = std::env::temp_dir().join(format!("haunts-report-render-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("dir");
    let (page, in_figures) = write_report(&dir);
    // The two figures one under the other fit in 1000 × 2400; the page may scale them to its
    // width (a little under 1000 px), so at least half their coloured pixels must show.
    let (samples, pixels) = screenshot(&browser, &page, 1000, 2400);
    let with = coloured(samples, &pixels);
    assert!(
        2 * with > in_figures,
        "{with} coloured pixels on the page, {in_figures} in the figures: they did not render"
    );
    for file in ["turbo.png", "viridis.png"] {
        std::fs::remove_file(dir.join(file)).expect("remove");
    }
    let (samples, pixels) = screenshot(&browser, &page, 1000, 2400);
    let without = coloured(samples, &pixels);
    eprintln!(
        "coloured pixels: {in_figures} in the figures, {with} on the page, {without} without"
    );
    assert!(
        without * 100 < with,
        "{without} coloured pixels without the figures, {with} with them"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
