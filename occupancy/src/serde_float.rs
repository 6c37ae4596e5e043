//! `f64` values that may be non-finite — a laser's `+inf` "no return", NaN dropouts, a score
//! of `−∞` — written so that they read back (feature `serde`).
//!
//! Human-readable formats whose numbers cannot be non-finite (JSON writes them as `null`, and
//! then refuses to read `null` as a number) get the strings `"inf"`, `"-inf"` and `"NaN"` for
//! them; finite values, and every value in other formats, are plain `f64`s. `null` is never
//! accepted. Use with `#[serde(with = "haunts_occupancy::serde_float::vec")]` (or `value`,
//! `option`), or wrap a value in [`Lenient`].
//!
//! ```
//! # #[cfg(feature = "serde")] {
//! use haunts_occupancy::LaserScan;
//! let scan = LaserScan::new(0.0, 0.0, 0.1, 0.1, 8.0, vec![1.5, f64::INFINITY, f64::NAN], vec![])?;
//! let text = serde_json::to_string(&scan).expect("writes");
//! assert!(text.contains(r#"[1.5,"inf","NaN"]"#));
//! let back: LaserScan = serde_json::from_str(&text).expect("reads");
//! assert_eq!(back.ranges[1], f64::INFINITY);
//! assert!(back.ranges[2].is_nan());
//! # }
//! # Ok::<(), haunts_occupancy::OccupancyError>(())
//! ```

use std::fmt;

use serde::de::{self, Unexpected, Visitor};
use serde::{Deserialize, Deserializer, Serialize, Serializer};

/// An `f64` that may be non-finite, (de)serialised as the [module](self) says.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Lenient(pub f64);

impl Serialize for Lenient {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let v = self.0;
        if v.is_finite() || !s.is_human_readable() {
            s.serialize_f64(v)
        } else if v.is_nan() {
            s.serialize_str("NaN")
        } else if v > 0.0 {
            s.serialize_str("inf")
        } else {
            s.serialize_str("-inf")
        }
    }
}

struct LenientVisitor;

impl Visitor<'_> for LenientVisitor {
    type Value = Lenient;
    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(r#"a number, or "inf", "-inf" or "NaN""#)
    }
    fn visit_f64<E: de::Error>(self, v: f64) -> Result<Lenient, E> {
        Ok(Lenient(v))
    }
    fn visit_i64<E: de::Error>(self, v: i64) -> Result<Lenient, E> {
        Ok(Lenient(v as f64))
    }
    fn visit_u64<E: de::Error>(self, v: u64) -> Result<Lenient, E> {
        Ok(Lenient(v as f64))
    }
    fn visit_str<E: de::Error>(self, v: &str) -> Result<Lenient, E> {
        match v {
            "inf" => Ok(Lenient(f64::INFINITY)),
            "-inf" => Ok(Lenient(f64::NEG_INFINITY)),
            "NaN" => Ok(Lenient(f64::NAN)),
            _ => Err(E::invalid_value(Unexpected::Str(v), &self)),
        }
    }
}

impl<'de> Deserialize<'de> for Lenient {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        if d.is_human_readable() {
            d.deserialize_any(LenientVisitor)
        } else {
            f64::deserialize(d).map(Lenient)
        }
    }
}

/// `#[serde(with)]` for an `f64` that may be non-finite.
pub mod value {
    use super::{Deserialize, Deserializer, Lenient, Serialize, Serializer};

    /// Writes `v` (see [`Lenient`]).
    pub fn serialize<S: Serializer>(v: &f64, s: S) -> Result<S::Ok, S::Error> {
        Lenient(*v).serialize(s)
    }
    /// Reads a value written by [`serialize`].
    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
        Ok(Lenient::deserialize(d)?.0)
    }
}

/// `#[serde(with)]` for an `Option<f64>` whose value may be non-finite (`null` is `None`).
pub mod option {
    use super::{Deserialize, Deserializer, Lenient, Serialize, Serializer};

    /// Writes `v` (see [`Lenient`]; `None` as `null`).
    pub fn serialize<S: Serializer>(v: &Option<f64>, s: S) -> Result<S::Ok, S::Error> {
        v.map(Lenient).serialize(s)
    }
    /// Reads a value written by [`serialize`].
    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Option<f64>, D::Error> {
        Ok(Option::<Lenient>::deserialize(d)?.map(|v| v.0))
    }
}

/// `#[serde(with)]` for a `Vec<f64>` whose values may be non-finite (a scan's ranges).
pub mod vec {
    use super::{Deserialize, Deserializer, Lenient, Serializer};

    /// Writes `v` (see [`Lenient`]).
    pub fn serialize<S: Serializer>(v: &[f64], s: S) -> Result<S::Ok, S::Error> {
        s.collect_seq(v.iter().map(|&x| Lenient(x)))
    }
    /// Reads values written by [`serialize`].
    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<f64>, D::Error> {
        Ok(Vec::<Lenient>::deserialize(d)?
            .into_iter()
            .map(|v| v.0)
            .collect())
    }
}
