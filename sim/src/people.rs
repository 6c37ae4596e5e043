//! People with daily rhythms: visits drawn from a time-of-day rate with morning and lunch
//! peaks, walks door → place → door, groups lingering at the day's tables, and two leg
//! circles per person that swing while walking.

use nalgebra::{Point2, Vector2};
use rand::{RngExt, SeedableRng, rngs::Xoshiro256PlusPlus};
use rand_distr::{Distribution, Poisson, StandardNormal};

use crate::error::{Result, invalid};
use crate::office::{Furniture, Office};
use crate::rng::{Stream, stream_seed};
use crate::shapes::Shape;

/// Largest accepted expected number of visits per day.
pub(crate) const MAX_VISITS_PER_DAY: f64 = 100_000.0;

/// A Gaussian bump of the arrival rate around a time of day.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct RatePeak {
    /// Centre, seconds after midnight.
    pub time: f64,
    /// Standard deviation, seconds.
    pub width: f64,
    /// Share of the visits in this peak, relative to the other peaks and the background.
    pub weight: f64,
    /// Relative weights of coffee, table and desk visits of this peak's arrivals (`None`:
    /// [`PeopleParams::activity_weights`], as for the background): what people come for
    /// depends on the time of day.
    pub activity_weights: Option<[f64; 3]>,
}

/// Why a person comes into the room.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Activity {
    /// A short stop at the coffee machine.
    Coffee,
    /// Lingering at a table or sofa of the day's layout, often in a group.
    Table,
    /// Working at one of the fixed desks.
    Desk,
}

/// Parameters of the people.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub struct PeopleParams {
    /// Expected number of visits (arrivals of groups or single people) per day.
    pub visits_per_day: f64,
    /// Start of the working day, seconds after midnight.
    pub open: f64,
    /// End of the working day, seconds after midnight (> `open`).
    pub close: f64,
    /// Share of the visits spread uniformly over the working day.
    pub background: f64,
    /// Peaks of the arrival rate.
    pub peaks: Vec<RatePeak>,
    /// Relative weights of coffee, table and desk visits.
    pub activity_weights: [f64; 3],
    /// Probability that a table visit is a group.
    pub group_probability: f64,
    /// Probability that a table or desk visitor first stops at the coffee machine.
    pub coffee_first: f64,
    /// Largest group (≥ 1); groups are 2..=max_group people, capped by the places.
    pub max_group: usize,
    /// Dwell time ranges `(min, max)`, seconds, for coffee, table and desk visits.
    pub dwell: [(f64, f64); 3],
    /// Mean walking speed, m/s.
    pub speed: f64,
    /// Standard deviation of a person's walking speed, m/s.
    pub speed_sd: f64,
    /// Radius of a leg, metres.
    pub leg_radius: f64,
    /// Half the lateral distance between the legs' centres, metres.
    pub leg_spread: f64,
    /// Distance walked per gait cycle, metres.
    pub stride: f64,
    /// Amplitude of the legs' forward/backward swing while walking, metres.
    pub swing: f64,
}

impl Default for PeopleParams {
    /// 160 visits over 7:00–19:00 with peaks at 9:30 (mostly coffee), 12:45 (mostly
    /// tables: lunch) and 15:30 (coffee and tables); the background visits come for coffee,
    /// a table or a desk in proportions 0.35, 0.45, 0.2.
    fn default() -> Self {
        let h = 3600.0;
        Self {
            visits_per_day: 160.0,
            open: 7.0 * h,
            close: 19.0 * h,
            background: 0.5,
            peaks: vec![
                RatePeak {
                    time: 9.5 * h,
                    width: 0.6 * h,
                    weight: 1.0,
                    activity_weights: Some([0.7, 0.1, 0.2]),
                },
                RatePeak {
                    time: 12.75 * h,
                    width: 0.5 * h,
                    weight: 1.2,
                    activity_weights: Some([0.1, 0.85, 0.05]),
                },
                RatePeak {
                    time: 15.5 * h,
                    width: 0.6 * h,
                    weight: 0.5,
                    activity_weights: Some([0.5, 0.35, 0.15]),
                },
            ],
            activity_weights: [0.35, 0.45, 0.2],
            group_probability: 0.6,
            coffee_first: 0.3,
            max_group: 4,
            dwell: [(60.0, 300.0), (300.0, 1800.0), (600.0, 3600.0)],
            speed: 1.1,
            speed_sd: 0.15,
            leg_radius: 0.06,
            leg_spread: 0.1,
            stride: 1.2,
            swing: 0.15,
        }
    }
}

impl PeopleParams {
    /// The parameters if usable.
    ///
    /// # Errors
    /// [`SimError::InvalidParameter`](crate::SimError::InvalidParameter) naming the first field that breaks its rule: finite
    /// values, `0 ≤ visits_per_day ≤ 100 000`, `open < close` within the day, non-negative
    /// weights with a positive sum, positive peak widths, probabilities in `[0, 1]`,
    /// `max_group ≥ 1`, `0 ≤ min ≤ max` dwell ranges, positive speed, leg radius, stride.
    pub fn check(self) -> Result<Self> {
        let v = self.visits_per_day;
        if !(v.is_finite() && (0.0..=MAX_VISITS_PER_DAY).contains(&v)) {
            return Err(invalid("people.visits_per_day", v, "must be in 0..=100000"));
        }
        if !(self.open.is_finite() && self.open >= 0.0) {
            return Err(invalid("people.open", self.open, "must be finite, >= 0"));
        }
        if !(self.close.is_finite() && self.close > self.open && self.close <= 86_400.0) {
            return Err(invalid(
                "people.close",
                self.close,
                "must be in (open, 86400]",
            ));
        }
        if !(self.background.is_finite() && self.background >= 0.0) {
            return Err(invalid(
                "people.background",
                self.background,
                "must be >= 0",
            ));
        }
        let mut total = self.background;
        for p in &self.peaks {
            if !(p.time.is_finite() && p.width.is_finite() && p.width > 0.0) {
                return Err(invalid(
                    "people.peaks.width",
                    p.width,
                    "must be finite and > 0",
                ));
            }
            if !(p.weight.is_finite() && p.weight >= 0.0) {
                return Err(invalid("people.peaks.weight", p.weight, "must be >= 0"));
            }
            total += p.weight;
        }
        if !(total > 0.0 && total.is_finite()) {
            return Err(invalid("people.background", total, "weights sum > 0"));
        }
        let weights = std::iter::once(self.activity_weights)
            .chain(self.peaks.iter().filter_map(|p| p.activity_weights));
        for a in weights {
            if !a.iter().all(|w| w.is_finite() && *w >= 0.0) || a.iter().sum::<f64>() <= 0.0 {
                return Err(invalid(
                    "people.activity_weights",
                    a.iter().sum(),
                    "non-negative with a positive sum",
                ));
            }
        }
        for (name, p) in [
            ("people.group_probability", self.group_probability),
            ("people.coffee_first", self.coffee_first),
        ] {
            if !(0.0..=1.0).contains(&p) {
                return Err(invalid(name, p, "in [0, 1]"));
            }
        }
        if self.max_group == 0 {
            return Err(invalid("people.max_group", 0.0, "must be >= 1"));
        }
        for (lo, hi) in self.dwell {
            if !(lo.is_finite() && hi.is_finite() && lo >= 0.0 && hi >= lo && hi <= 86_400.0) {
                return Err(invalid(
                    "people.dwell",
                    hi,
                    "must be 0 <= min <= max <= 86400",
                ));
            }
        }
        let positive = [
            ("people.speed", self.speed),
            ("people.leg_radius", self.leg_radius),
            ("people.stride", self.stride),
        ];
        for (name, x) in positive {
            if !(x.is_finite() && x > 0.0 && x < 100.0) {
                return Err(invalid(name, x, "finite, > 0 and < 100"));
            }
        }
        for (name, x) in [
            ("people.speed_sd", self.speed_sd),
            ("people.leg_spread", self.leg_spread),
            ("people.swing", self.swing),
        ] {
            if !(0.0..100.0).contains(&x) {
                return Err(invalid(name, x, "finite, >= 0 and < 100"));
            }
        }
        Ok(self)
    }

    /// Relative arrival rate at `time` (seconds after midnight), integrating to 1 over the
    /// day when the peaks lie well inside the working day: the background's uniform density
    /// plus each peak's Gaussian, weighted by their shares.
    pub fn rate(&self, time: f64) -> f64 {
        if time < self.open || time > self.close {
            return 0.0;
        }
        let total = self.background + self.peaks.iter().map(|p| p.weight).sum::<f64>();
        let mut r = self.background / (self.close - self.open);
        for p in &self.peaks {
            let z = (time - p.time) / p.width;
            r += p.weight * (-0.5 * z * z).exp() / (p.width * (std::f64::consts::TAU).sqrt());
        }
        r / total
    }

    /// An arrival time and the activity weights of the part of the rate it came from.
    fn arrival(&self, rng: &mut Xoshiro256PlusPlus) -> (f64, [f64; 3]) {
        let total = self.background + self.peaks.iter().map(|p| p.weight).sum::<f64>();
        let mut pick = rng.random::<f64>() * total;
        for p in &self.peaks {
            if pick < p.weight {
                let weights = p.activity_weights.unwrap_or(self.activity_weights);
                for _ in 0..16 {
                    let n: f64 = StandardNormal.sample(rng);
                    let t = p.time + p.width * n;
                    if (self.open..self.close).contains(&t) {
                        return (t, weights);
                    }
                }
                return (p.time.clamp(self.open, self.close), weights);
            }
            pick -= p.weight;
        }
        (
            rng.random_range(self.open..self.close),
            self.activity_weights,
        )
    }
}

/// One point of a person's piecewise-linear path.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
struct Key {
    t: f64,
    p: Point2<f64>,
    /// Distance walked since the start of the visit.
    s: f64,
}

/// One person's visit to the room: a piecewise-linear path with a stop at a place.
///
/// With the `serde` feature a visit (de)serialises with its path as `keys`, a list of
/// `{t, p, s}` (time, position, distance walked); deserialising checks that the place, the
/// facing and every key are finite, that there are at least two keys (arrival and departure)
/// and that time and distance never decrease along them.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(try_from = "VisitFields"))]
pub struct Visit {
    /// Identifier, unique over all days (`day · 10⁶ + index`).
    pub id: u64,
    /// Why the person came.
    pub activity: Activity,
    /// Where the person stops.
    pub place: Point2<f64>,
    /// Heading while standing at the place, radians.
    pub facing: f64,
    keys: Vec<Key>,
}

/// Ground truth of one person at one instant.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct PersonTruth {
    /// The visit's identifier.
    pub id: u64,
    /// Position (the midpoint between the legs), metres.
    pub position: Point2<f64>,
    /// Velocity, m/s (zero while standing).
    pub velocity: Vector2<f64>,
    /// Laser beams of the scan that returned from this person's legs (after the laser's
    /// dropouts and spurious max-range returns): in [`Day::people`](crate::Day::people),
    /// how well the laser saw the person; 0 from [`Visit::at`], which knows no scan.
    pub beams: usize,
}

/// The fields of a [`Visit`] as deserialised, before they are checked.
#[cfg(feature = "serde")]
#[derive(serde::Deserialize)]
struct VisitFields {
    id: u64,
    activity: Activity,
    place: Point2<f64>,
    facing: f64,
    keys: Vec<Key>,
}

#[cfg(feature = "serde")]
impl TryFrom<VisitFields> for Visit {
    type Error = crate::SimError;
    fn try_from(f: VisitFields) -> Result<Self> {
        // The first coordinate of `p` that is not finite.
        let non_finite = |p: &Point2<f64>| p.iter().copied().find(|v| !v.is_finite());
        if let Some(v) = non_finite(&f.place) {
            return Err(invalid("visit.place", v, "must be finite"));
        }
        if !f.facing.is_finite() {
            return Err(invalid("visit.facing", f.facing, "must be finite"));
        }
        if f.keys.len() < 2 {
            return Err(invalid(
                "visit.keys",
                f.keys.len() as f64,
                "at least 2 keys (arrival and departure)",
            ));
        }
        let mut previous: Option<Key> = None;
        for k in &f.keys {
            if let Some(v) = non_finite(&k.p) {
                return Err(invalid("visit.keys.p", v, "must be finite"));
            }
            if !(k.t.is_finite() && previous.is_none_or(|q| k.t >= q.t)) {
                return Err(invalid(
                    "visit.keys.t",
                    k.t,
                    "must be finite and non-decreasing",
                ));
            }
            if !(k.s.is_finite() && k.s >= previous.map_or(0.0, |q| q.s)) {
                return Err(invalid(
                    "visit.keys.s",
                    k.s,
                    "finite, >= 0 and non-decreasing",
                ));
            }
            previous = Some(*k);
        }
        Ok(Self {
            id: f.id,
            activity: f.activity,
            place: f.place,
            facing: f.facing,
            keys: f.keys,
        })
    }
}

impl Visit {
    /// When the person appears (at a door, outside the room), seconds of UNIX time.
    pub fn arrival(&self) -> f64 {
        self.keys.first().map_or(0.0, |k| k.t)
    }
    /// When the person vanishes (outside the room).
    pub fn departure(&self) -> f64 {
        self.keys.last().map_or(0.0, |k| k.t)
    }

    /// The path as `(time, position)` corners: door outside, door inside, stops (a
    /// repeated position with a later time is a stay), door inside, door outside.
    pub fn path(&self) -> impl Iterator<Item = (f64, Point2<f64>)> + '_ {
        self.keys.iter().map(|k| (k.t, k.p))
    }

    /// Position, velocity, heading and distance walked at `t`, if the person is present.
    fn state(&self, t: f64) -> Option<(Point2<f64>, Vector2<f64>, f64, f64)> {
        if t < self.arrival() || t > self.departure() {
            return None;
        }
        for w in self.keys.windows(2) {
            let (a, b) = (w[0], w[1]);
            if t <= b.t {
                let span = b.t - a.t;
                let f = if span > 0.0 { (t - a.t) / span } else { 1.0 };
                let d = b.p - a.p;
                let p = a.p + d * f;
                let s = a.s + (b.s - a.s) * f;
                return Some(if d.norm() > 0.0 && span > 0.0 {
                    (p, d / span, d.y.atan2(d.x), s)
                } else {
                    (p, Vector2::zeros(), self.facing, s)
                });
            }
        }
        None
    }

    /// Ground truth at `t`, if the person is present.
    pub fn at(&self, t: f64) -> Option<PersonTruth> {
        self.state(t).map(|(position, velocity, _, _)| PersonTruth {
            id: self.id,
            beams: 0,
            position,
            velocity,
        })
    }

    /// The two leg circles at `t` (none if absent): side by side while standing, swinging
    /// forward and back in antiphase while walking.
    pub fn legs(&self, t: f64, params: &PeopleParams) -> Option<[Shape; 2]> {
        let (p, v, heading, s) = self.state(t)?;
        let fwd = Vector2::new(heading.cos(), heading.sin());
        let side = Vector2::new(-fwd.y, fwd.x) * params.leg_spread;
        let swing = if v.norm() > 0.0 {
            params.swing * (std::f64::consts::TAU * s / params.stride).sin()
        } else {
            0.0
        };
        let leg = |sign: f64| Shape::Circle {
            center: p + side * sign + fwd * (swing * sign),
            radius: params.leg_radius,
        };
        Some([leg(1.0), leg(-1.0)])
    }
}

/// Places are held by one person at a time: people do not stand inside each other (two
/// people at one spot would be one pair of legs to the laser and two people to the truth).
/// A place is taken while anyone stays within [`PLACE_CLEARANCE`] of it.
#[derive(Debug, Default)]
struct Reservations(Vec<(Point2<f64>, (f64, f64))>);

/// Closest two standing people may be, metres (centre to centre): about a body's width.
const PLACE_CLEARANCE: f64 = 0.45;

/// Slack around a stay, seconds: arriving at and leaving a place is not instantaneous.
const STAY_SLACK: f64 = 3.0;

impl Reservations {
    /// Whether nobody stays near `place` during `(from, to)`.
    fn is_free(&self, place: Point2<f64>, (from, to): (f64, f64)) -> bool {
        self.0.iter().all(|(p, (a, b))| {
            (p - place).norm() >= PLACE_CLEARANCE
                || *b + STAY_SLACK <= from
                || to + STAY_SLACK <= *a
        })
    }

    fn take(&mut self, place: Point2<f64>, stay: (f64, f64)) {
        self.0.push((place, stay));
    }
}

/// Builds a path key by key at a walking speed.
struct Walker {
    keys: Vec<Key>,
    speed: f64,
}

impl Walker {
    fn new(t: f64, p: Point2<f64>, speed: f64) -> Self {
        Self {
            keys: vec![Key { t, p, s: 0.0 }],
            speed,
        }
    }

    fn last(&self) -> Key {
        self.keys[self.keys.len() - 1]
    }

    /// When a walk to `to` followed by a pause there would arrive and leave.
    fn stop_at(&self, to: Point2<f64>, pause: f64) -> (f64, f64) {
        let last = self.last();
        let t = last.t + (to - last.p).norm() / self.speed;
        (t, t + pause)
    }

    /// Walks to `to`, then stays `pause` seconds.
    fn walk(&mut self, to: Point2<f64>, pause: f64) {
        let last = self.last();
        let d = (to - last.p).norm();
        let k = Key {
            t: last.t + d / self.speed,
            p: to,
            s: last.s + d,
        };
        self.keys.push(k);
        if pause > 0.0 {
            self.keys.push(Key {
                t: k.t + pause,
                ..k
            });
        }
    }
}

/// Shuffles `items` in place (Fisher–Yates).
fn shuffle<T>(items: &mut [T], rng: &mut Xoshiro256PlusPlus) {
    for i in (1..items.len()).rev() {
        let j = rng.random_range(0..=i);
        items.swap(i, j);
    }
}

/// Draws the visits of one day for the day's furniture.
pub(crate) fn draw_visits(
    office: &Office,
    furniture: &[Furniture],
    params: &PeopleParams,
    seed: u64,
    day: usize,
    day_start: f64,
) -> Vec<Visit> {
    let mut rng =
        Xoshiro256PlusPlus::seed_from_u64(stream_seed(seed, day as u64, Stream::People, 0));
    let count = match Poisson::new(params.visits_per_day) {
        Ok(p) => p.sample(&mut rng) as usize,
        Err(_) => 0,
    };
    let tables: Vec<(Point2<f64>, Vec<Point2<f64>>)> = furniture
        .iter()
        .map(|f| (f.center, f.places()))
        .filter(|(_, p)| !p.is_empty())
        .collect();
    let mut visits = Vec::new();
    let mut reserved = Reservations::default();
    let base_id = day as u64 * 1_000_000;
    for _ in 0..count {
        let (t0, mut w) = params.arrival(&mut rng);
        let t0 = day_start + t0;
        if tables.is_empty() {
            w[1] = 0.0;
        }
        if office.coffee.is_empty() {
            w[0] = 0.0;
        }
        if office.desks.is_empty() {
            w[2] = 0.0;
        }
        let total: f64 = w.iter().sum();
        if total <= 0.0 {
            break;
        }
        let mut pick = rng.random::<f64>() * total;
        let mut activity = 2;
        for (i, wi) in w.iter().enumerate() {
            if pick < *wi {
                activity = i;
                break;
            }
            pick -= wi;
        }
        let (lo, hi) = params.dwell[activity];
        let dwell = lo + (hi - lo) * rng.random::<f64>();
        let door = rng.random_range(0..office.doors.len());
        // Candidate places (in order of preference) and the facing point, per member: a
        // member takes the first candidate that is free for the whole stay.
        let (candidates, face, size): (Vec<Point2<f64>>, Option<Point2<f64>>, usize) =
            match activity {
                0 => {
                    let mut order = office.coffee.clone();
                    shuffle(&mut order, &mut rng);
                    (order, None, 1)
                }
                1 => {
                    let (center, places) = &tables[rng.random_range(0..tables.len())];
                    let size = if params.max_group > 1 && rng.random_bool(params.group_probability)
                    {
                        rng.random_range(2..=params.max_group).min(places.len())
                    } else {
                        1
                    };
                    let mut order = places.clone();
                    shuffle(&mut order, &mut rng);
                    (order, Some(*center), size)
                }
                _ => {
                    let mut order = office.desks.clone();
                    shuffle(&mut order, &mut rng);
                    (order, None, 1)
                }
            };
        let activity = [Activity::Coffee, Activity::Table, Activity::Desk][activity];
        for m in 0..size {
            let n: f64 = StandardNormal.sample(&mut rng);
            let speed = (params.speed + params.speed_sd * n)
                .max(0.3 * params.speed)
                .min(3.0 * params.speed);
            let exit = rng.random_range(0..office.doors.len());
            let start = t0 + m as f64 * rng.random_range(2.0..15.0);
            let stay = dwell + rng.random_range(0.0..60.0);
            let (din, dout) = (office.doors[door], office.doors[exit]);
            let coffee_stop = (activity != Activity::Coffee
                && !office.coffee.is_empty()
                && rng.random::<f64>() < params.coffee_first)
                .then(|| {
                    let c = rng.random_range(0..office.coffee.len());
                    (c, rng.random_range(20.0..90.0))
                });
            // Nobody stands on the very spot of the last person: 10 cm and 0.3 rad of
            // scatter around the place and its heading.
            let (jx, jy, jh): (f64, f64, f64) = (
                StandardNormal.sample(&mut rng),
                StandardNormal.sample(&mut rng),
                StandardNormal.sample(&mut rng),
            );
            let scatter = Vector2::new(jx, jy) * 0.1;
            let mut walker = Walker::new(start, din.outside, speed);
            walker.walk(din.inside, 0.0);
            if let Some((c, pause)) = coffee_stop {
                // The other coffee points in turn if this one is taken; no stop if all are.
                let k = office.coffee.len();
                if let Some(point) = (0..k)
                    .map(|i| office.coffee[(c + i) % k])
                    .find(|&point| reserved.is_free(point, walker.stop_at(point, pause)))
                {
                    reserved.take(point, walker.stop_at(point, pause));
                    walker.walk(point, pause);
                }
            }
            // A member whose places are all taken does not come in.
            let Some(place) = candidates
                .iter()
                .map(|&p| p + scatter)
                .find(|&p| reserved.is_free(p, walker.stop_at(p, stay)))
            else {
                continue;
            };
            reserved.take(place, walker.stop_at(place, stay));
            walker.walk(place, stay);
            walker.walk(dout.inside, 0.0);
            walker.walk(dout.outside, 0.0);
            let approach = place - din.inside;
            let facing = match face {
                Some(c) => (c - place).y.atan2((c - place).x),
                None => approach.y.atan2(approach.x),
            } + 0.3 * jh;
            visits.push(Visit {
                id: base_id + visits.len() as u64,
                activity,
                place,
                facing,
                keys: walker.keys,
            });
        }
    }
    visits
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn rate_integrates_to_one_and_peaks_at_lunch() {
        let p = PeopleParams::default();
        let step = 10.0;
        let total: f64 = (0..8640).map(|i| p.rate(i as f64 * step) * step).sum();
        assert_relative_eq!(total, 1.0, epsilon = 0.01);
        assert!(p.rate(12.75 * 3600.0) > 3.0 * p.rate(17.5 * 3600.0));
        assert!(p.rate(9.5 * 3600.0) > 2.0 * p.rate(11.0 * 3600.0));
    }

    #[test]
    fn walking_legs_swing_standing_legs_do_not() {
        let office = Office::builtin();
        let params = PeopleParams::default();
        let visits = draw_visits(&office, &office.layouts[0].furniture, &params, 1, 0, 0.0);
        let v = &visits[0];
        let spread = |t: f64| {
            let [a, b] = v.legs(t, &params).unwrap();
            match (a, b) {
                (Shape::Circle { center: a, .. }, Shape::Circle { center: b, .. }) => {
                    (a - b).norm()
                }
                _ => unreachable!(),
            }
        };
        // Standing at the place: legs exactly 2·leg_spread apart.
        let stand = v.keys[2].t + 1.0;
        assert_relative_eq!(spread(stand), 2.0 * params.leg_spread, epsilon = 1e-9);
        // Walking: the distance varies along the way in.
        let (t0, t1) = (v.keys[0].t, v.keys[2].t);
        let max = (0..50)
            .map(|i| spread(t0 + (t1 - t0) * i as f64 / 50.0))
            .fold(0.0, f64::max);
        assert!(max > 2.0 * params.leg_spread + 0.05);
        assert!(v.at(v.departure() + 1.0).is_none());
    }

    #[test]
    fn bad_params_are_refused() {
        let d = PeopleParams::default;
        let bad = [
            PeopleParams {
                visits_per_day: f64::NAN,
                ..d()
            },
            PeopleParams {
                close: d().open,
                ..d()
            },
            PeopleParams {
                activity_weights: [0.0; 3],
                ..d()
            },
            PeopleParams {
                max_group: 0,
                ..d()
            },
            PeopleParams {
                speed_sd: f64::INFINITY,
                ..d()
            },
        ];
        for p in bad {
            assert!(p.clone().check().is_err(), "{p:?}");
        }
        assert!(PeopleParams::default().check().is_ok());
    }
}
