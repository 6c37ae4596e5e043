//! The simulated world: static walls, fixed and movable furniture, furniture layouts, doors
//! and the places people go to; the built-in coffee lounge of seed 000.

use nalgebra::{Point2, Rotation2, Vector2};

use crate::error::{Result, SimError};
use crate::shapes::Shape;

/// What a piece of furniture is, which decides how the laser sees it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum FurnitureKind {
    /// Four legs of radius 0.03 m at the corners; people stand around it.
    Table,
    /// Four legs of radius 0.02 m at the corners; pushed around every day.
    Chair,
    /// A solid rectangle; people sit in front of it.
    Sofa,
    /// A solid rectangle (cabinets, counters, desks).
    Cabinet,
}

impl FurnitureKind {
    /// Radius of a leg, metres, for the kinds seen as legs.
    pub fn leg_radius(self) -> Option<f64> {
        match self {
            Self::Table => Some(0.03),
            Self::Chair => Some(0.02),
            Self::Sofa | Self::Cabinet => None,
        }
    }
}

/// One piece of furniture: a kind and an oriented footprint.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Furniture {
    /// What it is.
    pub kind: FurnitureKind,
    /// Centre of the footprint, metres.
    pub center: Point2<f64>,
    /// Footprint size (along its own x, y axes), metres.
    pub size: Vector2<f64>,
    /// Rotation of the footprint, radians.
    pub angle: f64,
}

impl Furniture {
    /// A piece of `kind` at `(x, y)` with footprint `w × h` metres rotated by `angle`.
    pub fn new(kind: FurnitureKind, x: f64, y: f64, w: f64, h: f64, angle: f64) -> Self {
        Self {
            kind,
            center: Point2::new(x, y),
            size: Vector2::new(w, h),
            angle,
        }
    }

    fn is_valid(&self) -> bool {
        self.center.iter().all(|v| v.is_finite())
            && self.size.iter().all(|v| v.is_finite() && *v > 0.0)
            && self.angle.is_finite()
    }

    /// Appends the shapes the laser sees: four leg circles for tables and chairs, one
    /// rectangle for sofas and cabinets.
    pub(crate) fn push_shapes(&self, out: &mut Vec<Shape>) {
        let half = self.size / 2.0;
        match self.kind.leg_radius() {
            Some(r) => {
                let rot = Rotation2::new(self.angle);
                let inset = Vector2::new((half.x - r).max(0.0), (half.y - r).max(0.0));
                for (sx, sy) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
                    out.push(Shape::Circle {
                        center: self.center + rot * Vector2::new(sx * inset.x, sy * inset.y),
                        radius: r,
                    });
                }
            }
            None => out.push(Shape::Rect {
                center: self.center,
                half,
                angle: self.angle,
            }),
        }
    }

    /// Where people stand or sit at this piece, facing its centre: around a table (one
    /// place per side, two on long sides longer than 1.4 m) or in front of a sofa (one place
    /// per 0.7 m of length); none for chairs and cabinets.
    pub(crate) fn places(&self) -> Vec<Point2<f64>> {
        let rot = Rotation2::new(self.angle);
        let (hx, hy) = (self.size.x / 2.0, self.size.y / 2.0);
        let local: Vec<Vector2<f64>> = match self.kind {
            FurnitureKind::Table => {
                let gap = 0.4;
                let mut v = vec![Vector2::new(hx + gap, 0.0), Vector2::new(-hx - gap, 0.0)];
                let along = if self.size.x > 1.4 {
                    vec![-hx / 2.0, hx / 2.0]
                } else {
                    vec![0.0]
                };
                for a in along {
                    v.push(Vector2::new(a, hy + gap));
                    v.push(Vector2::new(a, -hy - gap));
                }
                v
            }
            FurnitureKind::Sofa => {
                let n = ((self.size.x / 0.7).floor() as usize).clamp(1, 8);
                (0..n)
                    .map(|i| {
                        let x = -hx + self.size.x * (i as f64 + 0.5) / n as f64;
                        Vector2::new(x, hy + 0.25)
                    })
                    .collect()
            }
            FurnitureKind::Chair | FurnitureKind::Cabinet => Vec::new(),
        };
        local.into_iter().map(|v| self.center + rot * v).collect()
    }
}

/// A door: people enter and leave through it.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Door {
    /// Just inside the room, in the door opening.
    pub inside: Point2<f64>,
    /// Where people appear and vanish, outside the room (in the corridor).
    pub outside: Point2<f64>,
}

/// One furniture layout of the room.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Layout {
    /// A short human-readable name.
    pub name: String,
    /// The movable furniture.
    pub furniture: Vec<Furniture>,
}

/// The whole simulated world except the people and the robot.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Office {
    /// Lower-left corner of the simulated area (and of the ground-truth grid), metres.
    pub min: Point2<f64>,
    /// Upper-right corner of the simulated area, metres.
    pub max: Point2<f64>,
    /// Walls that never move.
    pub walls: Vec<Shape>,
    /// Furniture that never moves (counters, desks).
    pub fixed: Vec<Furniture>,
    /// The furniture layouts; each day uses one of them.
    pub layouts: Vec<Layout>,
    /// Doors people use.
    pub doors: Vec<Door>,
    /// Where people get coffee.
    pub coffee: Vec<Point2<f64>>,
    /// Desk seats.
    pub desks: Vec<Point2<f64>>,
    /// The robot's patrol route (closed: the robot returns to the first waypoint), seed 000
    /// Fig. 7.
    pub waypoints: Vec<Point2<f64>>,
}

/// A table with its chairs around it: one chair per place, pushed back behind it (its
/// centre 0.35 m out, its front legs about 0.15 m behind the place), as people who stand at
/// a table push the chairs away; a chair at the place itself would put the person inside
/// it.
fn table_with_chairs(x: f64, y: f64, w: f64, h: f64, angle: f64) -> Vec<Furniture> {
    let table = Furniture::new(FurnitureKind::Table, x, y, w, h, angle);
    let mut v = vec![table];
    for p in table.places() {
        let out = (p - table.center).normalize();
        let c = p + out * 0.35;
        let a = out.y.atan2(out.x);
        v.push(Furniture::new(
            FurnitureKind::Chair,
            c.x,
            c.y,
            0.42,
            0.42,
            a,
        ));
    }
    v
}

fn wall(x0: f64, y0: f64, x1: f64, y1: f64) -> Shape {
    Shape::aabb(Point2::new(x0, y0), Point2::new(x1, y1))
}

impl Office {
    /// The built-in coffee lounge: a 16 m × 10 m room with three doors onto a corridor, a
    /// coffee counter on the north wall, three desks on the east wall, and five furniture
    /// layouts (seed 000 Fig. 10/12: tables, chairs and sofas moved around the middle of the
    /// room, which the patrol route of Fig. 7 circles).
    pub fn builtin() -> Self {
        let t = 0.1; // wall thickness
        let walls = vec![
            // The corridor's outer walls.
            wall(-2.0, -2.0, 18.0, -2.0 + t),
            wall(-2.0, 12.0 - t, 18.0, 12.0),
            wall(-2.0, -2.0, -2.0 + t, 12.0),
            wall(18.0 - t, -2.0, 18.0, 12.0),
            // South wall, door at x 7.0–8.2.
            wall(0.0, 0.0, 7.0, t),
            wall(8.2, 0.0, 16.0, t),
            // North wall, door at x 10.0–11.2.
            wall(0.0, 10.0 - t, 10.0, 10.0),
            wall(11.2, 10.0 - t, 16.0, 10.0),
            // West wall, door at y 4.2–5.4.
            wall(0.0, 0.0, t, 4.2),
            wall(0.0, 5.4, t, 10.0),
            // East wall.
            wall(16.0 - t, 0.0, 16.0, 10.0),
            // A pillar.
            wall(7.8, 9.0, 8.2, 9.4),
        ];
        let fixed = vec![
            Furniture::new(FurnitureKind::Cabinet, 3.0, 9.6, 4.0, 0.6, 0.0),
            Furniture::new(FurnitureKind::Cabinet, 15.5, 2.5, 0.8, 1.6, 0.0),
            Furniture::new(FurnitureKind::Cabinet, 15.5, 5.0, 0.8, 1.6, 0.0),
            Furniture::new(FurnitureKind::Cabinet, 15.5, 7.5, 0.8, 1.6, 0.0),
        ];
        use FurnitureKind::{Cabinet, Sofa};
        let l0 = [
            table_with_chairs(6.0, 5.0, 1.2, 0.8, 0.0),
            table_with_chairs(10.0, 5.0, 1.2, 0.8, 0.0),
        ]
        .concat();
        let l1 = [
            table_with_chairs(8.0, 5.0, 2.4, 1.0, 0.0),
            vec![Furniture::new(Sofa, 4.0, 4.0, 1.8, 0.8, 0.0)],
        ]
        .concat();
        let mut l2 = [
            table_with_chairs(5.0, 6.0, 0.9, 0.9, 0.0),
            table_with_chairs(8.0, 4.0, 0.9, 0.9, 0.0),
            table_with_chairs(11.0, 6.0, 0.9, 0.9, 0.0),
        ]
        .concat();
        l2.push(Furniture::new(Cabinet, 8.0, 6.8, 1.2, 0.45, 0.0));
        let l3 = [
            vec![
                Furniture::new(Sofa, 5.0, 6.5, 2.0, 0.8, std::f64::consts::PI),
                Furniture::new(Sofa, 5.0, 3.5, 2.0, 0.8, 0.0),
            ],
            table_with_chairs(10.5, 5.0, 1.0, 1.6, 0.0),
        ]
        .concat();
        let l4 = [
            table_with_chairs(5.5, 4.5, 1.6, 0.8, 0.4),
            table_with_chairs(10.5, 5.5, 1.6, 0.8, -0.4),
            vec![Furniture::new(Cabinet, 8.0, 3.4, 0.6, 0.6, 0.0)],
        ]
        .concat();
        let layouts = [
            ("two square tables", l0),
            ("long meeting table and sofa", l1),
            ("three small tables", l2),
            ("sofa corner", l3),
            ("angled tables", l4),
        ]
        .into_iter()
        .map(|(name, furniture)| Layout {
            name: name.to_string(),
            furniture,
        })
        .collect();
        Self {
            min: Point2::new(-2.0, -2.0),
            max: Point2::new(18.0, 12.0),
            walls,
            fixed,
            layouts,
            doors: vec![
                Door {
                    inside: Point2::new(7.6, 0.5),
                    outside: Point2::new(7.6, -1.2),
                },
                Door {
                    inside: Point2::new(10.6, 9.5),
                    outside: Point2::new(10.6, 11.2),
                },
                Door {
                    inside: Point2::new(0.5, 4.8),
                    outside: Point2::new(-1.2, 4.8),
                },
            ],
            coffee: vec![Point2::new(2.2, 8.8), Point2::new(3.8, 8.8)],
            desks: vec![
                Point2::new(14.6, 2.5),
                Point2::new(14.6, 5.0),
                Point2::new(14.6, 7.5),
            ],
            waypoints: vec![
                Point2::new(1.5, 1.5),
                Point2::new(7.6, 1.5),
                Point2::new(13.5, 1.5),
                Point2::new(13.5, 8.3),
                Point2::new(8.0, 8.3),
                Point2::new(1.5, 7.8),
                Point2::new(1.5, 1.5),
            ],
        }
    }

    /// The office if it is usable.
    ///
    /// # Errors
    /// [`SimError::NoLayouts`] without layouts; [`SimError::InvalidOffice`] for a
    /// non-finite or empty area, a non-finite or degenerate shape, no door, or a
    /// non-finite place; [`SimError::TooFewWaypoints`] for fewer than two distinct finite
    /// waypoints.
    pub fn check(self) -> Result<Self> {
        let bad = |what, index, reason| {
            Err(SimError::InvalidOffice {
                what,
                index,
                reason,
            })
        };
        let finite = |p: &Point2<f64>| p.iter().all(|v| v.is_finite());
        if !(finite(&self.min) && finite(&self.max))
            || self.max.x <= self.min.x
            || self.max.y <= self.min.y
        {
            return bad("area", 0, "min and max must be finite with max > min");
        }
        if self.layouts.is_empty() {
            return Err(SimError::NoLayouts);
        }
        for (i, w) in self.walls.iter().enumerate() {
            if !w.is_valid() {
                return bad("wall", i, "non-finite or negative size");
            }
        }
        for (i, f) in self.fixed.iter().enumerate() {
            if !f.is_valid() {
                return bad("fixed furniture", i, "non-finite or non-positive size");
            }
        }
        for (i, l) in self.layouts.iter().enumerate() {
            if !l.furniture.iter().all(Furniture::is_valid) {
                return bad("layout", i, "a piece is non-finite or of non-positive size");
            }
        }
        if self.doors.is_empty() {
            return bad("door", 0, "at least one door is needed");
        }
        for (i, d) in self.doors.iter().enumerate() {
            if !(finite(&d.inside) && finite(&d.outside)) {
                return bad("door", i, "non-finite position");
            }
        }
        for (what, list) in [("coffee", &self.coffee), ("desk", &self.desks)] {
            if let Some(i) = list.iter().position(|p| !finite(p)) {
                return bad(what, i, "non-finite position");
            }
        }
        let usable: Vec<_> = self.waypoints.iter().filter(|p| finite(p)).collect();
        let distinct = usable.windows(2).filter(|w| w[0] != w[1]).count();
        if usable.len() != self.waypoints.len() || distinct == 0 {
            return Err(SimError::TooFewWaypoints {
                count: usable.len().min(distinct + 1),
            });
        }
        Ok(self)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn builtin_is_valid_and_has_places() {
        let o = Office::builtin();
        assert!(o.clone().check().is_ok());
        assert!(o.layouts.len() >= 4);
        for l in &o.layouts {
            let places: usize = l.furniture.iter().map(|f| f.places().len()).sum();
            assert!(places >= 4, "{} has {places} places", l.name);
        }
    }

    #[test]
    fn bad_office_is_refused() {
        let mut o = Office::builtin();
        o.layouts.clear();
        assert!(matches!(o.check(), Err(SimError::NoLayouts)));
        let mut o = Office::builtin();
        o.waypoints = vec![Point2::new(1.0, 1.0)];
        assert!(matches!(o.check(), Err(SimError::TooFewWaypoints { .. })));
        let mut o = Office::builtin();
        o.walls.push(Shape::Circle {
            center: Point2::new(f64::NAN, 0.0),
            radius: 1.0,
        });
        assert!(matches!(o.check(), Err(SimError::InvalidOffice { .. })));
    }
}
