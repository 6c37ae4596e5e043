//! How well scores separate two classes: ROC AUC, and precision and recall at a threshold.

/// The area under the ROC curve of `scores` for the classes `positive`: the probability
/// that a random positive scores above a random negative, ties counting one half
/// (Mann–Whitney U / (n₊ n₋)). NaN when either class is empty.
///
/// # Complexity
/// O(n log n).
///
/// # Example
/// ```
/// use haunts_tracking::detect::forest::quality::roc_auc;
///
/// let auc = roc_auc(&[0.9, 0.8, 0.3, 0.8, 0.1], &[true, true, false, false, false]);
/// // Positives beat negatives in 5 of 6 pairs, and tie in the sixth.
/// approx::assert_relative_eq!(auc, 5.5 / 6.0);
/// ```
pub fn roc_auc(scores: &[f64], positive: &[bool]) -> f64 {
    let mut order: Vec<usize> = (0..scores.len().min(positive.len())).collect();
    order.sort_by(|&a, &b| scores[a].total_cmp(&scores[b]));
    // Mid-ranks (1-based) of tied groups.
    let (mut rank_sum, mut n_pos) = (0.0, 0usize);
    let mut i = 0;
    while i < order.len() {
        let mut j = i;
        while j + 1 < order.len() && scores[order[j + 1]] == scores[order[i]] {
            j += 1;
        }
        let mid = (i + j) as f64 / 2.0 + 1.0;
        for &k in &order[i..=j] {
            if positive[k] {
                rank_sum += mid;
                n_pos += 1;
            }
        }
        i = j + 1;
    }
    let n_neg = order.len() - n_pos;
    if n_pos == 0 || n_neg == 0 {
        return f64::NAN;
    }
    let u = rank_sum - (n_pos * (n_pos + 1)) as f64 / 2.0;
    u / (n_pos as f64 * n_neg as f64)
}

/// `(precision, recall)` of calling positive every score `≥ threshold` (precision is 1 when
/// nothing is called positive; recall NaN without positives).
pub fn precision_recall(scores: &[f64], positive: &[bool], threshold: f64) -> (f64, f64) {
    let (mut tp, mut fp, mut pos) = (0usize, 0usize, 0usize);
    for (&s, &p) in scores.iter().zip(positive) {
        pos += usize::from(p);
        if s >= threshold {
            if p {
                tp += 1;
            } else {
                fp += 1;
            }
        }
    }
    let precision = if tp + fp == 0 {
        1.0
    } else {
        tp as f64 / (tp + fp) as f64
    };
    (precision, tp as f64 / pos as f64)
}

/// The threshold among the distinct scores with the best F1 score (the harmonic mean of
/// precision and recall; the lowest such threshold on ties), with its precision and recall.
///
/// # Complexity
/// O(n log n).
#[cfg_attr(not(feature = "train"), allow(dead_code))]
pub(crate) fn best_f1_threshold(scores: &[f64], positive: &[bool]) -> (f64, f64, f64) {
    let mut order: Vec<usize> = (0..scores.len().min(positive.len())).collect();
    // Highest first: walking down, each distinct score is a candidate threshold.
    order.sort_by(|&a, &b| scores[b].total_cmp(&scores[a]));
    let total_pos = order.iter().filter(|&&k| positive[k]).count();
    let (mut tp, mut fp) = (0usize, 0usize);
    let mut best = (f64::NEG_INFINITY, 1.0, 1.0, 0.0);
    let mut i = 0;
    while i < order.len() {
        let s = scores[order[i]];
        while i < order.len() && scores[order[i]] == s {
            if positive[order[i]] {
                tp += 1;
            } else {
                fp += 1;
            }
            i += 1;
        }
        let precision = tp as f64 / (tp + fp) as f64;
        let recall = tp as f64 / total_pos.max(1) as f64;
        let f1 = if tp == 0 {
            0.0
        } else {
            2.0 * precision * recall / (precision + recall)
        };
        if f1 >= best.0 {
            best = (f1, s, precision, recall);
        }
    }
    (best.1, best.2, best.3)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The AUC by counting every pair (the definition).
    fn pairs(scores: &[f64], positive: &[bool]) -> f64 {
        let (mut sum, mut n) = (0.0, 0.0);
        for (a, &pa) in scores.iter().zip(positive) {
            for (b, &pb) in scores.iter().zip(positive) {
                if pa && !pb {
                    n += 1.0;
                    sum += if a > b {
                        1.0
                    } else if a == b {
                        0.5
                    } else {
                        0.0
                    };
                }
            }
        }
        sum / n
    }

    proptest::proptest! {
        #[test]
        fn auc_is_the_pair_count(
            v in proptest::collection::vec((0u8..6, proptest::bool::ANY), 2..40)
        ) {
            let scores: Vec<f64> = v.iter().map(|x| f64::from(x.0) / 5.0).collect();
            let positive: Vec<bool> = v.iter().map(|x| x.1).collect();
            let (a, b) = (roc_auc(&scores, &positive), pairs(&scores, &positive));
            proptest::prop_assert!((a - b).abs() < 1e-12 || (a.is_nan() && b.is_nan()));
        }
    }

    #[test]
    fn the_best_f1_threshold_separates_a_clean_split() {
        let scores = [0.9, 0.8, 0.7, 0.4, 0.2];
        let positive = [true, true, false, false, false];
        assert_eq!(best_f1_threshold(&scores, &positive), (0.8, 1.0, 1.0));
        assert_eq!(precision_recall(&scores, &positive, 0.7), (2.0 / 3.0, 1.0));
    }
}
