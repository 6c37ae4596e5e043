//! Support of the `serde` feature: how nalgebra vectors and matrices, and report values that
//! may be infinite, are written.
//!
//! Matrices are written as arrays of rows (row-major, human-readable) and read back with their
//! shape checked, without nalgebra's own representation (whose reader multiplies the declared
//! sizes unchecked).

use std::fmt;

use nalgebra::{DMatrix, DVector};
use serde::de::{self, Unexpected, Visitor};
use serde::{Deserialize, Deserializer, Serialize, Serializer};

/// A report value that may legitimately be infinite or NaN (a membership change of `∞` after
/// one iteration, a score of `−∞`). Human-readable formats, whose numbers cannot be
/// non-finite (JSON writes them as `null`), get the strings `"inf"`, `"-inf"` and `"NaN"`
/// for them; other formats get the plain `f64`. `null` is never accepted.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Lenient(pub(crate) f64);

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

/// `#[serde(with)]` for an `f64` that may be non-finite (see [`Lenient`]).
pub(crate) mod lenient {
    use super::{Deserialize, Deserializer, Lenient, Serialize, Serializer};

    pub(crate) fn serialize<S: Serializer>(v: &f64, s: S) -> Result<S::Ok, S::Error> {
        Lenient(*v).serialize(s)
    }
    pub(crate) fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
        Ok(Lenient::deserialize(d)?.0)
    }
}

/// `#[serde(with)]` for an `Option<f64>` whose value may be non-finite (`null` is `None`).
pub(crate) mod lenient_option {
    use super::{Deserialize, Deserializer, Lenient, Serialize, Serializer};

    pub(crate) fn serialize<S: Serializer>(v: &Option<f64>, s: S) -> Result<S::Ok, S::Error> {
        v.map(Lenient).serialize(s)
    }
    pub(crate) fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Option<f64>, D::Error> {
        Ok(Option::<Lenient>::deserialize(d)?.map(|v| v.0))
    }
}

/// `#[serde(with)]` for `(k, score)` pairs whose scores may be non-finite.
pub(crate) mod lenient_pairs {
    use super::{Deserialize, Deserializer, Lenient, Serializer};

    pub(crate) fn serialize<S: Serializer>(v: &[(usize, f64)], s: S) -> Result<S::Ok, S::Error> {
        s.collect_seq(v.iter().map(|&(k, x)| (k, Lenient(x))))
    }
    pub(crate) fn deserialize<'de, D: Deserializer<'de>>(
        d: D,
    ) -> Result<Vec<(usize, f64)>, D::Error> {
        Ok(Vec::<(usize, Lenient)>::deserialize(d)?
            .into_iter()
            .map(|(k, v)| (k, v.0))
            .collect())
    }
}

/// `#[serde(with)]` for a [`DVector`], as a plain array.
pub(crate) mod vector {
    use super::{DVector, Deserialize, Deserializer, Serialize, Serializer};

    pub(crate) fn serialize<S: Serializer>(v: &DVector<f64>, s: S) -> Result<S::Ok, S::Error> {
        v.as_slice().serialize(s)
    }
    pub(crate) fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<DVector<f64>, D::Error> {
        Ok(DVector::from_vec(Vec::<f64>::deserialize(d)?))
    }
}

/// A square matrix written as its rows.
struct Rows<'a>(&'a DMatrix<f64>);

impl Serialize for Rows<'_> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_seq(
            self.0
                .row_iter()
                .map(|row| row.iter().copied().collect::<Vec<f64>>()),
        )
    }
}

/// The square matrix of `rows`, or why they are not one.
fn from_rows(rows: Vec<Vec<f64>>) -> Result<DMatrix<f64>, String> {
    let n = rows.len();
    if let Some((i, row)) = rows.iter().enumerate().find(|(_, r)| r.len() != n) {
        return Err(format!(
            "matrix is not square: row {i} has {} values for {n} rows",
            row.len()
        ));
    }
    Ok(DMatrix::from_fn(n, n, |i, j| rows[i][j]))
}

/// `#[serde(with)]` for a square [`DMatrix`], as an array of rows.
pub(crate) mod square_matrix {
    use super::{DMatrix, Deserialize, Deserializer, Rows, Serialize, Serializer, from_rows};
    use serde::de::Error;

    pub(crate) fn serialize<S: Serializer>(m: &DMatrix<f64>, s: S) -> Result<S::Ok, S::Error> {
        Rows(m).serialize(s)
    }
    pub(crate) fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<DMatrix<f64>, D::Error> {
        from_rows(Vec::<Vec<f64>>::deserialize(d)?).map_err(D::Error::custom)
    }
}

/// `#[serde(with)]` for square [`DMatrix`]es, each as an array of rows.
pub(crate) mod square_matrices {
    use super::{DMatrix, Deserialize, Deserializer, Rows, Serializer, from_rows};
    use serde::de::Error;

    pub(crate) fn serialize<S: Serializer>(m: &[DMatrix<f64>], s: S) -> Result<S::Ok, S::Error> {
        s.collect_seq(m.iter().map(Rows))
    }
    pub(crate) fn deserialize<'de, D: Deserializer<'de>>(
        d: D,
    ) -> Result<Vec<DMatrix<f64>>, D::Error> {
        Vec::<Vec<Vec<f64>>>::deserialize(d)?
            .into_iter()
            .enumerate()
            .map(|(i, rows)| {
                from_rows(rows).map_err(|e| D::Error::custom(format!("matrix {i}: {e}")))
            })
            .collect()
    }
}
