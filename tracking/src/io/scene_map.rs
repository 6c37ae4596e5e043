//! OpenTraj's `map.xml`: the walls and poles of an ETH scene, read beside its `obsmat.txt`
//! and drawn into an occupancy grid.
//!
//! The format is a list of start tags: `<Line x1=".." y1=".." x2=".." y2=".." …>` for a wall
//! and `<Circle x=".." y=".." radius=".." …>` for a pole, in metres in the frame of the
//! trajectories; everything else is ignored. A tag whose coordinates are missing, unreadable
//! or not finite, or a negative radius, is an error naming the tag (a map that silently lost
//! a wall would send a planner through it).

use nalgebra::Point2;

use haunts_occupancy::{OCCUPIED, OccupancyGrid, budget};

use crate::{Result, TrackingError};

/// The obstacles of a `map.xml`.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SceneMap {
    /// Walls: segments from one end to the other, metres.
    pub lines: Vec<[Point2<f64>; 2]>,
    /// Poles: centre and radius, metres.
    pub circles: Vec<(Point2<f64>, f64)>,
}

/// The numeric attribute `name="…"` of an XML start tag (`None` when absent or unreadable).
fn attribute(tag: &str, name: &str) -> Option<f64> {
    let key = format!(" {name}=\"");
    let from = tag.find(&key)? + key.len();
    let len = tag.get(from..)?.find('"')?;
    tag.get(from..from + len)?.trim().parse().ok()
}

/// Every `<Name …` start tag of `xml`, up to its `>` (or the end of the text).
fn tags<'a>(xml: &'a str, name: &str) -> Vec<&'a str> {
    let open = format!("<{name} ");
    let mut out = Vec::new();
    let mut rest = xml;
    while let Some(i) = rest.find(&open) {
        let tail = &rest[i..];
        let end = tail.find('>').unwrap_or(tail.len());
        out.push(&tail[..end]);
        rest = &tail[end..];
    }
    out
}

/// A bad tag, shortened for the message.
fn bad(tag: &str, rule: &'static str) -> TrackingError {
    let tag: String = tag.chars().take(120).collect();
    TrackingError::SceneMap { tag, rule }
}

/// Reads the walls and poles of an OpenTraj `map.xml`.
///
/// The format is a list of start tags: `<Line x1=".." y1=".." x2=".." y2=".." …>` for a wall
/// and `<Circle x=".." y=".." radius=".." …>` for a pole, in metres in the frame of the
/// trajectories; everything else is ignored. A tag whose coordinates are missing, unreadable
/// or not finite, or a negative radius, is an error naming the tag (a map that silently lost
/// a wall would send a planner through it).
///
/// # Errors
/// [`TrackingError::SceneMap`] naming the first `<Line>` or `<Circle>` tag with a missing,
/// unreadable or non-finite coordinate, or a radius that is negative or not finite.
///
/// ```
/// use haunts_tracking::parse_scene_map;
/// let map = parse_scene_map(r#"<Map><Line x1="0" y1="0" x2="4" y2="0"/><Circle x="1" y="2" radius="0.3"/></Map>"#)?;
/// assert_eq!((map.lines.len(), map.circles.len()), (1, 1));
/// assert!(parse_scene_map(r#"<Line x1="0" y1="nan" x2="4" y2="0"/>"#).is_err());
/// # Ok::<(), haunts_tracking::TrackingError>(())
/// ```
pub fn parse_scene_map(xml: &str) -> Result<SceneMap> {
    let mut map = SceneMap::default();
    for tag in tags(xml, "Line") {
        let [Some(x1), Some(y1), Some(x2), Some(y2)] =
            ["x1", "y1", "x2", "y2"].map(|k| attribute(tag, k))
        else {
            return Err(bad(tag, "needs numeric x1, y1, x2, y2"));
        };
        if ![x1, y1, x2, y2].iter().all(|v| v.is_finite()) {
            return Err(bad(tag, "a coordinate is not finite"));
        }
        map.lines.push([Point2::new(x1, y1), Point2::new(x2, y2)]);
    }
    for tag in tags(xml, "Circle") {
        let [Some(x), Some(y), Some(radius)] = ["x", "y", "radius"].map(|k| attribute(tag, k))
        else {
            return Err(bad(tag, "needs numeric x, y, radius"));
        };
        if !(x.is_finite() && y.is_finite()) {
            return Err(bad(tag, "the centre is not finite"));
        }
        if !(radius.is_finite() && radius >= 0.0) {
            return Err(bad(tag, "the radius must be finite and >= 0"));
        }
        map.circles.push((Point2::new(x, y), radius));
    }
    Ok(map)
}

impl SceneMap {
    /// Marks the cells of `map` the obstacles cover as occupied: each wall sampled every
    /// quarter cell (a wall much longer than the grid clipped to it first, so a wall to 1e300
    /// costs what the grid's diagonal does), each pole's cells whose centre is within `radius + resolution / 2`.
    /// Returns the number of cells newly marked.
    ///
    /// # Errors
    /// [`TrackingError::Occupancy`] holding
    /// [`OccupancyError::WorkTooLarge`](haunts_occupancy::OccupancyError::WorkTooLarge) when
    /// the poles' boxes, clipped to the grid, hold more cells than the work budget allows
    /// (checked before drawing).
    ///
    /// # Complexity
    /// O(walls · (width + height)) plus the cells of the poles' boxes.
    pub fn draw(&self, map: &mut OccupancyGrid) -> Result<usize> {
        let g = *map.geometry();
        let r = g.resolution();
        // The cell box (columns, rows) of each pole, clipped to the grid.
        let boxes: Vec<Option<([usize; 2], [usize; 2])>> = self
            .circles
            .iter()
            .map(|(c, radius)| {
                let reach = radius + r;
                let lo = (c - nalgebra::Vector2::new(reach, reach) - g.origin().coords) / r;
                let hi = (c + nalgebra::Vector2::new(reach, reach) - g.origin().coords) / r;
                let (w, h) = (g.width() as f64, g.height() as f64);
                if hi.x < 0.0 || hi.y < 0.0 || lo.x >= w || lo.y >= h {
                    return None;
                }
                // Clamped into the grid, so the casts are exact.
                let cols = [lo.x.max(0.0) as usize, hi.x.min(w - 1.0) as usize];
                let rows = [lo.y.max(0.0) as usize, hi.y.min(h - 1.0) as usize];
                Some((cols, rows))
            })
            .collect();
        let cells: f64 = boxes
            .iter()
            .flatten()
            .map(|(c, r)| ((c[1] - c[0] + 1) * (r[1] - r[0] + 1)) as f64)
            .sum();
        budget::check_work("map.xml poles", &[("cells in the poles' boxes", cells)])?;
        let mut marked = 0;
        let mut mark = |map: &mut OccupancyGrid, cell| {
            if map.value(cell) != Some(OCCUPIED) {
                map.set(cell, OCCUPIED);
                marked += 1;
            }
        };
        // A wall far longer than the grid (to 1e300, say) is clipped to it first: its samples
        // are bounded by the grid's size, not by the wall's (walls on the grid are unchanged).
        let most = 8.0 * (g.width() + g.height()) as f64;
        for &[mut a, mut b] in &self.lines {
            if (b - a).norm() / (0.25 * r) > most {
                match clip(a, b, g.origin(), g.upper_corner()) {
                    Some((p, q)) => (a, b) = (p, q),
                    None => continue,
                }
            }
            let steps = ((b - a).norm() / (0.25 * r)).ceil().max(1.0) as usize;
            for i in 0..=steps {
                if let Some(c) = g.world_to_cell(a + (b - a) * (i as f64 / steps as f64)) {
                    mark(map, c);
                }
            }
        }
        for ((centre, radius), cell_box) in self.circles.iter().zip(&boxes) {
            let Some((cols, rows)) = cell_box else {
                continue;
            };
            for row in rows[0]..=rows[1] {
                for col in cols[0]..=cols[1] {
                    let c = haunts_occupancy::Cell::new(col, row);
                    // `hypot`, not `norm`: the square of 1e300 overflows.
                    let d = g.cell_center(c) - centre;
                    if d.x.hypot(d.y) <= radius + 0.5 * r {
                        mark(map, c);
                    }
                }
            }
        }
        Ok(marked)
    }
}

/// The part of segment `a`–`b` inside the box `lo`–`hi` (Liang–Barsky), or `None` if it
/// misses the box.
fn clip(
    a: Point2<f64>,
    b: Point2<f64>,
    lo: Point2<f64>,
    hi: Point2<f64>,
) -> Option<(Point2<f64>, Point2<f64>)> {
    let d = b - a;
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    for (p, q) in [
        (-d.x, a.x - lo.x),
        (d.x, hi.x - a.x),
        (-d.y, a.y - lo.y),
        (d.y, hi.y - a.y),
    ] {
        if p == 0.0 {
            if q < 0.0 {
                return None;
            }
        } else if p < 0.0 {
            t0 = t0.max(q / p);
        } else {
            t1 = t1.min(q / p);
        }
    }
    (t0 <= t1).then(|| (a + d * t0, a + d * t1))
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;
    use haunts_occupancy::{FREE, GridGeometry};

    fn free(width: usize, height: usize) -> OccupancyGrid {
        let g = GridGeometry::new(0.5, Point2::origin(), width, height).unwrap();
        OccupancyGrid::from_values(g, vec![FREE; g.len()]).unwrap()
    }

    #[test]
    fn a_wall_and_a_pole_are_drawn_where_they_stand() {
        let scene = parse_scene_map(
            r#"<Map> <Line x1="0.1" y1="0.2" x2="4.9" y2="0.2" /> <Circle x="2.25" y="3.25" radius="0.1" /></Map>"#,
        )
        .unwrap();
        let mut map = free(10, 10);
        assert_eq!(scene.draw(&mut map).unwrap(), 10 + 1);
        assert_eq!(map.value(haunts_occupancy::Cell::new(9, 0)), Some(OCCUPIED));
        assert_eq!(map.value(haunts_occupancy::Cell::new(4, 6)), Some(OCCUPIED));
        assert_eq!(map.value(haunts_occupancy::Cell::new(4, 5)), Some(FREE));
    }

    #[test]
    fn absurd_walls_and_poles_cost_what_the_grid_does() {
        // A wall to 1e300 is clipped to the grid (its 10 cells of row 2 marked).
        let wall = parse_scene_map(r#"<Line x1="0.2" y1="1.2" x2="1e300" y2="1.2"/>"#).unwrap();
        let mut map = free(10, 10);
        assert_eq!(wall.draw(&mut map).unwrap(), 10);
        // A pole of radius 1e300 fills the grid.
        let pole = parse_scene_map(r#"<Circle x="1e300" y="0" radius="1e300"/>"#).unwrap();
        let mut map = free(10, 10);
        assert_eq!(pole.draw(&mut map).unwrap(), 100);
        // Far away: nothing drawn.
        let far = parse_scene_map(r#"<Circle x="1e300" y="0" radius="1"/>"#).unwrap();
        assert_eq!(far.draw(&mut free(10, 10)).unwrap(), 0);
    }

    #[test]
    fn bad_tags_are_refused_by_name() {
        for xml in [
            r#"<Line x1="0" y1="0" x2="1"/>"#,
            r#"<Line x1="0" y1="inf" x2="1" y2="1"/>"#,
            r#"<Circle x="0" y="0" radius="-1"/>"#,
            r#"<Circle x="0" y="NaN" radius="1"/>"#,
            r#"<Circle x="0" y="0" radius="x"/>"#,
        ] {
            match parse_scene_map(xml) {
                Err(TrackingError::SceneMap { tag, .. }) => assert!(xml.starts_with(&tag)),
                other => panic!("{xml}: {other:?}"),
            }
        }
        // Unknown tags and text are ignored.
        assert_eq!(
            parse_scene_map("<Map><Other x=\"1\"/>text</Map>").unwrap(),
            SceneMap::default()
        );
    }
}
