//! Training of a [`LegForest`] with smartcore's random forest, and cross-validation inside
//! the training set (feature `train`).
//!
//! The input is [`Samples`]: feature rows of labelled clusters, each with the recording and
//! scan it came from, however the labelled scans were read (the text copies of
//! `leg_tracker`'s training bags, or a user's own). Training is deterministic: the same rows
//! and [`ForestParams`] give the same model, byte for byte ([`LegForest::to_bytes`]), on the
//! same platform (smartcore draws from `rand`'s `SmallRng`, Xoshiro256++ on 64-bit targets).

use smartcore::ensemble::random_forest_classifier::{
    RandomForestClassifier, RandomForestClassifierParameters,
};
use smartcore::linalg::basic::matrix::DenseMatrix;

use super::{LEAF, LegForest, Node};
use crate::detect::forest::quality::{best_f1_threshold, roc_auc};
use crate::detect::rule;
use crate::detect::training::{Recording, SampleParams, Samples, read_training_dir};
use crate::{Result, TrackingError};

/// Parameters of [`train_forest`] and [`cross_validate`].
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub struct ForestParams {
    /// Number of trees.
    pub trees: u16,
    /// Deepest a tree may grow (`None`: until its leaves are pure).
    pub max_depth: Option<u16>,
    /// Fewest rows a leaf may hold.
    pub min_samples_leaf: usize,
    /// Features drawn as split candidates at each node (`None`: `⌊√16⌋ = 4`, the usual
    /// choice for classification).
    pub features_per_split: Option<usize>,
    /// Seed of the bootstrap samples and the feature draws.
    pub seed: u64,
    /// Folds of [`cross_validate`].
    pub folds: usize,
}

impl Default for ForestParams {
    /// 20 trees grown until their leaves hold fewer than 5 rows' worth of a split, 4
    /// features per split, seed 17, 5 folds. `leg_tracker` grows 30 trees of depth ≤ 50;
    /// ours are fewer, with larger leaves, so that the model shipped inside the crate stays
    /// about half a megabyte and the test that retrains it takes tens of seconds. Depth
    /// limits cost more than they save: on the training set's folds, depth ≤ 8 gives AUC
    /// 0.82 and depth ≤ 12 0.90, against 0.93 unlimited (BENCHMARKS.md).
    fn default() -> Self {
        Self {
            trees: 20,
            max_depth: None,
            min_samples_leaf: 5,
            features_per_split: None,
            seed: 17,
            folds: 5,
        }
    }
}

impl ForestParams {
    /// Sets [`ForestParams::trees`].
    pub fn with_trees(mut self, v: u16) -> Self {
        self.trees = v;
        self
    }
    /// Sets [`ForestParams::max_depth`].
    pub fn with_max_depth(mut self, v: Option<u16>) -> Self {
        self.max_depth = v;
        self
    }
    /// Sets [`ForestParams::min_samples_leaf`].
    pub fn with_min_samples_leaf(mut self, v: usize) -> Self {
        self.min_samples_leaf = v;
        self
    }
    /// Sets [`ForestParams::features_per_split`].
    pub fn with_features_per_split(mut self, v: Option<usize>) -> Self {
        self.features_per_split = v;
        self
    }
    /// Sets [`ForestParams::seed`].
    pub fn with_seed(mut self, v: u64) -> Self {
        self.seed = v;
        self
    }
    /// Sets [`ForestParams::folds`].
    pub fn with_folds(mut self, v: usize) -> Self {
        self.folds = v;
        self
    }

    /// The parameters, if every rule holds.
    ///
    /// # Errors
    /// [`TrackingError::InvalidParameter`] naming `trees` (≥ 1), `max_depth` (≥ 1 when
    /// given), `min_samples_leaf` (≥ 1), `features_per_split` (1 to 16 when given) or
    /// `folds` (≥ 2).
    pub fn check(self) -> Result<Self> {
        rule(
            self.trees >= 1,
            "trees",
            f64::from(self.trees),
            "must be >= 1",
        )?;
        let depth = self.max_depth.unwrap_or(1);
        rule(
            depth >= 1,
            "max_depth",
            f64::from(depth),
            "must be >= 1 when given",
        )?;
        rule(
            self.min_samples_leaf >= 1,
            "min_samples_leaf",
            self.min_samples_leaf as f64,
            "must be >= 1",
        )?;
        let m = self.features_per_split.unwrap_or(1);
        rule(
            (1..=crate::detect::features::FEATURES).contains(&m),
            "features_per_split",
            m as f64,
            "must be in 1..=16 when given",
        )?;
        rule(self.folds >= 2, "folds", self.folds as f64, "must be >= 2")?;
        Ok(self)
    }
}

/// Trains a forest on every row of `samples`, with the operating point `threshold`; each leaf
/// holds the share of legs among the rows that reach it (the soft vote of [`LegForest`]).
///
/// # Errors
/// As [`ForestParams::check`]; [`TrackingError::InvalidParameter`] for a threshold outside
/// `[0, 1]`; [`TrackingError::Training`] when smartcore refuses the rows (no rows, or one
/// class only).
///
/// # Complexity
/// smartcore's: about O(trees · nodes · rows · features_per_split).
pub fn train_forest(samples: &Samples, params: &ForestParams, threshold: f64) -> Result<LegForest> {
    let params = params.check()?;
    let x: Vec<Vec<f64>> = samples.features.iter().map(|f| f.to_vec()).collect();
    let y: Vec<u32> = samples.legs.iter().map(|&l| u32::from(l)).collect();
    let failed = |e: smartcore::error::Failed| TrackingError::Training {
        message: e.to_string(),
    };
    let x = DenseMatrix::from_2d_vec(&x).map_err(failed)?;
    let mut p = RandomForestClassifierParameters::default()
        .with_n_trees(params.trees)
        .with_min_samples_leaf(params.min_samples_leaf)
        .with_seed(params.seed);
    p.max_depth = params.max_depth;
    p.m = params.features_per_split;
    let fitted = RandomForestClassifier::fit(&x, &y, p).map_err(failed)?;
    let mut forest = extract(&fitted)?;
    // Soft votes: each leaf's share of legs among the training rows (smartcore keeps only
    // the majority class of a leaf).
    forest.fit_leaves(&samples.features, &samples.legs);
    forest.with_threshold(threshold)
}

/// The trees of a fitted smartcore forest in our form, read through its serde
/// representation (smartcore keeps its nodes private): per tree `nodes` with
/// `split_feature`, `split_value`, `true_child` (taken when `x <= split_value`),
/// `false_child` and `output` (an index into `classes`).
fn extract(
    fitted: &RandomForestClassifier<f64, u32, DenseMatrix<f64>, Vec<u32>>,
) -> Result<LegForest> {
    let bad = |what| TrackingError::InvalidModel { what };
    let json = serde_json::to_value(fitted).map_err(|_| bad("smartcore model not serialisable"))?;
    let trees = json["trees"]
        .as_array()
        .ok_or(bad("smartcore model without trees"))?;
    let mut out = Vec::with_capacity(trees.len());
    for tree in trees {
        let classes: Vec<u64> = tree["classes"]
            .as_array()
            .ok_or(bad("smartcore tree without classes"))?
            .iter()
            .filter_map(serde_json::Value::as_u64)
            .collect();
        let nodes = tree["nodes"]
            .as_array()
            .ok_or(bad("smartcore tree without nodes"))?;
        let mut ours = Vec::with_capacity(nodes.len());
        for n in nodes {
            let output = n["output"].as_u64().ok_or(bad("node without output"))? as usize;
            let leg = f64::from(u8::from(classes.get(output) == Some(&1)));
            let index = |key: &str| n[key].as_u64().map(|v| v as u32);
            let node = match (index("true_child"), index("false_child")) {
                (Some(yes), Some(no)) => Node {
                    feature: u8::try_from(
                        n["split_feature"]
                            .as_u64()
                            .ok_or(bad("split without feature"))?,
                    )
                    .map_err(|_| bad("split feature out of range"))?,
                    leg,
                    threshold: n["split_value"]
                        .as_f64()
                        .ok_or(bad("split without value"))?,
                    yes,
                    no,
                },
                _ => Node {
                    feature: LEAF,
                    leg,
                    threshold: 0.0,
                    yes: 0,
                    no: 0,
                },
            };
            ours.push(node);
        }
        out.push(ours);
    }
    // Through the bytes, so that whatever smartcore wrote is checked like a file.
    LegForest::from_bytes(
        &LegForest {
            trees: out,
            threshold: 0.5,
        }
        .to_bytes(),
    )
}

/// What [`cross_validate`] measured.
#[derive(Debug, Clone, PartialEq)]
pub struct CrossValidation {
    /// Each row's leg probability from the forest trained without its fold.
    pub out_of_fold: Vec<f64>,
    /// ROC AUC of the out-of-fold probabilities.
    pub auc: f64,
    /// The threshold with the best F1 score on them (the operating point).
    pub threshold: f64,
    /// Precision and recall at that threshold.
    pub precision: f64,
    /// See [`CrossValidation::precision`].
    pub recall: f64,
}

/// The fold of each row: every recording's scans are cut into `folds` runs of consecutive
/// scans, and run `k` of every recording makes fold `k` (neighbouring scans, which show
/// the same people a few centimetres apart, stay in one fold; every fold has rows of every
/// recording, so legs and non-legs alike).
pub fn folds(samples: &Samples, folds: usize) -> Vec<usize> {
    let mut scans: Vec<usize> = Vec::new();
    for &(r, s) in &samples.origin {
        if scans.len() <= r {
            scans.resize(r + 1, 0);
        }
        scans[r] = scans[r].max(s + 1);
    }
    samples
        .origin
        .iter()
        .map(|&(r, s)| (s * folds / scans[r].max(1)).min(folds.saturating_sub(1)))
        .collect()
}

/// `params.folds`-fold cross-validation inside `samples` (see [`folds`]): each fold is
/// scored by a forest trained on the others; the operating point is the threshold with
/// the best F1 score on the pooled out-of-fold probabilities.
///
/// # Errors
/// As [`train_forest`].
///
/// # Complexity
/// `folds` trainings on `(folds − 1)/folds` of the rows.
pub fn cross_validate(samples: &Samples, params: &ForestParams) -> Result<CrossValidation> {
    let params = params.check()?;
    let fold = folds(samples, params.folds);
    let mut out_of_fold = vec![0.0; samples.len()];
    for k in 0..params.folds {
        let train = samples.subset(|i| fold[i] != k);
        let forest = train_forest(&train, &params, 0.5)?;
        for i in (0..samples.len()).filter(|&i| fold[i] == k) {
            out_of_fold[i] = forest.probability(&samples.features[i]);
        }
    }
    let auc = roc_auc(&out_of_fold, &samples.legs);
    let (threshold, precision, recall) = best_f1_threshold(&out_of_fold, &samples.legs);
    Ok(CrossValidation {
        out_of_fold,
        auc,
        threshold,
        precision,
        recall,
    })
}

/// A forest trained from labelled scans, with what it was measured on.
#[derive(Debug, Clone, PartialEq)]
pub struct Trained {
    /// The forest, its threshold the cross-validated operating point.
    pub forest: LegForest,
    /// The cross-validation inside the training rows.
    pub cross_validation: CrossValidation,
    /// The rows it was trained on.
    pub samples: Samples,
    /// The recordings read, in order.
    pub recordings: Vec<String>,
    /// What the reader skipped: malformed lines of text copies, or messages of a bag that
    /// could not be decoded or converted.
    pub skipped_lines: usize,
}

/// Reads the labelled scans of `dir` (one recording per `NAME.scans.txt.gz` or
/// `NAME.scans.txt`, in file-name order, with its `NAME.legs.txt` labels when there is one,
/// else a recording without people: the layout of `leg_tracker/training/text`) and trains
/// on them as [`train_from_recordings`] does: how a user with scans as text trains a model
/// for another laser. (The shipped model is trained from the original bags, read by the
/// facade's `haunts::training`; the text copies give the same rows up to the rounding of
/// their ranges to the millimetre and their angles to 10⁻⁹ rad.)
///
/// # Errors
/// The reader's and [`train_from_recordings`]' errors.
pub fn train_from_dir(
    dir: impl AsRef<std::path::Path>,
    sample_params: &SampleParams,
    params: &ForestParams,
) -> Result<Trained> {
    let (recordings, skipped_lines) = read_training_dir(dir)?;
    train_from_recordings(recordings, skipped_lines, sample_params, params)
}

/// Turns named recordings of labelled scans (in the order given: each one's index is its
/// recording number in [`Samples::origin`]) into rows, cross-validates, and trains on every
/// row with the cross-validated operating point. `skipped` (what the reader skipped) is
/// passed through to [`Trained::skipped_lines`].
///
/// # Errors
/// [`Samples::add`]'s, [`cross_validate`]'s and [`train_forest`]'s.
pub fn train_from_recordings(
    recordings: Vec<Recording>,
    skipped: usize,
    sample_params: &SampleParams,
    params: &ForestParams,
) -> Result<Trained> {
    let mut samples = Samples::default();
    for (k, (_, scans)) in recordings.iter().enumerate() {
        samples.add(k, scans, sample_params)?;
    }
    let cross_validation = cross_validate(&samples, params)?;
    let forest = train_forest(&samples, params, cross_validation.threshold)?;
    Ok(Trained {
        forest,
        cross_validation,
        samples,
        recordings: recordings.into_iter().map(|r| r.0).collect(),
        skipped_lines: skipped,
    })
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;
    use crate::detect::features::FEATURES;

    /// Legs narrower than 0.15 m, non-legs wider, with noise in another feature.
    fn toy() -> Samples {
        let mut s = Samples::default();
        for i in 0..200 {
            let leg = i % 3 == 0;
            let mut f = [0.0; FEATURES];
            f[1] = if leg { 0.05 } else { 0.25 } + 0.001 * (i % 7) as f64;
            f[3] = (i * 37 % 11) as f64;
            s.features.push(f);
            s.legs.push(leg);
            s.origin.push((i % 2, i / 2));
            s.cluster.push(0);
        }
        s
    }

    #[test]
    fn training_is_deterministic_and_learns_a_clean_rule() {
        // Every feature a candidate: 14 of the 16 are constant here.
        let params = ForestParams::default()
            .with_trees(5)
            .with_features_per_split(Some(FEATURES));
        let a = train_forest(&toy(), &params, 0.5).unwrap();
        let b = train_forest(&toy(), &params, 0.5).unwrap();
        assert_eq!(a.to_bytes(), b.to_bytes());
        let mut x = [0.0; FEATURES];
        x[1] = 0.05;
        assert!(a.probability(&x) > 0.9);
        x[1] = 0.3;
        assert!(a.probability(&x) < 0.1);
        let cv = cross_validate(&toy(), &params).unwrap();
        assert!(cv.auc > 0.99, "{}", cv.auc);
    }

    #[test]
    fn folds_cut_each_recording_into_runs() {
        let s = toy();
        let f = folds(&s, 5);
        // Recording 0 holds scans 0..100 (even rows): scan 0..20 → fold 0, …
        assert_eq!((f[0], f[38], f[40], f[198]), (0, 0, 1, 4));
    }
}
