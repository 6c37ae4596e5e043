//! A random forest that tells leg clusters from the rest, as `leg_tracker` does: the trained
//! model, its file format, the model shipped with the crate, and (feature `train`) its
//! training with smartcore.
//!
//! A [`LegForest`] is a set of binary decision trees over the [`crate::detect::features`] of a
//! cluster; a cluster's leg probability is the mean over the trees of the leg fraction of
//! the leaf it reaches (a *soft* vote: the training rows' share of legs in that leaf). A
//! leaf holding only 0 or 1 makes it `leg_tracker`'s hard vote, the fraction of trees that
//! vote *leg* (`PREDICT_SUM / n_trees`), which is what models of format version 1 hold. The
//! soft vote ranks clusters better: with 20 trees a hard vote has 21 levels, and inside the
//! training set it cross-validates at ROC AUC 0.92 where the same trees soft-voted reach
//! 0.95 (BENCHMARKS.md). The model also holds the operating point chosen by cross-validation
//! on its training set ([`LegForest::threshold`]).
//!
//! [`LegForest::shipped`] is a forest trained on `leg_tracker`'s own training set (BSD
//! 3-Clause, Copyright (c) 2018 Angus Leigh; the notice is in `models/LICENSE-leg_tracker`
//! beside the model), for lasers like its Hokuyo (768 beams at 0.352°, at leg height).
//! `examples/train_leg_detector.rs` in the facade rebuilds it bit for bit, and trains one
//! for another laser from a user's labelled scans.

pub mod quality;
#[cfg(feature = "train")]
pub mod train;

use crate::detect::features::FEATURES;
use crate::{Result, TrackingError};

/// The first bytes of a model file.
const MAGIC: &[u8; 8] = b"HAUNTSLF";

/// The version of the file format this crate writes and reads.
const FORMAT_VERSION: u32 = 2;

/// One node of a tree: a split `x[feature] <= threshold` (then `yes`, else `no`) or a leaf.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Node {
    /// `LEAF` for a leaf.
    feature: u8,
    /// A leaf's leg fraction in `[0, 1]` (0 for a split).
    leg: f64,
    threshold: f64,
    yes: u32,
    no: u32,
}

const LEAF: u8 = u8::MAX;

/// A trained leg classifier (see the [module docs](self)).
///
/// # Example
/// ```
/// use haunts_tracking::detect::features::point_features;
/// use haunts_tracking::detect::forest::LegForest;
/// use nalgebra::Point2;
///
/// let forest = LegForest::shipped()?;
/// // Ten points of a leg (6 cm radius) 2 m ahead, and ten of a wall 2 m ahead.
/// let leg: Vec<Point2<f64>> = (0..10)
///     .map(|i| {
///         let t = -1.2 + 2.4 * i as f64 / 9.0;
///         Point2::new(2.0 - 0.06 * t.cos(), 0.06 * t.sin())
///     })
///     .collect();
/// let wall: Vec<Point2<f64>> = (0..10).map(|i| Point2::new(2.0, -0.3 + 0.066 * i as f64)).collect();
/// let p_leg = forest.probability(&point_features(&leg, false));
/// let p_wall = forest.probability(&point_features(&wall, false));
/// assert!(p_leg > forest.threshold() && p_wall < forest.threshold(), "{p_leg} {p_wall}");
/// # Ok::<(), haunts_tracking::TrackingError>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct LegForest {
    trees: Vec<Vec<Node>>,
    threshold: f64,
}

impl LegForest {
    /// The forest trained on `leg_tracker`'s training set, shipped inside the crate.
    ///
    /// # Errors
    /// [`TrackingError::InvalidModel`] if the shipped file is damaged (a build problem).
    pub fn shipped() -> Result<Self> {
        Self::from_bytes(include_bytes!("../../models/leg_forest.bin"))
    }

    /// The leg probability of a cluster with features `x`: the mean over the trees of the
    /// leg fraction of the leaf it reaches, in `[0, 1]`. A NaN feature takes the `no` branch
    /// of every split on it.
    ///
    /// # Complexity
    /// O(Σ depth) over the trees.
    pub fn probability(&self, x: &[f64; FEATURES]) -> f64 {
        if self.trees.is_empty() {
            return 0.0;
        }
        let votes: f64 = self.trees.iter().map(|t| vote(t, x)).sum();
        votes / self.trees.len() as f64
    }

    /// The operating point: a cluster is a leg when its probability reaches this (chosen by
    /// cross-validation on the training set: `forest::train::cross_validate`, feature
    /// `train`).
    pub fn threshold(&self) -> f64 {
        self.threshold
    }

    /// The same forest with another operating point.
    ///
    /// # Errors
    /// [`TrackingError::InvalidParameter`] unless `threshold` is in `[0, 1]`.
    pub fn with_threshold(mut self, threshold: f64) -> Result<Self> {
        crate::detect::rule(
            (0.0..=1.0).contains(&threshold),
            "threshold",
            threshold,
            "must be in [0, 1]",
        )?;
        self.threshold = threshold;
        Ok(self)
    }

    /// Number of trees.
    pub fn trees(&self) -> usize {
        self.trees.len()
    }

    /// Each leaf's leg fraction from labelled rows: the share of legs among the rows that
    /// reach it (a leaf no row reaches keeps its value). Training sets the leaves of every
    /// tree from all the training rows, those its bootstrap sample left out too.
    #[cfg(feature = "train")]
    pub(crate) fn fit_leaves(&mut self, rows: &[[f64; FEATURES]], legs: &[bool]) {
        for tree in &mut self.trees {
            let mut counts = vec![(0u32, 0u32); tree.len()];
            for (x, &is_leg) in rows.iter().zip(legs) {
                if let Some(k) = leaf(tree, x) {
                    counts[k].0 += u32::from(is_leg);
                    counts[k].1 += 1;
                }
            }
            for (n, (l, all)) in tree.iter_mut().zip(counts) {
                if n.feature == LEAF && all > 0 {
                    n.leg = f64::from(l) / f64::from(all);
                }
            }
        }
    }

    /// Number of nodes over all trees.
    pub fn nodes(&self) -> usize {
        self.trees.iter().map(Vec::len).sum()
    }

    /// The model as bytes: the magic `HAUNTSLF`, the format version 2 (u32), the number of features
    /// (u32), the threshold (f64), the number of trees (u32), each tree as its number of
    /// nodes (u32) and its nodes (feature u8 with 255 for a leaf, leg fraction f64,
    /// threshold f64, `yes` and `no` child indices u32), then the 64-bit FNV-1a checksum of
    /// everything before it (u64); all little-endian. (Version 1, still read, held a vote u8
    /// where version 2 holds the leg fraction.)
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(32 + 25 * self.nodes());
        out.extend_from_slice(MAGIC);
        out.extend_from_slice(&FORMAT_VERSION.to_le_bytes());
        out.extend_from_slice(&(FEATURES as u32).to_le_bytes());
        out.extend_from_slice(&self.threshold.to_le_bytes());
        out.extend_from_slice(&(self.trees.len() as u32).to_le_bytes());
        for tree in &self.trees {
            out.extend_from_slice(&(tree.len() as u32).to_le_bytes());
            for n in tree {
                out.push(n.feature);
                out.extend_from_slice(&n.leg.to_le_bytes());
                out.extend_from_slice(&n.threshold.to_le_bytes());
                out.extend_from_slice(&n.yes.to_le_bytes());
                out.extend_from_slice(&n.no.to_le_bytes());
            }
        }
        let sum = fnv1a(&out);
        out.extend_from_slice(&sum.to_le_bytes());
        out
    }

    /// Reads a model written by [`LegForest::to_bytes`], checking all of it.
    ///
    /// # Errors
    /// [`TrackingError::InvalidModel`] for a wrong magic, a format version other than 1 or 2,
    /// another feature count, a checksum mismatch, a truncated or overlong file, a threshold
    /// or a leaf's leg fraction outside `[0, 1]`, a split on an unknown feature or a NaN
    /// value, or a child index that does not point forward within its tree (which also rules
    /// out loops).
    pub fn from_bytes(bytes: &[u8]) -> Result<Self> {
        let bad = |what| TrackingError::InvalidModel { what };
        if bytes.len() < MAGIC.len() + 8 || &bytes[..MAGIC.len()] != MAGIC {
            return Err(bad("not a leg forest (bad magic)"));
        }
        let (body, sum) = bytes.split_at(bytes.len() - 8);
        let sum = u64::from_le_bytes(sum.try_into().map_err(|_| bad("truncated"))?);
        if fnv1a(body) != sum {
            return Err(bad("checksum mismatch"));
        }
        let mut r = Reader {
            bytes: body,
            at: MAGIC.len(),
        };
        let version = r.u32()?;
        if !(1..=FORMAT_VERSION).contains(&version) {
            return Err(bad("unknown format version"));
        }
        if r.u32()? as usize != FEATURES {
            return Err(bad("another number of features"));
        }
        let threshold = r.f64()?;
        if !(0.0..=1.0).contains(&threshold) {
            return Err(bad("threshold outside [0, 1]"));
        }
        let n_trees = r.u32()? as usize;
        let mut trees = Vec::with_capacity(n_trees.min(body.len()));
        for _ in 0..n_trees {
            let n = r.u32()? as usize;
            if n == 0 || n > body.len() {
                return Err(bad("a tree has no node or too many"));
            }
            let mut tree = Vec::with_capacity(n);
            for k in 0..n {
                let feature = r.u8()?;
                let leg = match version {
                    1 => f64::from(u8::from(r.u8()? != 0)),
                    _ => r.f64()?,
                };
                let threshold = r.f64()?;
                if !(0.0..=1.0).contains(&leg) {
                    return Err(bad("a leg fraction outside [0, 1]"));
                }
                let (yes, no) = (r.u32()?, r.u32()?);
                if feature != LEAF {
                    if feature as usize >= FEATURES || threshold.is_nan() {
                        return Err(bad("a split on an unknown feature or at NaN"));
                    }
                    let forward = |c: u32| (c as usize) > k && (c as usize) < n;
                    if !(forward(yes) && forward(no)) {
                        return Err(bad("a child index out of range"));
                    }
                }
                tree.push(Node {
                    feature,
                    leg,
                    threshold,
                    yes,
                    no,
                });
            }
            trees.push(tree);
        }
        if r.at != body.len() {
            return Err(bad("bytes after the last tree"));
        }
        Ok(Self { trees, threshold })
    }
}

/// The leg fraction of the leaf of one tree that `x` reaches.
fn vote(tree: &[Node], x: &[f64; FEATURES]) -> f64 {
    leaf(tree, x).map_or(0.0, |k| tree[k].leg)
}

/// The index of the leaf of one tree that `x` reaches (children point forward, checked on
/// construction, so the walk ends).
fn leaf(tree: &[Node], x: &[f64; FEATURES]) -> Option<usize> {
    let mut k = 0;
    while let Some(n) = tree.get(k) {
        if n.feature == LEAF {
            return Some(k);
        }
        k = if x[n.feature as usize] <= n.threshold {
            n.yes
        } else {
            n.no
        } as usize;
    }
    None
}

/// The 64-bit FNV-1a hash of `bytes`.
fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3)
    })
}

struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl Reader<'_> {
    fn take<const N: usize>(&mut self) -> Result<[u8; N]> {
        let end = self.at.checked_add(N).filter(|&e| e <= self.bytes.len());
        let end = end.ok_or(TrackingError::InvalidModel { what: "truncated" })?;
        let mut out = [0; N];
        out.copy_from_slice(&self.bytes[self.at..end]);
        self.at = end;
        Ok(out)
    }
    fn u8(&mut self) -> Result<u8> {
        Ok(self.take::<1>()?[0])
    }
    fn u32(&mut self) -> Result<u32> {
        Ok(u32::from_le_bytes(self.take()?))
    }
    fn f64(&mut self) -> Result<f64> {
        Ok(f64::from_le_bytes(self.take()?))
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;

    /// A stump on the width: legs are narrower than 0.2 m.
    fn stump() -> LegForest {
        let split = Node {
            feature: 1,
            leg: 0.0,
            threshold: 0.2,
            yes: 1,
            no: 2,
        };
        let leaf = |leg: f64| Node {
            feature: LEAF,
            leg,
            threshold: 0.0,
            yes: 0,
            no: 0,
        };
        LegForest {
            trees: vec![vec![split, leaf(1.0), leaf(0.25)], vec![leaf(1.0)]],
            threshold: 0.5,
        }
    }

    #[test]
    fn the_probability_is_the_mean_leaf_fraction() {
        let f = stump();
        let mut x = [0.0; FEATURES];
        x[1] = 0.1;
        assert_eq!(f.probability(&x), 1.0);
        x[1] = 0.3;
        assert_eq!(f.probability(&x), 0.625);
        x[1] = f64::NAN;
        assert_eq!(f.probability(&x), 0.625);
    }

    #[test]
    fn version_1_models_are_read_as_hard_votes() {
        // The stump with 0/1 leaves, written as format version 1 (a vote byte per node).
        let mut hard = stump();
        hard.trees[0][2].leg = 0.0;
        let mut v1 = Vec::new();
        v1.extend_from_slice(MAGIC);
        v1.extend_from_slice(&1u32.to_le_bytes());
        v1.extend_from_slice(&(FEATURES as u32).to_le_bytes());
        v1.extend_from_slice(&hard.threshold.to_le_bytes());
        v1.extend_from_slice(&(hard.trees.len() as u32).to_le_bytes());
        for tree in &hard.trees {
            v1.extend_from_slice(&(tree.len() as u32).to_le_bytes());
            for n in tree {
                v1.push(n.feature);
                v1.push(u8::from(n.leg > 0.5));
                v1.extend_from_slice(&n.threshold.to_le_bytes());
                v1.extend_from_slice(&n.yes.to_le_bytes());
                v1.extend_from_slice(&n.no.to_le_bytes());
            }
        }
        let sum = fnv1a(&v1);
        v1.extend_from_slice(&sum.to_le_bytes());
        let read = LegForest::from_bytes(&v1).unwrap();
        assert_eq!(read, hard);
        let mut x = [0.0; FEATURES];
        x[1] = 0.3;
        assert_eq!(read.probability(&x), 0.5);
        // Written again, it is version 2 and reads back the same.
        assert_eq!(LegForest::from_bytes(&read.to_bytes()).unwrap(), hard);
        // A leaf fraction outside [0, 1] is refused.
        let mut bad = stump();
        bad.trees[1][0].leg = 1.5;
        assert!(LegForest::from_bytes(&bad.to_bytes()).is_err());
    }

    #[test]
    fn models_round_trip_and_every_corruption_is_refused() {
        let f = stump();
        let bytes = f.to_bytes();
        assert_eq!(LegForest::from_bytes(&bytes).unwrap(), f);
        // Any one flipped byte, and any truncation, is refused without a panic.
        for i in 0..bytes.len() {
            let mut b = bytes.clone();
            b[i] ^= 0x5a;
            assert!(LegForest::from_bytes(&b).is_err(), "byte {i}");
            assert!(LegForest::from_bytes(&bytes[..i]).is_err(), "length {i}");
        }
        // A loop, with a valid checksum, is refused too.
        let mut looped = f.clone();
        looped.trees[0][0].no = 0;
        assert!(matches!(
            LegForest::from_bytes(&looped.to_bytes()),
            Err(TrackingError::InvalidModel { .. })
        ));
    }

    #[test]
    fn the_shipped_model_loads() {
        let f = LegForest::shipped().unwrap();
        assert!(f.trees() >= 10 && f.nodes() > f.trees());
        assert!(f.threshold() > 0.0 && f.threshold() < 1.0);
    }
}
