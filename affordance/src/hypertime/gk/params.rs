//! The parameters of the Gustafson–Kessel clustering and its covariance regularisation.

use nalgebra::{DMatrix, DVector};

use crate::{AffordanceError, Result};

/// How cluster covariances are kept invertible (Babuška, van der Veen & Kaymak, "Improved
/// covariance estimation for Gustafson–Kessel clustering", FUZZ-IEEE 2002), applied in this
/// order to each fuzzy covariance `F`:
///
/// 1. **identity blending**: `F ← (1 − γ)·F + γ·det(F₀)^{1/d}·I`, `F₀` the covariance of the
///    whole data set (its mean variance `tr(F₀)/d` when `F₀` is singular; `γ = 0` turns
///    blending off);
/// 2. **eigenvalue ratio**: every eigenvalue is raised to at least `λ_max / β`, and to at
///    least the absolute floor `ε` (so a cluster of identical points stays invertible).
///
/// Points of the time dimensions lie on a circle, so a cluster that spans a short stretch of
/// time is nearly flat across the circle: step 2 bounds how flat.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Regularisation {
    /// `γ` in `[0, 1]`.
    pub identity_blend: f64,
    /// `β ≥ 1`: the largest allowed ratio of a cluster's largest to smallest eigenvalue.
    pub max_condition: f64,
    /// `ε > 0`: the smallest allowed eigenvalue, in the data's squared units.
    pub min_eigenvalue: f64,
}

impl Default for Regularisation {
    /// `γ = 0`, `β = 100` (standard deviations at most 10:1), `ε = 10⁻⁹`.
    fn default() -> Self {
        Self {
            identity_blend: 0.0,
            max_condition: 1e2,
            min_eigenvalue: 1e-9,
        }
    }
}

impl Regularisation {
    /// The rules, checked: `0 ≤ γ ≤ 1`, `β ≥ 1` finite, `ε > 0` finite.
    ///
    /// # Errors
    /// [`AffordanceError::InvalidParameter`] naming the first rule broken.
    pub fn check(self) -> Result<Self> {
        rule(
            (0.0..=1.0).contains(&self.identity_blend),
            "identity_blend",
            self.identity_blend,
            "must be in [0, 1]",
        )?;
        rule(
            self.max_condition.is_finite() && self.max_condition >= 1.0,
            "max_condition",
            self.max_condition,
            "must be finite and >= 1",
        )?;
        rule(
            self.min_eigenvalue.is_finite() && self.min_eigenvalue > 0.0,
            "min_eigenvalue",
            self.min_eigenvalue,
            "must be finite and > 0",
        )?;
        Ok(self)
    }

    /// The eigen-decomposition `(λ, Φ)` of the regularised `f`, or `None` if `f` is not finite.
    /// `nu` is `det(F₀)^{1/d}`.
    pub(crate) fn apply(&self, f: DMatrix<f64>, nu: f64) -> Option<(DVector<f64>, DMatrix<f64>)> {
        if f.iter().any(|v| !v.is_finite()) {
            return None;
        }
        let d = f.nrows();
        let f = if self.identity_blend > 0.0 {
            f * (1.0 - self.identity_blend) + DMatrix::identity(d, d) * (self.identity_blend * nu)
        } else {
            f
        };
        let eig = f.symmetric_eigen();
        let max = eig.eigenvalues.max();
        let floor = (max / self.max_condition).max(self.min_eigenvalue);
        let values = eig.eigenvalues.map(|l| l.max(floor));
        (values.iter().all(|l| l.is_finite()) && eig.eigenvectors.iter().all(|v| v.is_finite()))
            .then_some((values, eig.eigenvectors))
    }
}

/// Parameters of [`GkParams::fit`].
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub struct GkParams {
    /// Number of clusters `c` (seed 001: 30).
    pub clusters: usize,
    /// Fuzzifier `m > 1` (seed 001: 2).
    pub fuzzifier: f64,
    /// Cluster volume `ρ > 0`: every norm-inducing matrix has determinant `ρ` (eq. 6). With
    /// one `ρ` for all clusters it scales every distance alike, so memberships and prototypes do
    /// not depend on it; it scales the objective `J`.
    pub volume: f64,
    /// Convergence: stop when no membership changed by more than this between two iterations
    /// (`≥ 0`; `0` stops only at an exact fixed point).
    pub tolerance: f64,
    /// Iteration cap (`≥ 1`).
    pub max_iterations: usize,
    /// How covariances are kept invertible.
    pub regularisation: Regularisation,
    /// Seed of the k-means++ initialisation.
    pub seed: u64,
}

impl Default for GkParams {
    /// 30 clusters, `m = 2`, `ρ = 1`, tolerance `10⁻³`, at most 300 iterations, the default
    /// [`Regularisation`], seed 0.
    fn default() -> Self {
        Self {
            clusters: 30,
            fuzzifier: 2.0,
            volume: 1.0,
            tolerance: 1e-3,
            max_iterations: 300,
            regularisation: Regularisation::default(),
            seed: 0,
        }
    }
}

fn rule(ok: bool, name: &'static str, value: f64, rule: &'static str) -> Result<()> {
    if ok {
        Ok(())
    } else {
        Err(AffordanceError::InvalidParameter(
            haunts_core::InvalidParameter { name, value, rule },
        ))
    }
}

impl GkParams {
    /// Sets the number of clusters.
    pub fn with_clusters(mut self, clusters: usize) -> Self {
        self.clusters = clusters;
        self
    }
    /// Sets the fuzzifier `m`.
    pub fn with_fuzzifier(mut self, fuzzifier: f64) -> Self {
        self.fuzzifier = fuzzifier;
        self
    }
    /// Sets the cluster volume `ρ`.
    pub fn with_volume(mut self, volume: f64) -> Self {
        self.volume = volume;
        self
    }
    /// Sets the convergence tolerance on memberships.
    pub fn with_tolerance(mut self, tolerance: f64) -> Self {
        self.tolerance = tolerance;
        self
    }
    /// Sets the iteration cap.
    pub fn with_max_iterations(mut self, max_iterations: usize) -> Self {
        self.max_iterations = max_iterations;
        self
    }
    /// Sets the covariance regularisation.
    pub fn with_regularisation(mut self, regularisation: Regularisation) -> Self {
        self.regularisation = regularisation;
        self
    }
    /// Sets the seed of the initialisation.
    pub fn with_seed(mut self, seed: u64) -> Self {
        self.seed = seed;
        self
    }

    /// The parameters, checked: `clusters ≥ 1`, `m > 1` finite, `ρ > 0` finite,
    /// `tolerance ≥ 0` finite, `max_iterations ≥ 1`, and the regularisation's rules.
    ///
    /// # Errors
    /// [`AffordanceError::InvalidParameter`] naming the first rule broken.
    pub fn check(self) -> Result<Self> {
        rule(
            self.clusters >= 1,
            "clusters",
            self.clusters as f64,
            "must be >= 1",
        )?;
        rule(
            self.fuzzifier.is_finite() && self.fuzzifier > 1.0,
            "fuzzifier",
            self.fuzzifier,
            "must be finite and > 1",
        )?;
        rule(
            self.volume.is_finite() && self.volume > 0.0,
            "volume",
            self.volume,
            "must be finite and > 0",
        )?;
        rule(
            self.tolerance.is_finite() && self.tolerance >= 0.0,
            "tolerance",
            self.tolerance,
            "must be finite and >= 0",
        )?;
        rule(
            self.max_iterations >= 1,
            "max_iterations",
            self.max_iterations as f64,
            "must be >= 1",
        )?;
        self.regularisation.check()?;
        Ok(self)
    }
}
