//! Clustering of days into layouts from a similarity matrix: the seed's greedy threshold
//! algorithm (seed 000 III-D) and complete-linkage agglomerative clustering.

use crate::difference::{Symmetrisation, snap};
use crate::error::{Result, rule};
use crate::matrix::SimilarityMatrix;

/// When two maps count as the same layout, and in what units the threshold is given.
///
/// The directed difference `cmapXmapY` sums distances in cells over occupied cells, so for a
/// wall of length `L` moved by `D` (beyond `ct`) it is about `L·D / res²`: it grows with the
/// inverse square of the cell side, and with the amount of structure mapped. Seed 000's
/// threshold, 1300 at 0.05 m cells, is therefore 1300 · 0.05² = 3.25 m² of "moved wall length
/// × displacement", the default here, which means the same thing at any resolution.
/// [`LayoutThreshold::PerOccupiedCell`] also removes the dependence on how much structure a
/// map holds (large maps, or maps explored more or less thoroughly).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum LayoutThreshold {
    /// The raw measure in cells², at the resolution of the maps (the seed: `Cells(1300.0)`
    /// at 0.05 m).
    Cells(f64),
    /// The measure times res², in m² (default `SquareMetres(3.25)`, the seed's 1300 at 0.05 m).
    SquareMetres(f64),
    /// The directed measure divided by the number of occupied cells of the measured map: the
    /// mean excess displacement per occupied cell, in cells.
    PerOccupiedCell(f64),
}

impl Default for LayoutThreshold {
    fn default() -> Self {
        Self::SquareMetres(1300.0 * 0.05 * 0.05)
    }
}

impl LayoutThreshold {
    fn value(self) -> f64 {
        match self {
            Self::Cells(v) | Self::SquareMetres(v) | Self::PerOccupiedCell(v) => v,
        }
    }
}

/// Parameters of both clusterings.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub struct ClusterParams {
    /// Two maps are the same layout when their combined difference is strictly below this.
    pub threshold: LayoutThreshold,
    /// How the two directions are combined (default: the larger).
    pub symmetrisation: Symmetrisation,
}

impl ClusterParams {
    /// Sets the threshold.
    pub fn with_threshold(mut self, threshold: LayoutThreshold) -> Self {
        self.threshold = threshold;
        self
    }
    /// Sets the symmetrisation.
    pub fn with_symmetrisation(mut self, symmetrisation: Symmetrisation) -> Self {
        self.symmetrisation = symmetrisation;
        self
    }
    /// The parameters after checking that the threshold is finite and ≥ 0.
    ///
    /// # Errors
    /// [`crate::SimilarityError::InvalidParameter`] naming `threshold`.
    pub fn check(self) -> Result<Self> {
        let v = self.threshold.value();
        rule(
            "threshold",
            v,
            v.is_finite() && v >= 0.0,
            "must be finite and >= 0",
        )?;
        Ok(self)
    }

    /// The symmetric layout distances (row-major, `n × n`) in the threshold's units.
    pub fn layout_distances(&self, matrix: &SimilarityMatrix) -> Vec<f64> {
        let n = matrix.len();
        let res2 = matrix.resolution() * matrix.resolution();
        let directed = |x: usize, y: usize| {
            let v = matrix.values()[x * n + y];
            match self.threshold {
                LayoutThreshold::Cells(_) => v,
                LayoutThreshold::SquareMetres(_) => v * res2,
                LayoutThreshold::PerOccupiedCell(_) => {
                    v / matrix.occupied_counts()[y].max(1) as f64
                }
            }
        };
        let mut out = vec![0.0; n * n];
        for x in 0..n {
            for y in 0..n {
                out[x * n + y] = self.symmetrisation.combine(directed(x, y), directed(y, x));
            }
        }
        out
    }

    /// The threshold in the units of [`ClusterParams::layout_distances`] (snapped to an
    /// integer within 10⁻⁹, so `SquareMetres(3.25)` is exactly 1300 cells² at 0.05 m).
    fn limit(&self, matrix: &SimilarityMatrix) -> f64 {
        match self.threshold {
            LayoutThreshold::SquareMetres(v) => {
                let res2 = matrix.resolution() * matrix.resolution();
                snap(v / res2) * res2
            }
            t => t.value(),
        }
    }
}

/// A partition of the maps into layouts.
#[derive(Debug, Clone, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Clustering {
    /// Layout of each map, numbered 0, 1, … in order of first appearance.
    pub labels: Vec<usize>,
    /// Number of layouts.
    pub clusters: usize,
}

impl Clustering {
    fn from_groups(n: usize, groups: &[Vec<usize>]) -> Self {
        let mut labels = vec![0; n];
        let mut order: Vec<&Vec<usize>> = groups.iter().collect();
        order.sort_by_key(|g| g.iter().min().copied());
        for (k, g) in order.iter().enumerate() {
            for &i in g.iter() {
                labels[i] = k;
            }
        }
        Self {
            labels,
            clusters: groups.len(),
        }
    }
}

/// Seed 000 III-D: take the first unclustered map, put every unclustered map closer to it
/// than the threshold in its cluster, remove them, repeat.
///
/// Only closeness to each cluster's first map is guaranteed, so a cluster may hold maps
/// further apart than the threshold (the seed's Fig. 12 failure), and the result depends on
/// the order of the maps.
///
/// # Errors
/// [`crate::SimilarityError::InvalidParameter`] for a bad threshold.
///
/// # Complexity
/// O(n²).
///
/// # Example
/// ```
/// use haunts_similarity::{greedy_layouts, ClusterParams, LayoutThreshold, SimilarityMatrix};
/// // Map 1 is near 0 and 2, but 0 and 2 are far apart.
/// let m = SimilarityMatrix::from_values(
///     vec![0.0, 100.0, 2000.0, 100.0, 0.0, 100.0, 2000.0, 100.0, 0.0], vec![50; 3], 0.05).unwrap();
/// let p = ClusterParams::default().with_threshold(LayoutThreshold::Cells(1300.0));
/// assert_eq!(greedy_layouts(&m, &p).unwrap().labels, vec![0, 0, 1]);
/// ```
pub fn greedy_layouts(matrix: &SimilarityMatrix, params: &ClusterParams) -> Result<Clustering> {
    let params = params.check()?;
    let n = matrix.len();
    let d = params.layout_distances(matrix);
    let limit = params.limit(matrix);
    let mut unclustered: Vec<usize> = (0..n).collect();
    let mut groups = Vec::new();
    while let Some(&seed) = unclustered.first() {
        let (group, rest): (Vec<usize>, Vec<usize>) = unclustered
            .iter()
            .partition(|&&j| j == seed || d[seed * n + j] < limit);
        groups.push(group);
        unclustered = rest;
    }
    Ok(Clustering::from_groups(n, &groups))
}

/// Complete-linkage agglomerative clustering: repeatedly merge the two clusters whose farthest
/// pair of maps is closest, while that distance is below the threshold.
///
/// This gives the threshold exactly the meaning seed 000 intends — every two maps of a layout
/// differ by less than it — independently of the order of the maps. Ties are broken by the
/// lowest map indices.
///
/// # Errors
/// [`crate::SimilarityError::InvalidParameter`] for a bad threshold.
///
/// # Complexity
/// O(n³) time, O(n²) memory.
///
/// # Example
/// ```
/// use haunts_similarity::{complete_linkage_layouts, ClusterParams, LayoutThreshold, SimilarityMatrix};
/// let m = SimilarityMatrix::from_values(
///     vec![0.0, 100.0, 2000.0, 100.0, 0.0, 100.0, 2000.0, 100.0, 0.0], vec![50; 3], 0.05).unwrap();
/// let p = ClusterParams::default().with_threshold(LayoutThreshold::Cells(1300.0));
/// let c = complete_linkage_layouts(&m, &p).unwrap();
/// assert_eq!(c.clusters, 2);
/// assert_ne!(c.labels[0], c.labels[2]);
/// ```
pub fn complete_linkage_layouts(
    matrix: &SimilarityMatrix,
    params: &ClusterParams,
) -> Result<Clustering> {
    let params = params.check()?;
    let n = matrix.len();
    let mut d = params.layout_distances(matrix);
    let limit = params.limit(matrix);
    let mut groups: Vec<Option<Vec<usize>>> = (0..n).map(|i| Some(vec![i])).collect();
    loop {
        let mut best: Option<(f64, usize, usize)> = None;
        for a in 0..n {
            if groups[a].is_none() {
                continue;
            }
            for b in a + 1..n {
                if groups[b].is_none() {
                    continue;
                }
                let v = d[a * n + b];
                if v < limit && best.is_none_or(|(bv, _, _)| v < bv) {
                    best = Some((v, a, b));
                }
            }
        }
        let Some((_, a, b)) = best else { break };
        let moved = groups[b].take().unwrap_or_default();
        if let Some(g) = groups[a].as_mut() {
            g.extend(moved);
        }
        for c in 0..n {
            let v = d[a * n + c].max(d[b * n + c]);
            d[a * n + c] = v;
            d[c * n + a] = v;
        }
    }
    let groups: Vec<Vec<usize>> = groups.into_iter().flatten().collect();
    Ok(Clustering::from_groups(n, &groups))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::SimilarityError;

    fn matrix(n: usize, f: impl Fn(usize, usize) -> f64) -> SimilarityMatrix {
        let values = (0..n * n).map(|i| f(i / n, i % n)).collect();
        SimilarityMatrix::from_values(values, vec![100; n], 0.05).unwrap()
    }

    #[test]
    fn threshold_scales_with_resolution() {
        // 1300 cells² at 0.05 m is 3.25 m²; at 0.1 m the same 3.25 m² is 325 cells².
        let at = |res: f64, v: f64| {
            let m = SimilarityMatrix::from_values(vec![0.0, v, v, 0.0], vec![10, 10], res).unwrap();
            greedy_layouts(&m, &ClusterParams::default())
                .unwrap()
                .clusters
        };
        assert_eq!(at(0.05, 1299.0), 1);
        assert_eq!(at(0.05, 1300.0), 2);
        assert_eq!(at(0.1, 324.0), 1);
        assert_eq!(at(0.1, 325.0), 2);
        let per_cell =
            ClusterParams::default().with_threshold(LayoutThreshold::PerOccupiedCell(2.0));
        let m = SimilarityMatrix::from_values(vec![0.0, 150.0, 240.0, 0.0], vec![100, 100], 0.05)
            .unwrap();
        assert_eq!(greedy_layouts(&m, &per_cell).unwrap().clusters, 2);
        let mean = per_cell.with_symmetrisation(Symmetrisation::Mean);
        assert_eq!(greedy_layouts(&m, &mean).unwrap().clusters, 1);
    }

    #[test]
    fn complete_linkage_recovers_blocks_in_any_order() {
        // Three blocks of days, near inside a block, far across; shuffled order.
        let truth = [0, 1, 2, 0, 1, 2, 2, 0, 1, 1];
        let m = matrix(10, |x, y| {
            if x == y {
                0.0
            } else if truth[x] == truth[y] {
                200.0 + (x + y) as f64
            } else {
                5000.0
            }
        });
        let p = ClusterParams::default().with_threshold(LayoutThreshold::Cells(1300.0));
        for c in [
            greedy_layouts(&m, &p).unwrap(),
            complete_linkage_layouts(&m, &p).unwrap(),
        ] {
            assert_eq!(c.clusters, 3);
            assert_eq!(c.labels, vec![0, 1, 2, 0, 1, 2, 2, 0, 1, 1]);
        }
    }

    #[test]
    fn complete_linkage_never_joins_a_far_pair() {
        // A chain 0–1–2–3 with steps of 500: greedy puts 0, 1, 2 together (each within 1300 of
        // map 0); complete linkage pairs {0,1} and {2,3} and keeps every
        // joined pair below 1300.
        let m = matrix(4, |x, y| 500.0 * (x as f64 - y as f64).abs());
        let p = ClusterParams::default().with_threshold(LayoutThreshold::Cells(1300.0));
        let c = complete_linkage_layouts(&m, &p).unwrap();
        for x in 0..4 {
            for y in 0..4 {
                if c.labels[x] == c.labels[y] {
                    assert!(m.get(x, y).unwrap() < 1300.0);
                }
            }
        }
        assert_eq!(c.labels, vec![0, 0, 1, 1]);
        assert_eq!(greedy_layouts(&m, &p).unwrap().labels, vec![0, 0, 0, 1]);
        assert!(matches!(
            greedy_layouts(&m, &p.with_threshold(LayoutThreshold::Cells(f64::NAN))),
            Err(SimilarityError::InvalidParameter(
                haunts_core::InvalidParameter {
                    name: "threshold",
                    ..
                }
            ))
        ));
    }
}
