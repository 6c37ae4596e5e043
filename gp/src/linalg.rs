//! The dense linear algebra of the crate, on faer: Cholesky with an explicit jitter policy,
//! triangular solves, the inverse from a factor, and parallel filling of kernel matrices.
//!
//! faer stores matrices column-major; every matrix here is symmetric or is filled column by
//! column, so the layout never leaks out of this module and `exact`/`sparse`.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::{LltRegularization, cholesky_in_place};
use faer::{Mat, MatMut, MatRef, Par};

use crate::error::{GpError, Result};
use crate::kernel::Kernel;

/// The parallelism faer uses: every rayon thread with the `rayon` feature, else sequential.
pub(crate) fn par() -> Par {
    #[cfg(feature = "rayon")]
    {
        Par::rayon(0)
    }
    #[cfg(not(feature = "rayon"))]
    Par::Seq
}

/// How much is added to the diagonal when a covariance matrix is not numerically positive
/// definite, and how it escalates.
///
/// Attempt 0 adds nothing; attempt k ≥ 1 adds `initial · growth^(k−1)` times the mean of the
/// diagonal (so the policy is scale free), up to `max_attempts` attempts in all. The jitter
/// that succeeded is reported by the fitted model ([`crate::ExactGp::jitter`]); a matrix that
/// fails every attempt is [`GpError::NotPositiveDefinite`].
///
/// The default (1e-10, ×10, 7 attempts, i.e. up to 1e-5 of the mean variance) is GPy's
/// `jitchol` escalation; scikit-learn instead adds a fixed `alpha = 1e-10` and fails.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct JitterPolicy {
    /// First jitter, relative to the mean of the diagonal.
    pub initial: f64,
    /// Factor between consecutive jitters (> 1).
    pub growth: f64,
    /// Attempts in all, the first without jitter (1 ..= [`JitterPolicy::MAX_ATTEMPTS`]).
    pub max_attempts: u32,
}

impl Default for JitterPolicy {
    fn default() -> Self {
        Self {
            initial: 1e-10,
            growth: 10.0,
            max_attempts: 7,
        }
    }
}

impl JitterPolicy {
    /// The most attempts a policy may make: each one is a factorisation (O(n³) for an exact
    /// GP), and a hundred steps of any growth > 1 cover every useful jitter. Without a bound
    /// a policy read from a file could ask for billions.
    pub const MAX_ATTEMPTS: u32 = 100;

    /// No jitter at all: a matrix that is not positive definite is an error at once.
    pub fn none() -> Self {
        Self {
            max_attempts: 1,
            ..Self::default()
        }
    }

    /// Checks the rules of each field.
    ///
    /// # Errors
    /// [`GpError::InvalidParameter`] naming the field that breaks its rule.
    pub fn check(self) -> Result<Self> {
        if !(self.initial.is_finite() && self.initial > 0.0) {
            return Err(GpError::invalid(
                "jitter.initial",
                self.initial,
                "finite and > 0",
            ));
        }
        if !(self.growth.is_finite() && self.growth > 1.0) {
            return Err(GpError::invalid(
                "jitter.growth",
                self.growth,
                "finite and > 1",
            ));
        }
        if !(1..=Self::MAX_ATTEMPTS).contains(&self.max_attempts) {
            return Err(GpError::invalid(
                "jitter.max_attempts",
                f64::from(self.max_attempts),
                "between 1 and 100",
            ));
        }
        Ok(self)
    }

    /// The relative jitter of attempt `k` (0 for the first).
    fn relative(&self, k: u32) -> f64 {
        if k == 0 {
            0.0
        } else {
            self.initial * self.growth.powi(k as i32 - 1)
        }
    }
}

/// A lower Cholesky factor `L` (its strict upper triangle is garbage: never read it) with the
/// absolute jitter that was added to the diagonal.
#[derive(Debug, Clone)]
pub(crate) struct Factor {
    pub(crate) l: Mat<f64>,
    pub(crate) jitter: f64,
}

impl Factor {
    /// log det(L Lᵀ) = 2 Σ ln L_ii.
    pub(crate) fn log_det(&self) -> f64 {
        2.0 * (0..self.l.nrows())
            .map(|i| self.l[(i, i)].ln())
            .sum::<f64>()
    }

    /// Solves `L x = b` in place for every column of `rhs`.
    pub(crate) fn solve_lower(&self, rhs: MatMut<'_, f64>) {
        faer::linalg::triangular_solve::solve_lower_triangular_in_place(
            self.l.as_ref(),
            rhs,
            par(),
        );
    }

    /// Solves `Lᵀ x = b` in place for every column of `rhs`.
    pub(crate) fn solve_upper(&self, rhs: MatMut<'_, f64>) {
        faer::linalg::triangular_solve::solve_upper_triangular_in_place(
            self.l.as_ref().transpose(),
            rhs,
            par(),
        );
    }

    /// Solves `(L Lᵀ) x = b` for one vector.
    pub(crate) fn solve_vec(&self, b: &[f64]) -> Vec<f64> {
        let mut m = Mat::from_fn(b.len(), 1, |i, _| b[i]);
        self.solve_lower(m.as_mut());
        self.solve_upper(m.as_mut());
        (0..b.len()).map(|i| m[(i, 0)]).collect()
    }

    /// The lower triangle of (L Lᵀ)⁻¹ (the strict upper triangle is zero).
    pub(crate) fn inverse_lower(&self) -> Mat<f64> {
        let n = self.l.nrows();
        let mut out = Mat::zeros(n, n);
        let par = par();
        let mut buf =
            MemBuffer::new(faer::linalg::cholesky::llt::inverse::inverse_scratch::<f64>(n, par));
        faer::linalg::cholesky::llt::inverse::inverse(
            out.as_mut(),
            self.l.as_ref(),
            par,
            MemStack::new(&mut buf),
        );
        out
    }
}

/// Factors the symmetric matrix that `fill` writes (at least its lower triangle) as `L Lᵀ`,
/// escalating the jitter by `policy` until the factorisation succeeds.
///
/// `fill` is called again before each further attempt (it must write the same matrix): a
/// refill costs less than keeping an n × n copy to restart from on every call.
pub(crate) fn cholesky_with_jitter(
    n: usize,
    fill: impl Fn(MatMut<'_, f64>),
    policy: &JitterPolicy,
) -> Result<Factor> {
    cholesky_with_floor(n, fill, policy, 0.0)
}

/// As [`cholesky_with_jitter`], but an attempt whose smallest pivot `L_ii²` is below
/// `floor` times the mean of the diagonal counts as failed too: the factor of a matrix that
/// is singular to working precision is numerically meaningless even when no pivot is negative
/// (its small pivots are mostly rounding), and what is computed from it jumps with θ.
pub(crate) fn cholesky_with_floor(
    n: usize,
    fill: impl Fn(MatMut<'_, f64>),
    policy: &JitterPolicy,
    floor: f64,
) -> Result<Factor> {
    let mut a = Mat::<f64>::zeros(n, n);
    fill(a.as_mut());
    if let Some(i) = (0..n).find(|&i| !a[(i, i)].is_finite()) {
        return Err(GpError::NonFiniteMatrix { index: i });
    }
    let mean_diag = if n == 0 {
        0.0
    } else {
        (0..n).map(|i| a[(i, i)]).sum::<f64>() / n as f64
    };
    let par = par();
    let mut buf = MemBuffer::new(
        faer::linalg::cholesky::llt::factor::cholesky_in_place_scratch::<f64>(
            n,
            par,
            Default::default(),
        ),
    );
    let mut last_pivot = 0;
    for k in 0..policy.max_attempts {
        let jitter = policy.relative(k) * mean_diag.abs();
        if k > 0 {
            fill(a.as_mut());
            for i in 0..n {
                a[(i, i)] += jitter;
            }
        }
        match cholesky_in_place(
            a.as_mut(),
            LltRegularization::default(),
            par,
            MemStack::new(&mut buf),
            Default::default(),
        ) {
            Ok(_) => {
                let smallest = (0..n).min_by(|&i, &j| a[(i, i)].total_cmp(&a[(j, j)]));
                match smallest {
                    Some(i) if a[(i, i)] * a[(i, i)] < floor * mean_diag.abs() => last_pivot = i,
                    _ => return Ok(Factor { l: a, jitter }),
                }
            }
            Err(faer::linalg::cholesky::llt::factor::LltError::NonPositivePivot { index }) => {
                last_pivot = index;
            }
        }
    }
    Err(GpError::NotPositiveDefinite {
        pivot: last_pivot,
        max_jitter: policy.relative(policy.max_attempts - 1) * mean_diag.abs(),
    })
}

/// Writes the covariance matrix of the points `x` (flat, `dim` per point) into `out`,
/// lower triangle and diagonal only, plus `diag_add` on the diagonal. Parallel by column.
pub(crate) fn fill_covariance_lower(
    kernel: &dyn Kernel,
    x: &[f64],
    dim: usize,
    diag_add: f64,
    out: MatMut<'_, f64>,
) {
    for_each_column(out, |j, col| {
        let b = &x[j * dim..(j + 1) * dim];
        for (i, c) in col.iter_mut().enumerate().skip(j) {
            *c = kernel.value(&x[i * dim..(i + 1) * dim], b);
        }
        col[j] += diag_add;
    });
}

/// Writes K(x1, x2) (`n1 × n2`) into `out`, parallel by column (one column per point of `x2`).
pub(crate) fn fill_cross(
    kernel: &dyn Kernel,
    x1: &[f64],
    x2: &[f64],
    dim: usize,
    out: MatMut<'_, f64>,
) {
    for_each_column(out, |j, col| {
        let b = &x2[j * dim..(j + 1) * dim];
        for (c, a) in col.iter_mut().zip(x1.chunks_exact(dim)) {
            *c = kernel.value(a, b);
        }
    });
}

/// Calls `f(j, column j)` for every column of a column-major matrix with unit row stride, in
/// parallel with the `rayon` feature.
pub(crate) fn for_each_column(m: MatMut<'_, f64>, f: impl Fn(usize, &mut [f64]) + Sync + Send) {
    let cols: Vec<&mut [f64]> = m
        .col_iter_mut()
        .map(|c| {
            c.try_as_col_major_mut()
                .map_or(&mut [][..], |c| c.as_slice_mut())
        })
        .collect();
    #[cfg(feature = "rayon")]
    {
        use rayon::prelude::*;
        cols.into_par_iter().enumerate().for_each(|(j, c)| f(j, c));
    }
    #[cfg(not(feature = "rayon"))]
    cols.into_iter().enumerate().for_each(|(j, c)| f(j, c));
}

/// A column-major view of a row-major-indexed matrix's column as a slice, for reading.
pub(crate) fn col(m: MatRef<'_, f64>, j: usize) -> &[f64] {
    m.col(j).try_as_col_major().map_or(&[], |c| c.as_slice())
}

/// `(0..n).map(f)` collected in order, in parallel with the `rayon` feature.
pub(crate) fn map_range<T: Send>(n: usize, f: impl Fn(usize) -> T + Sync + Send) -> Vec<T> {
    #[cfg(feature = "rayon")]
    {
        use rayon::prelude::*;
        (0..n).into_par_iter().map(f).collect()
    }
    #[cfg(not(feature = "rayon"))]
    (0..n).map(f).collect()
}
