//! Agreement of a clustering with ground-truth labels: pair counts, Rand index, adjusted Rand
//! index, purity.

use std::collections::BTreeMap;

use crate::error::{Result, SimilarityError};

/// How a clustering and the ground truth agree on the `n(n−1)/2` unordered pairs of items.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Agreement {
    /// Pairs together in both.
    pub together_both: u64,
    /// Pairs together in the prediction only (wrongly merged).
    pub together_predicted_only: u64,
    /// Pairs together in the truth only (wrongly split).
    pub together_truth_only: u64,
    /// Pairs apart in both.
    pub apart_both: u64,
    /// Rand index = pairwise accuracy: the fraction of pairs on which prediction and truth
    /// agree (same layout or not). 1 is perfect; chance level depends on the cluster sizes.
    pub rand_index: f64,
    /// Adjusted Rand index (Hubert & Arabie 1985): the Rand index corrected for chance, 0 in
    /// expectation for random labels, 1 for identical partitions, negative when worse than
    /// chance. As scikit-learn, 1 when both partitions agree on every pair.
    pub adjusted_rand_index: f64,
    /// Fraction of items in the majority true class of their predicted cluster.
    pub purity: f64,
}

/// The agreement of `predicted` with `truth` (labels are arbitrary integers; only equality
/// matters).
///
/// # Errors
/// [`SimilarityError::LengthMismatch`] when the label lists differ in length;
/// [`SimilarityError::TooFew`] for fewer than 2 items (no pair).
///
/// # Complexity
/// O(n log n).
///
/// # Example
/// The examples of scikit-learn's `adjusted_rand_score` documentation:
/// ```
/// use haunts_similarity::agreement;
/// let a = agreement(&[0, 0, 1, 2], &[0, 0, 1, 1]).unwrap();
/// approx::assert_relative_eq!(a.adjusted_rand_index, 4.0 / 7.0, epsilon = 1e-12); // 0.57
/// approx::assert_relative_eq!(a.rand_index, 5.0 / 6.0, epsilon = 1e-12); // 0.83
/// assert_eq!(agreement(&[0, 0, 1, 1], &[1, 1, 0, 0]).unwrap().adjusted_rand_index, 1.0);
/// assert_eq!(agreement(&[0, 0, 0, 0], &[0, 1, 2, 3]).unwrap().adjusted_rand_index, 0.0);
/// assert_eq!(agreement(&[0, 0, 1, 1], &[0, 1, 0, 1]).unwrap().adjusted_rand_index, -0.5);
/// ```
pub fn agreement(predicted: &[usize], truth: &[usize]) -> Result<Agreement> {
    if predicted.len() != truth.len() {
        return Err(SimilarityError::LengthMismatch {
            what: "predicted vs true labels",
            left: predicted.len(),
            right: truth.len(),
        });
    }
    let n = predicted.len() as u64;
    if n < 2 {
        return Err(SimilarityError::TooFew {
            what: "labels",
            found: predicted.len(),
            needed: 2,
        });
    }
    let pairs = |k: u64| k * k.saturating_sub(1) / 2;
    let mut joint: BTreeMap<(usize, usize), u64> = BTreeMap::new();
    let mut rows: BTreeMap<usize, u64> = BTreeMap::new();
    let mut cols: BTreeMap<usize, u64> = BTreeMap::new();
    for (&p, &t) in predicted.iter().zip(truth) {
        *joint.entry((p, t)).or_default() += 1;
        *rows.entry(p).or_default() += 1;
        *cols.entry(t).or_default() += 1;
    }
    let tp: u64 = joint.values().map(|&k| pairs(k)).sum();
    let pred_same: u64 = rows.values().map(|&k| pairs(k)).sum();
    let truth_same: u64 = cols.values().map(|&k| pairs(k)).sum();
    let (fp, fn_) = (pred_same - tp, truth_same - tp);
    let tn = pairs(n) - tp - fp - fn_;
    let rand_index = (tp + tn) as f64 / pairs(n) as f64;
    let adjusted_rand_index = if fp == 0 && fn_ == 0 {
        1.0
    } else {
        let (tp, fp, fn_, tn) = (tp as f64, fp as f64, fn_ as f64, tn as f64);
        2.0 * (tp * tn - fn_ * fp) / ((tp + fn_) * (fn_ + tn) + (tp + fp) * (fp + tn))
    };
    let mut best: BTreeMap<usize, u64> = BTreeMap::new();
    for (&(p, _), &k) in &joint {
        let b = best.entry(p).or_default();
        *b = (*b).max(k);
    }
    let purity = best.values().sum::<u64>() as f64 / n as f64;
    Ok(Agreement {
        together_both: tp,
        together_predicted_only: fp,
        together_truth_only: fn_,
        apart_both: tn,
        rand_index,
        adjusted_rand_index,
        purity,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn hand_computed_contingency() {
        // Hubert–Arabie on a 6-item example worked by hand:
        // predicted [0,0,0,1,1,1], truth [0,0,1,1,2,2]:
        // together both: {0,1},{4,5} = 2; predicted-same 6, truth-same 3 → fp 4, fn 1; tn 8.
        let a = agreement(&[0, 0, 0, 1, 1, 1], &[0, 0, 1, 1, 2, 2]).unwrap();
        assert_eq!(
            (
                a.together_both,
                a.together_predicted_only,
                a.together_truth_only,
                a.apart_both
            ),
            (2, 4, 1, 8)
        );
        approx::assert_relative_eq!(a.rand_index, 10.0 / 15.0, epsilon = 1e-12);
        // ARI = (2 − 6·3/15) / (½(6+3) − 6·3/15) = 0.8 / 3.3
        approx::assert_relative_eq!(a.adjusted_rand_index, 0.8 / 3.3, epsilon = 1e-12);
        approx::assert_relative_eq!(a.purity, 4.0 / 6.0, epsilon = 1e-12);
    }

    #[test]
    fn bad_input() {
        assert!(matches!(
            agreement(&[0, 1], &[0]),
            Err(SimilarityError::LengthMismatch { .. })
        ));
        assert!(matches!(
            agreement(&[0], &[0]),
            Err(SimilarityError::TooFew { .. })
        ));
    }

    /// Plain reference: O(n²) over pairs, ARI by the expected-index formula.
    fn reference(p: &[usize], t: &[usize]) -> (f64, f64) {
        let n = p.len();
        let (mut agree, mut total) = (0.0, 0.0);
        for i in 0..n {
            for j in i + 1..n {
                total += 1.0;
                if (p[i] == p[j]) == (t[i] == t[j]) {
                    agree += 1.0;
                }
            }
        }
        let c2 = |k: f64| k * (k - 1.0) / 2.0;
        let mut idx = 0.0;
        let (mut sa, mut sb) = (0.0, 0.0);
        for a in 0..5 {
            sa += c2(p.iter().filter(|&&x| x == a).count() as f64);
            sb += c2(t.iter().filter(|&&x| x == a).count() as f64);
            for b in 0..5 {
                idx += c2((0..n).filter(|&i| p[i] == a && t[i] == b).count() as f64);
            }
        }
        let expected = sa * sb / c2(n as f64);
        let max = 0.5 * (sa + sb);
        let ari = if max == expected {
            1.0
        } else {
            (idx - expected) / (max - expected)
        };
        (agree / total, ari)
    }

    proptest! {
        #[test]
        fn matches_reference(labels in proptest::collection::vec((0usize..5, 0usize..5), 2..30)) {
            let (p, t): (Vec<usize>, Vec<usize>) = labels.into_iter().unzip();
            let a = agreement(&p, &t).unwrap();
            let (ri, ari) = reference(&p, &t);
            prop_assert!((a.rand_index - ri).abs() < 1e-12);
            prop_assert!((a.adjusted_rand_index - ari).abs() < 1e-9, "{} vs {}", a.adjusted_rand_index, ari);
            let swapped = agreement(&t, &p).unwrap();
            prop_assert!((swapped.adjusted_rand_index - a.adjusted_rand_index).abs() < 1e-12);
        }
    }
}
