//! An irregular floor plan for registration tests: outer walls of a 12 m × 8 m box, rooms of
//! different sizes and a few pillars, so that no rotation or shift but the identity maps it
//! onto itself.

/// The plan's walls as segments `(from, to)`, metres.
pub const WALLS: [([f64; 2], [f64; 2]); 13] = [
    ([0.0, 0.0], [12.0, 0.0]),
    ([12.0, 0.0], [12.0, 8.0]),
    ([12.0, 8.0], [0.0, 8.0]),
    ([0.0, 8.0], [0.0, 0.0]),
    ([4.0, 0.0], [4.0, 3.0]),
    ([4.0, 4.5], [4.0, 8.0]),
    ([4.0, 5.0], [7.5, 5.0]),
    ([9.0, 5.0], [12.0, 5.0]),
    ([8.0, 0.0], [8.0, 2.0]),
    ([1.0, 6.0], [2.5, 6.0]),
    ([10.0, 2.0], [10.5, 2.0]),
    ([10.0, 2.0], [10.0, 3.0]),
    ([6.0, 2.0], [6.3, 2.0]),
];

/// Points along every wall of [`WALLS`], at most 1 cm apart, both ends included: mark the
/// cell of each (moved by the test's pose) occupied to draw the plan into a grid.
pub fn wall_points() -> impl Iterator<Item = [f64; 2]> {
    WALLS.iter().flat_map(|&([ax, ay], [bx, by])| {
        let n = ((bx - ax).hypot(by - ay) / 0.01).ceil() as usize;
        (0..=n).map(move |i| {
            let t = i as f64 / n as f64;
            [ax + (bx - ax) * t, ay + (by - ay) * t]
        })
    })
}
