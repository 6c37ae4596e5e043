//! What every haunts crate shares and none owns: [`InvalidParameter`], the error of a
//! parameter that breaks its rule; the checks that make it ([`positive`], [`non_negative`],
//! [`fraction`], [`at_least_one`]); and [`median`], the median of a sample.
//!
//! Every crate's error enum has a variant `InvalidParameter(InvalidParameter)` converted
//! `From` this type, so a check reads the same everywhere and `?` lifts it into the crate's
//! own error:
//!
//! ```
//! use haunts_core::{positive, InvalidParameter};
//!
//! #[derive(Debug, thiserror::Error)]
//! enum MyError {
//!     #[error(transparent)]
//!     InvalidParameter(#[from] InvalidParameter),
//! }
//!
//! fn cell_size(resolution: f64) -> Result<f64, MyError> {
//!     Ok(positive("resolution", resolution)?)
//! }
//!
//! assert_eq!(cell_size(0.05).unwrap(), 0.05);
//! let err = cell_size(f64::NAN).unwrap_err();
//! assert!(matches!(err, MyError::InvalidParameter(InvalidParameter { name: "resolution", .. })));
//! assert_eq!(err.to_string(), "parameter `resolution` = NaN: must be finite and > 0");
//! ```

/// A parameter that breaks its rule: its name (a field path such as `jitter.growth`), the
/// value it had (counts converted to `f64`) and the rule, in words.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
#[error("parameter `{name}` = {value}: {rule}")]
pub struct InvalidParameter {
    /// The parameter.
    pub name: &'static str,
    /// Its value.
    pub value: f64,
    /// The rule it broke.
    pub rule: &'static str,
}

impl InvalidParameter {
    /// `name` = `value` broke `rule`.
    pub fn new(name: &'static str, value: f64, rule: &'static str) -> Self {
        Self { name, value, rule }
    }
}

/// `value` if it is finite and above zero.
///
/// # Errors
/// [`InvalidParameter`] (`"must be finite and > 0"`) otherwise, NaN included.
pub fn positive(name: &'static str, value: f64) -> Result<f64, InvalidParameter> {
    if value.is_finite() && value > 0.0 {
        Ok(value)
    } else {
        Err(InvalidParameter::new(name, value, "must be finite and > 0"))
    }
}

/// `value` if it is finite and not below zero.
///
/// # Errors
/// [`InvalidParameter`] (`"must be finite and >= 0"`) otherwise, NaN included.
pub fn non_negative(name: &'static str, value: f64) -> Result<f64, InvalidParameter> {
    if value.is_finite() && value >= 0.0 {
        Ok(value)
    } else {
        Err(InvalidParameter::new(
            name,
            value,
            "must be finite and >= 0",
        ))
    }
}

/// `value` if it is a fraction in (0, 1] (a share, a probability that must not be zero).
///
/// # Errors
/// [`InvalidParameter`] (`"must be in (0, 1]"`) otherwise, NaN included.
pub fn fraction(name: &'static str, value: f64) -> Result<f64, InvalidParameter> {
    if value > 0.0 && value <= 1.0 {
        Ok(value)
    } else {
        Err(InvalidParameter::new(name, value, "must be in (0, 1]"))
    }
}

/// `value` if it is at least one (a count of scans, folds, trees…).
///
/// # Errors
/// [`InvalidParameter`] (`"must be >= 1"`) for zero.
pub fn at_least_one(name: &'static str, value: usize) -> Result<usize, InvalidParameter> {
    if value >= 1 {
        Ok(value)
    } else {
        Err(InvalidParameter::new(name, value as f64, "must be >= 1"))
    }
}

/// The median of `values`: the element of rank ⌊n/2⌋ in [`f64::total_cmp`]'s order, so the
/// upper of the two middle elements for an even count (no averaging: the result is one of
/// the values, which keeps a median interval an interval that occurred). `None` when empty.
///
/// Reorders `values` (a selection, O(n) on average). NaNs sort after every number (and
/// negative NaNs before), as `total_cmp` orders them; filter them out first if they are not
/// values.
///
/// ```
/// let mut gaps = [0.1, 0.1, 3.0, 0.1, 0.2];
/// assert_eq!(haunts_core::median(&mut gaps), Some(0.1));
/// assert_eq!(haunts_core::median(&mut [1.0, 2.0]), Some(2.0));
/// assert_eq!(haunts_core::median(&mut []), None);
/// ```
pub fn median(values: &mut [f64]) -> Option<f64> {
    if values.is_empty() {
        return None;
    }
    let mid = values.len() / 2;
    Some(*values.select_nth_unstable_by(mid, f64::total_cmp).1)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn checks_name_the_parameter_and_the_rule() {
        assert_eq!(positive("a", 1.5), Ok(1.5));
        for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            let e = positive("a", bad).unwrap_err();
            assert_eq!((e.name, e.rule), ("a", "must be finite and > 0"));
        }
        assert_eq!(non_negative("b", 0.0), Ok(0.0));
        for bad in [-1e-300, f64::NAN, f64::NEG_INFINITY] {
            assert_eq!(
                non_negative("b", bad).unwrap_err().rule,
                "must be finite and >= 0"
            );
        }
        assert_eq!(fraction("c", 1.0), Ok(1.0));
        for bad in [0.0, 1.0 + f64::EPSILON, f64::NAN] {
            assert_eq!(fraction("c", bad).unwrap_err().rule, "must be in (0, 1]");
        }
        assert_eq!(at_least_one("d", 1), Ok(1));
        assert_eq!(
            at_least_one("d", 0),
            Err(InvalidParameter::new("d", 0.0, "must be >= 1"))
        );
    }

    proptest! {
        /// The median against sorting the whole sample: the element of rank ⌊n/2⌋, with at
        /// least half the values at or below it and at least half at or above it.
        #[test]
        fn median_is_the_middle_of_the_sorted_sample(
            values in proptest::collection::vec(-1e6f64..1e6, 0..60)
        ) {
            let mut sorted = values.clone();
            sorted.sort_by(f64::total_cmp);
            let got = median(&mut values.clone());
            prop_assert_eq!(got, sorted.get(sorted.len() / 2).copied());
            if let Some(m) = got {
                let n = values.len();
                prop_assert!(2 * values.iter().filter(|v| **v <= m).count() > n);
                prop_assert!(2 * values.iter().filter(|v| **v >= m).count() >= n);
            }
        }
    }
}
