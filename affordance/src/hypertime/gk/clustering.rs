//! The result of a Gustafson–Kessel clustering.

use nalgebra::DMatrix;

/// A Gustafson–Kessel clustering: prototypes, regularised fuzzy covariances and the fuzzy
/// partition. Its `Debug` form is a summary (the partition has `n × c` entries).
///
/// With the `serde` feature it is saved whole (covariances as arrays of rows; an objective or
/// change that is not finite, such as the change `∞` after one iteration, as `"inf"`, `"-inf"`
/// or `"NaN"` in human-readable formats); loading checks the shapes (`clusters × dim` centres,
/// `clusters` covariances of `dim × dim`, `clusters` memberships per point), that centres and
/// covariances are finite, and that every point's memberships lie in `[0, 1]` and sum to 1.
#[derive(Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(try_from = "GkClusteringFields"))]
pub struct GkClustering {
    pub(super) dim: usize,
    pub(super) clusters: usize,
    pub(super) centres: Vec<f64>,
    #[cfg_attr(
        feature = "serde",
        serde(with = "crate::serde_support::square_matrices")
    )]
    pub(super) covariances: Vec<DMatrix<f64>>,
    pub(super) memberships: Vec<f64>,
    pub(super) iterations: usize,
    #[cfg_attr(
        feature = "serde",
        serde(with = "haunts_occupancy::serde_float::value")
    )]
    pub(super) objective: f64,
    #[cfg_attr(
        feature = "serde",
        serde(with = "haunts_occupancy::serde_float::value")
    )]
    pub(super) change: f64,
}

/// The fields of a [`GkClustering`] as deserialised, before their shapes and values are
/// checked.
#[cfg(feature = "serde")]
#[derive(serde::Deserialize)]
struct GkClusteringFields {
    dim: usize,
    clusters: usize,
    centres: Vec<f64>,
    #[serde(with = "crate::serde_support::square_matrices")]
    covariances: Vec<DMatrix<f64>>,
    memberships: Vec<f64>,
    iterations: usize,
    #[serde(with = "haunts_occupancy::serde_float::value")]
    objective: f64,
    #[serde(with = "haunts_occupancy::serde_float::value")]
    change: f64,
}

#[cfg(feature = "serde")]
impl TryFrom<GkClusteringFields> for GkClustering {
    type Error = crate::AffordanceError;
    fn try_from(f: GkClusteringFields) -> crate::Result<Self> {
        let bad = |problem: String| crate::AffordanceError::InvalidModel {
            model: "GK clustering",
            problem,
        };
        let (dim, k) = (f.dim, f.clusters);
        if dim == 0 || k == 0 {
            return Err(bad(format!(
                "dim = {dim} and clusters = {k} (both must be >= 1)"
            )));
        }
        if k.checked_mul(dim) != Some(f.centres.len()) {
            return Err(bad(format!(
                "{} centre values for {k} clusters of dimension {dim}",
                f.centres.len()
            )));
        }
        if let Some(i) = f.centres.iter().position(|v| !v.is_finite()) {
            return Err(bad(format!("centre {} is not finite", i / dim)));
        }
        if f.covariances.len() != k {
            return Err(bad(format!(
                "{} covariances for {k} clusters",
                f.covariances.len()
            )));
        }
        for (i, c) in f.covariances.iter().enumerate() {
            if c.nrows() != dim {
                return Err(bad(format!(
                    "covariance {i} is {0} × {0}, expected {dim} × {dim}",
                    c.nrows()
                )));
            }
            if c.iter().any(|v| !v.is_finite()) {
                return Err(bad(format!("covariance {i} is not finite")));
            }
        }
        if f.memberships.len() % k != 0 {
            return Err(bad(format!(
                "{} memberships are not rows of {k} clusters",
                f.memberships.len()
            )));
        }
        for (j, u) in f.memberships.chunks_exact(k).enumerate() {
            let sum: f64 = u.iter().sum();
            if u.iter().any(|v| !(0.0..=1.0).contains(v)) || (sum - 1.0).abs() > 1e-6 {
                return Err(bad(format!(
                    "the memberships of point {j} are not in [0, 1] summing to 1"
                )));
            }
        }
        Ok(Self {
            dim,
            clusters: k,
            centres: f.centres,
            covariances: f.covariances,
            memberships: f.memberships,
            iterations: f.iterations,
            objective: f.objective,
            change: f.change,
        })
    }
}

impl std::fmt::Debug for GkClustering {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("GkClustering")
            .field("dim", &self.dim)
            .field("clusters", &self.clusters)
            .field("points", &self.len())
            .field("iterations", &self.iterations)
            .field("objective", &self.objective)
            .field("change", &self.change)
            .finish_non_exhaustive()
    }
}

impl GkClustering {
    /// Dimension of the data.
    pub fn dim(&self) -> usize {
        self.dim
    }
    /// Number of clusters.
    pub fn clusters(&self) -> usize {
        self.clusters
    }
    /// Number of points clustered.
    pub fn len(&self) -> usize {
        self.memberships.len() / self.clusters.max(1)
    }
    /// Whether no point was clustered (never true for a result of [`GkParams::fit`](super::GkParams::fit)).
    pub fn is_empty(&self) -> bool {
        self.memberships.is_empty()
    }
    /// All prototypes, flat (`clusters × dim`).
    pub fn centres(&self) -> &[f64] {
        &self.centres
    }
    /// Prototype `i`, or `None` past the last cluster.
    pub fn centre(&self, i: usize) -> Option<&[f64]> {
        self.centres.get(i * self.dim..(i + 1) * self.dim)
    }
    /// The regularised fuzzy covariance `Fᵢ` of cluster `i` (before volume normalisation), or
    /// `None` past the last cluster.
    pub fn covariance(&self, i: usize) -> Option<&DMatrix<f64>> {
        self.covariances.get(i)
    }
    /// The norm-inducing matrix `Aᵢ = (ρ det Fᵢ)^{1/d} Fᵢ⁻¹` (determinant `ρ`) of cluster `i`
    /// for volume `ρ`, or `None` past the last cluster or if `Fᵢ` is singular.
    pub fn norm_matrix(&self, i: usize, volume: f64) -> Option<DMatrix<f64>> {
        let f = self.covariances.get(i)?;
        let inv = f.clone().try_inverse()?;
        Some(inv * (volume * f.determinant()).powf(1.0 / self.dim as f64))
    }
    /// The fuzzy partition, flat and row-major: `clusters` memberships per point, each row
    /// summing to 1.
    pub fn memberships(&self) -> &[f64] {
        &self.memberships
    }
    /// The memberships of point `j`, or `None` past the last point.
    pub fn membership(&self, j: usize) -> Option<&[f64]> {
        self.memberships
            .get(j * self.clusters..(j + 1) * self.clusters)
    }
    /// The cluster of largest membership of each point (the lowest index on ties).
    pub fn hard_labels(&self) -> Vec<usize> {
        self.memberships
            .chunks_exact(self.clusters.max(1))
            .map(|u| {
                let mut best = 0;
                for (i, v) in u.iter().enumerate() {
                    if *v > u[best] {
                        best = i;
                    }
                }
                best
            })
            .collect()
    }
    /// Iterations run.
    pub fn iterations(&self) -> usize {
        self.iterations
    }
    /// The objective `J = Σᵢⱼ uᵢⱼᵐ d²ᵢⱼ` (eq. 2) of the last iteration.
    pub fn objective(&self) -> f64 {
        self.objective
    }
    /// The largest change of a membership in the last iteration (∞ after one iteration).
    pub fn change(&self) -> f64 {
        self.change
    }
}
