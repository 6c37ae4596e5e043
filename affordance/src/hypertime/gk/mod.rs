//! Gustafson–Kessel fuzzy clustering (seed 001 eqs. 2–7; Gustafson & Kessel 1979), with
//! Babuška's covariance regularisation and seeded k-means++ initialisation.
//!
//! [`GkRun`] holds a clustering in progress; each of its iterations is one fused pass over the
//! points (distances, memberships and the weighted sums for the next prototypes, module
//! `pass`), then a small update of the `c` prototypes. Every sum over points is taken block by
//! block ([`BLOCK`] rows, whatever the number of threads) and the block sums are added in block
//! order, so results are bit-identical with one thread or many.

use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};

use crate::{AffordanceError, Result};

mod clustering;
mod params;
mod pass;
mod run;
#[cfg(test)]
mod tests;

pub use clustering::GkClustering;
pub use params::{GkParams, Regularisation};
pub use run::GkRun;

/// Rows per block of every parallel pass; fixed so that sums do not depend on threads.
pub(crate) const BLOCK: usize = 512;

impl GkParams {
    /// Gustafson–Kessel clustering of `data` (flat, row-major, `dim` values per row), started
    /// from [`kmeans_plus_plus`] centres with identity covariances.
    ///
    /// Each iteration (seed 001 eqs. 2–7, with the fuzzy covariance weighted by `uᵐ` as in
    /// Gustafson & Kessel; the seed's eq. 7 prints `u`):
    /// 1. distances `d²ᵢⱼ = (xⱼ − cᵢ)ᵀ Aᵢ (xⱼ − cᵢ)`, `Aᵢ = (ρ det Fᵢ)^{1/d} Fᵢ⁻¹`, so every
    ///    `Aᵢ` has determinant `ρ`;
    /// 2. memberships `uᵢⱼ = 1 / Σₖ (d²ᵢⱼ / d²ₖⱼ)^{1/(m−1)}` (a point on one or more prototypes
    ///    shares its membership equally among them), so `Σᵢ uᵢⱼ = 1`;
    /// 3. prototypes `cᵢ = Σⱼ uᵢⱼᵐ xⱼ / Σⱼ uᵢⱼᵐ` and fuzzy covariances
    ///    `Fᵢ = Σⱼ uᵢⱼᵐ (xⱼ − cᵢ)(xⱼ − cᵢ)ᵀ / Σⱼ uᵢⱼᵐ`, regularised by [`Regularisation`]; a
    ///    cluster whose total weight underflows to 0 keeps its prototype and covariance;
    ///
    /// until no membership changes by more than `tolerance`.
    ///
    /// # Errors
    /// [`AffordanceError::InvalidParameter`] for bad parameters;
    /// [`AffordanceError::BadShape`] if `dim == 0` or `data.len()` is not a multiple of `dim`;
    /// [`AffordanceError::TooFewPoints`] if there are fewer rows than clusters;
    /// [`AffordanceError::NonFiniteInput`] naming the first non-finite value;
    /// [`AffordanceError::DegenerateCovariance`] naming a cluster whose covariance overflowed;
    /// [`AffordanceError::NotConverged`] with the clustering after the last iteration.
    ///
    /// # Complexity
    /// `O(n·c·d²)` time per iteration and `O(n·c)` memory for the memberships; parallel over
    /// blocks of rows with the `rayon` feature.
    ///
    /// ```
    /// use haunts_affordance::hypertime::GkParams;
    /// // Two tight groups on a line.
    /// let data = [0.0, 0.0, 0.1, 0.0, 0.0, 0.1, 5.0, 5.0, 5.1, 5.0, 5.0, 5.1];
    /// let gk = GkParams::default().with_clusters(2).fit(&data, 2)?;
    /// let mut xs: Vec<f64> = (0..2).map(|i| gk.centre(i).unwrap()[0]).collect();
    /// xs.sort_by(f64::total_cmp);
    /// approx::assert_abs_diff_eq!(xs[0], 1.0 / 30.0, epsilon = 1e-3);
    /// approx::assert_abs_diff_eq!(xs[1], 5.0 + 1.0 / 30.0, epsilon = 1e-3);
    /// # Ok::<(), haunts_affordance::AffordanceError>(())
    /// ```
    pub fn fit(&self, data: &[f64], dim: usize) -> Result<GkClustering> {
        let params = self.check()?;
        check_data(data, dim, params.clusters)?;
        let centres = kmeans_plus_plus(data, dim, params.clusters, params.seed)?;
        run(GkRun::new(params, data, dim, centres))
    }

    /// As [`fit`](Self::fit), from given initial centres (flat, `clusters × dim`) instead of
    /// k-means++.
    ///
    /// # Errors
    /// As [`fit`](Self::fit); [`AffordanceError::BadShape`] if `centres` does not hold
    /// `clusters × dim` values, [`AffordanceError::NonFiniteInput`] (row = cluster) if one is
    /// not finite.
    pub fn fit_from(&self, data: &[f64], dim: usize, centres: &[f64]) -> Result<GkClustering> {
        run(self.start_from(data, dim, centres)?)
    }

    /// A clustering of `data` from given initial centres (flat, `clusters × dim`) with identity
    /// covariances, to be advanced one iteration at a time with [`GkRun::step`] (no
    /// convergence test): for timing iterations, or stopping by another rule.
    ///
    /// # Errors
    /// As [`fit_from`](Self::fit_from), but never [`AffordanceError::NotConverged`] or
    /// [`AffordanceError::DegenerateCovariance`] (those come from the steps).
    pub fn start_from<'a>(
        &self,
        data: &'a [f64],
        dim: usize,
        centres: &[f64],
    ) -> Result<GkRun<'a>> {
        let params = self.check()?;
        check_data(data, dim, params.clusters)?;
        if centres.len() != params.clusters * dim {
            return Err(AffordanceError::BadShape {
                len: centres.len(),
                dim,
            });
        }
        check_finite(centres, dim)?;
        Ok(GkRun::new(params, data, dim, centres.to_vec()))
    }
}

/// Checks the shape and finiteness of `data`; returns the number of rows.
fn check_data(data: &[f64], dim: usize, clusters: usize) -> Result<usize> {
    if dim == 0 || data.len() % dim != 0 {
        return Err(AffordanceError::BadShape {
            len: data.len(),
            dim,
        });
    }
    let n = data.len() / dim;
    if n < clusters || n == 0 {
        return Err(AffordanceError::TooFewPoints {
            points: n,
            clusters,
        });
    }
    check_finite(data, dim)?;
    Ok(n)
}

fn check_finite(data: &[f64], dim: usize) -> Result<()> {
    match data.iter().position(|v| !v.is_finite()) {
        Some(i) => Err(AffordanceError::NonFiniteInput {
            row: i / dim,
            column: i % dim,
        }),
        None => Ok(()),
    }
}

/// Seeded k-means++ seeding (Arthur & Vassilvitskii 2007): the first centre uniformly, each
/// next one with probability proportional to the squared distance to the nearest centre so
/// far (uniformly when every point sits on a centre). Returns `k × dim` values, flat.
///
/// # Errors
/// [`AffordanceError::BadShape`], [`AffordanceError::TooFewPoints`] (fewer rows than `k`, or
/// `k = 0`), [`AffordanceError::NonFiniteInput`].
pub fn kmeans_plus_plus(data: &[f64], dim: usize, k: usize, seed: u64) -> Result<Vec<f64>> {
    let n = check_data(data, dim, k.max(1))?;
    if k == 0 {
        return Err(AffordanceError::TooFewPoints {
            points: n,
            clusters: 0,
        });
    }
    let mut rng = StdRng::seed_from_u64(seed);
    let row = |i: usize| &data[i * dim..(i + 1) * dim];
    let mut centres = Vec::with_capacity(k * dim);
    centres.extend_from_slice(row(rng.random_range(0..n)));
    let mut d2 = vec![f64::INFINITY; n];
    while centres.len() < k * dim {
        let last = &centres[centres.len() - dim..];
        for_each_block_mut(&mut d2, 1, |b, chunk| {
            for (o, d) in chunk.iter_mut().enumerate() {
                let x = row(b * BLOCK + o);
                let s: f64 = x.iter().zip(last).map(|(a, c)| (a - c) * (a - c)).sum();
                *d = d.min(s);
            }
        });
        let total: f64 = d2.iter().sum();
        let next = if total > 0.0 && total.is_finite() {
            let mut t = rng.random_range(0.0..total);
            let mut pick = n - 1;
            for (i, d) in d2.iter().enumerate() {
                if t < *d {
                    pick = i;
                    break;
                }
                t -= d;
            }
            pick
        } else {
            rng.random_range(0..n)
        };
        centres.extend_from_slice(row(next));
    }
    Ok(centres)
}

/// Runs `f(block index, chunk)` on consecutive chunks of `BLOCK × width` values of `v`, in
/// parallel with the `rayon` feature.
fn for_each_block_mut(v: &mut [f64], width: usize, f: impl Fn(usize, &mut [f64]) + Sync + Send) {
    #[cfg(feature = "rayon")]
    {
        use rayon::prelude::*;
        v.par_chunks_mut(BLOCK * width)
            .enumerate()
            .for_each(|(b, c)| f(b, c));
    }
    #[cfg(not(feature = "rayon"))]
    v.chunks_mut(BLOCK * width)
        .enumerate()
        .for_each(|(b, c)| f(b, c));
}

/// `f(block, rows of the block, memberships of the block)` on every block, results in block
/// order; parallel with the `rayon` feature.
pub(crate) fn map_blocks<T: Send>(
    data: &[f64],
    dim: usize,
    memberships: &mut [f64],
    k: usize,
    f: impl Fn(&[f64], &mut [f64]) -> T + Sync + Send,
) -> Vec<T> {
    #[cfg(feature = "rayon")]
    {
        use rayon::prelude::*;
        data.par_chunks(BLOCK * dim)
            .zip(memberships.par_chunks_mut(BLOCK * k))
            .map(|(x, u)| f(x, u))
            .collect()
    }
    #[cfg(not(feature = "rayon"))]
    data.chunks(BLOCK * dim)
        .zip(memberships.chunks_mut(BLOCK * k))
        .map(|(x, u)| f(x, u))
        .collect()
}

/// The loop of [`GkParams::fit`]: iterations until no membership changes by more than the
/// tolerance.
fn run(mut state: GkRun<'_>) -> Result<GkClustering> {
    let params = state.params();
    for _ in 0..params.max_iterations {
        let change = state.step()?;
        if state.iterations() > 1 && change <= params.tolerance {
            return Ok(state.into_clustering());
        }
    }
    let change = state.change();
    Err(AffordanceError::NotConverged {
        iterations: params.max_iterations,
        change,
        partial: Box::new(state.into_clustering()),
    })
}
