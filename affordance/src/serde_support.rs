//! Support of the `serde` feature: how nalgebra vectors and matrices, and pairs of report
//! values that may be infinite (`haunts_occupancy::serde_float`), are written.
//!
//! Matrices are written as arrays of rows (row-major, human-readable) and read back with their
//! shape checked, without nalgebra's own representation (whose reader multiplies the declared
//! sizes unchecked).

use haunts_occupancy::serde_float::Lenient;
use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Deserializer, Serialize, Serializer};

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
