//! Helpers shared by the integration tests (not every test file uses every helper).
#![allow(dead_code)]

use haunts_occupancy::{Cell, FREE, GridGeometry, OCCUPIED, OccupancyGrid};
use nalgebra::Point2;

#[allow(unused_imports)] // not every test file reads the real data
pub use data::shared_data;
use haunts_test_support::data;

/// 3 m × 3 m at 0.05 m: the room of the layout tests.
pub fn room() -> GridGeometry {
    GridGeometry::new(0.05, Point2::origin(), 60, 60).expect("a valid geometry")
}

/// A day's map of [`room`]: a wall along column `col` (all 60 rows), the rest of the room
/// seen free (the day observed the whole room, as seed 000's days do: its days and layouts
/// compare as whole maps whether or not `LayoutParams::observed_only` is on).
pub fn wall_at(col: usize) -> OccupancyGrid {
    wall_seen_in(col, 0..60)
}

/// A day's map of [`room`] that saw only the columns `seen`: a wall along column `col` in
/// it, the rest of `seen` free, everything else unknown.
pub fn wall_seen_in(col: usize, seen: std::ops::Range<usize>) -> OccupancyGrid {
    let mut m = OccupancyGrid::unknown(room());
    for c in seen {
        for row in 0..60 {
            m.set(Cell::new(c, row), if c == col { OCCUPIED } else { FREE });
        }
    }
    m
}

/// A straight walk from `a` to `b` in `n` samples, 0.4 s apart.
pub fn walk(id: u64, a: (f64, f64), b: (f64, f64), n: usize) -> haunts_tracking::Trajectory {
    haunts_tracking::Trajectory {
        id,
        samples: (0..n)
            .map(|k| {
                let t = k as f64 / (n - 1) as f64;
                (
                    k as f64 * 0.4,
                    Point2::new(a.0 + t * (b.0 - a.0), a.1 + t * (b.1 - a.1)),
                )
            })
            .collect(),
    }
}

/// The people detections of a shared stroll day (`"25"` or `"26"`, `t x y …` columns), read
/// whole, or `None` with a notice when the shared data are absent.
pub fn stroll_day(
    day: &str,
) -> Option<haunts_tracking::Parsed<haunts_affordance::hypertime::TimedPoint>> {
    use haunts_affordance::hypertime::{DetectionColumns, read_detections};
    let path = shared_data(&format!("people/2017_05_{day}.txt"))?;
    let columns = DetectionColumns::default().with_columns(0, 1, 2);
    Some(read_detections(path, &columns).expect("the shared stroll day reads"))
}

/// Rooms of the drifting site (see [`drifting_day`]): centres, metres, all inside the ring
/// corridor `[0, 28] × [0, 20]`.
pub const DRIFT_ROOMS: [(f64, f64); 6] = [
    (4.0, 4.0),   // A
    (12.0, 5.0),  // B
    (21.0, 4.0),  // C
    (23.0, 15.0), // D
    (14.0, 15.0), // E
    (5.0, 14.0),  // F
];

/// One day of people detections on a site whose people drift from room to room: from 08:00
/// to 18:00 UTC of day `day` (days since the epoch), `per_hour` detections an hour; the day
/// is cut into `rooms.len()` equal parts and in part `i` 85 % of the detections lie around
/// [`DRIFT_ROOMS`]`[rooms[i]]` (σ 0.7 m), the other 15 % anywhere on the ring corridor
/// around the site's edge (so every day's detections span the whole site). Seeded.
pub fn drifting_day(
    day: u32,
    rooms: &[usize],
    per_hour: usize,
    seed: u64,
) -> Vec<haunts_affordance::hypertime::TimedPoint> {
    use haunts_affordance::hypertime::{DAY, TimedPoint};
    use rand::rngs::StdRng;
    use rand::{RngExt, SeedableRng};
    let mut rng = StdRng::seed_from_u64(seed);
    let gaussian = |rng: &mut StdRng| {
        let u1: f64 = rng.random::<f64>().max(1e-300);
        let u2: f64 = rng.random();
        (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
    };
    let (start, hours) = (8.0 * 3600.0, 10.0);
    let n = (hours as usize) * per_hour;
    (0..n)
        .map(|k| {
            let of_day = (k as f64 + rng.random::<f64>()) / n as f64;
            let t = f64::from(day) * DAY + start + of_day * hours * 3600.0;
            let (x, y) = if rng.random::<f64>() < 0.15 {
                // A point on the ring's perimeter of length 2 · (28 + 20) = 96 m.
                let s = 96.0 * rng.random::<f64>();
                match s {
                    s if s < 28.0 => (s, 0.0),
                    s if s < 48.0 => (28.0, s - 28.0),
                    s if s < 76.0 => (76.0 - s, 20.0),
                    s => (0.0, 96.0 - s),
                }
            } else {
                let part = ((of_day * rooms.len() as f64) as usize).min(rooms.len() - 1);
                let (cx, cy) = DRIFT_ROOMS[rooms[part]];
                (cx + 0.7 * gaussian(&mut rng), cy + 0.7 * gaussian(&mut rng))
            };
            TimedPoint::new(t, x, y)
        })
        .collect()
}
