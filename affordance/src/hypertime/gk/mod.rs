//! Gustafson–Kessel fuzzy clustering (seed 001 eqs. 2–7; Gustafson & Kessel 1979), with
//! Babuška's covariance regularisation and seeded k-means++ initialisation.
//!
//! Every sum over points is taken block by block ([`BLOCK`] rows, whatever the number of
//! threads) and the block sums are added in block order, so results are bit-identical with
//! one thread or many.

use nalgebra::{DMatrix, DVector};
use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};

use crate::{AffordanceError, Result};

mod clustering;
mod params;

pub use clustering::GkClustering;
pub(crate) use clustering::membership_totals;
pub use params::{GkParams, Regularisation};

/// Rows per block of every parallel pass; fixed so that sums do not depend on threads.
pub const BLOCK: usize = 512;

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
        run(&params, data, dim, centres)
    }

    /// As [`fit`](Self::fit), from given initial centres (flat, `clusters × dim`) instead of
    /// k-means++.
    ///
    /// # Errors
    /// As [`fit`](Self::fit); [`AffordanceError::BadShape`] if `centres` does not hold
    /// `clusters × dim` values, [`AffordanceError::NonFiniteInput`] (row = cluster) if one is
    /// not finite.
    pub fn fit_from(&self, data: &[f64], dim: usize, centres: &[f64]) -> Result<GkClustering> {
        let params = self.check()?;
        check_data(data, dim, params.clusters)?;
        if centres.len() != params.clusters * dim {
            return Err(AffordanceError::BadShape {
                len: centres.len(),
                dim,
            });
        }
        check_finite(centres, dim)?;
        run(&params, data, dim, centres.to_vec())
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

/// Index of the packed upper triangle, row by row: `(0,0), (0,1), …, (0,d−1), (1,1), …`.
fn packed_len(d: usize) -> usize {
    d * (d + 1) / 2
}

/// The prototypes of one iteration: centres and packed norm-inducing matrices, off-diagonal
/// entries doubled so that `dᵀAd = Σ packed · products`.
struct Prototypes {
    centres: Vec<f64>,
    norms: Vec<f64>,
    covariances: Vec<DMatrix<f64>>,
}

/// One block's sums: per cluster `Σw`, `Σw·δ`, `Σw·δδᵀ` (packed), with `δ = x − c_old`.
struct Partial {
    w: Vec<f64>,
    wd: Vec<f64>,
    wdd: Vec<f64>,
    objective: f64,
    change: f64,
}

fn pack_norm(a: &DMatrix<f64>, out: &mut [f64]) {
    let d = a.nrows();
    let mut p = 0;
    for r in 0..d {
        for c in r..d {
            out[p] = if r == c {
                a[(r, c)]
            } else {
                a[(r, c)] + a[(c, r)]
            };
            p += 1;
        }
    }
}

/// The memberships of one point from its squared distances (see [`GkParams::fit`] step 2).
pub(crate) fn memberships_from(d2: &[f64], exponent: f64, u: &mut [f64]) {
    let min = d2.iter().copied().fold(f64::INFINITY, f64::min);
    if min <= 0.0 {
        let zeros = d2.iter().filter(|v| **v <= 0.0).count() as f64;
        for (u, d) in u.iter_mut().zip(d2) {
            *u = if *d <= 0.0 { 1.0 / zeros } else { 0.0 };
        }
        return;
    }
    let mut sum = 0.0;
    for (u, d) in u.iter_mut().zip(d2) {
        let r = min / d;
        *u = if exponent == 1.0 { r } else { r.powf(exponent) };
        sum += *u;
    }
    // sum ≥ 1: the nearest prototype contributes exactly 1.
    for u in u.iter_mut() {
        *u /= sum;
    }
}

/// One pass over a block: memberships from the current prototypes, and the block's sums.
/// `D` is the dimension when known at compile time (the loops then unroll), 0 otherwise.
fn block_pass<const D: usize>(
    x: &[f64],
    u: &mut [f64],
    proto: &Prototypes,
    dim: usize,
    k: usize,
    m: f64,
    first: bool,
) -> Partial {
    let dim = if D == 0 { dim } else { D };
    let p = packed_len(dim);
    let mut part = Partial {
        w: vec![0.0; k],
        wd: vec![0.0; k * dim],
        wdd: vec![0.0; k * p],
        objective: 0.0,
        change: 0.0,
    };
    let exponent = 1.0 / (m - 1.0);
    let mut diff = vec![0.0; k * dim];
    let mut d2 = vec![0.0; k];
    let mut new_u = vec![0.0; k];
    for (row, u_row) in x.chunks_exact(dim).zip(u.chunks_exact_mut(k)) {
        for c in 0..k {
            let centre = &proto.centres[c * dim..(c + 1) * dim];
            let dc = &mut diff[c * dim..(c + 1) * dim];
            for ((o, a), b) in dc.iter_mut().zip(row).zip(centre) {
                *o = a - b;
            }
            let norm = &proto.norms[c * p..(c + 1) * p];
            let mut q = 0.0;
            let mut i = 0;
            for (a, da) in dc.iter().enumerate() {
                let len = dim - a;
                let s: f64 = norm[i..i + len]
                    .iter()
                    .zip(&dc[a..])
                    .map(|(m, x)| m * x)
                    .sum();
                i += len;
                q += da * s;
            }
            d2[c] = q.max(0.0);
        }
        memberships_from(&d2, exponent, &mut new_u);
        for c in 0..k {
            if !first {
                part.change = part.change.max((new_u[c] - u_row[c]).abs());
            }
            u_row[c] = new_u[c];
            let w = if m == 2.0 {
                new_u[c] * new_u[c]
            } else {
                new_u[c].powf(m)
            };
            if w == 0.0 {
                continue;
            }
            part.w[c] += w;
            part.objective += w * d2[c];
            let dc = &diff[c * dim..(c + 1) * dim];
            for (s, v) in part.wd[c * dim..(c + 1) * dim].iter_mut().zip(dc) {
                *s += w * v;
            }
            let acc = &mut part.wdd[c * p..(c + 1) * p];
            let mut i = 0;
            for (a, da) in dc.iter().enumerate() {
                let (wa, len) = (w * da, dim - a);
                for (s, x) in acc[i..i + len].iter_mut().zip(&dc[a..]) {
                    *s += wa * x;
                }
                i += len;
            }
        }
    }
    if first {
        part.change = f64::INFINITY;
    }
    part
}

/// Unpacks a packed symmetric matrix (no doubling).
pub(crate) fn unpack(packed: &[f64], d: usize, scale: f64) -> DMatrix<f64> {
    let mut m = DMatrix::zeros(d, d);
    let mut i = 0;
    for r in 0..d {
        for c in r..d {
            m[(r, c)] = packed[i] * scale;
            m[(c, r)] = packed[i] * scale;
            i += 1;
        }
    }
    m
}

/// `det(F₀)^{1/d}` of the covariance of the whole data set (its mean variance if singular),
/// the scale of Babuška's identity blending.
fn data_scale(data: &[f64], dim: usize) -> f64 {
    let n = (data.len() / dim) as f64;
    let p = packed_len(dim);
    // Blockwise sums about the first row (exact shift formula), added in block order.
    let origin = &data[..dim];
    let parts: Vec<(Vec<f64>, Vec<f64>)> = data
        .chunks(BLOCK * dim)
        .map(|block| {
            let mut s = vec![0.0; dim];
            let mut ss = vec![0.0; p];
            for row in block.chunks_exact(dim) {
                let mut i = 0;
                for a in 0..dim {
                    let da = row[a] - origin[a];
                    s[a] += da;
                    for b in a..dim {
                        ss[i] += da * (row[b] - origin[b]);
                        i += 1;
                    }
                }
            }
            (s, ss)
        })
        .collect();
    let mut s = vec![0.0; dim];
    let mut ss = vec![0.0; p];
    for (a, b) in &parts {
        s.iter_mut().zip(a).for_each(|(x, y)| *x += y);
        ss.iter_mut().zip(b).for_each(|(x, y)| *x += y);
    }
    let mean = DVector::from_iterator(dim, s.iter().map(|v| v / n));
    let cov = unpack(&ss, dim, 1.0 / n) - &mean * mean.transpose();
    let eig = cov.symmetric_eigen();
    if eig.eigenvalues.iter().all(|l| *l > 0.0) {
        (eig.eigenvalues.iter().map(|l| l.ln()).sum::<f64>() / dim as f64).exp()
    } else {
        (eig.eigenvalues.sum() / dim as f64).max(0.0)
    }
}

fn run(params: &GkParams, data: &[f64], dim: usize, centres: Vec<f64>) -> Result<GkClustering> {
    let k = params.clusters;
    let n = data.len() / dim;
    let p = packed_len(dim);
    let nu = data_scale(data, dim);
    let mut norms = vec![0.0; k * p];
    let start = DMatrix::identity(dim, dim) * params.volume.powf(1.0 / dim as f64);
    for c in 0..k {
        pack_norm(&start, &mut norms[c * p..(c + 1) * p]);
    }
    let mut proto = Prototypes {
        centres,
        norms,
        covariances: vec![DMatrix::identity(dim, dim); k],
    };
    let mut memberships = vec![0.0; n * k];
    let mut objective = f64::NAN;
    let mut change = f64::INFINITY;
    for iteration in 1..=params.max_iterations {
        let first = iteration == 1;
        let parts = map_blocks(data, dim, &mut memberships, k, |x, u| {
            let m = params.fuzzifier;
            match dim {
                // The hypertime dimensions of one and two periods.
                4 => block_pass::<4>(x, u, &proto, dim, k, m, first),
                6 => block_pass::<6>(x, u, &proto, dim, k, m, first),
                _ => block_pass::<0>(x, u, &proto, dim, k, m, first),
            }
        });
        let mut w = vec![0.0; k];
        let mut wd = vec![0.0; k * dim];
        let mut wdd = vec![0.0; k * p];
        objective = 0.0;
        change = 0.0;
        for part in &parts {
            w.iter_mut().zip(&part.w).for_each(|(a, b)| *a += b);
            wd.iter_mut().zip(&part.wd).for_each(|(a, b)| *a += b);
            wdd.iter_mut().zip(&part.wdd).for_each(|(a, b)| *a += b);
            objective += part.objective;
            change = change.max(part.change);
        }
        for c in 0..k {
            if !(w[c] > 0.0 && w[c].is_finite()) {
                continue;
            }
            let delta =
                DVector::from_iterator(dim, wd[c * dim..(c + 1) * dim].iter().map(|v| v / w[c]));
            let f = unpack(&wdd[c * p..(c + 1) * p], dim, 1.0 / w[c]) - &delta * delta.transpose();
            let (values, vectors) = params
                .regularisation
                .apply(f, nu)
                .ok_or(AffordanceError::DegenerateCovariance { cluster: c })?;
            for (x, dx) in proto.centres[c * dim..(c + 1) * dim]
                .iter_mut()
                .zip(delta.iter())
            {
                *x += dx;
            }
            let log_det: f64 = values.iter().map(|l| l.ln()).sum();
            let scale = ((params.volume.ln() + log_det) / dim as f64).exp();
            let inverse =
                &vectors * DMatrix::from_diagonal(&values.map(|l| scale / l)) * vectors.transpose();
            pack_norm(&inverse, &mut proto.norms[c * p..(c + 1) * p]);
            proto.covariances[c] = &vectors * DMatrix::from_diagonal(&values) * vectors.transpose();
        }
        if change <= params.tolerance && !first {
            return Ok(finish(
                proto,
                memberships,
                dim,
                k,
                iteration,
                objective,
                change,
            ));
        }
    }
    let partial = finish(
        proto,
        memberships,
        dim,
        k,
        params.max_iterations,
        objective,
        change,
    );
    Err(AffordanceError::NotConverged {
        iterations: params.max_iterations,
        change,
        partial: Box::new(partial),
    })
}

fn finish(
    proto: Prototypes,
    memberships: Vec<f64>,
    dim: usize,
    clusters: usize,
    iterations: usize,
    objective: f64,
    change: f64,
) -> GkClustering {
    GkClustering {
        dim,
        clusters,
        centres: proto.centres,
        covariances: proto.covariances,
        memberships,
        iterations,
        objective,
        change,
    }
}
