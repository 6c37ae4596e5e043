//! A Gustafson–Kessel clustering in progress, advanced one iteration at a time.

use nalgebra::{DMatrix, DVector};

use super::pass::{LANES, Partial, Prototypes, block_pass, packed_len};
use super::{BLOCK, GkClustering, GkParams, map_blocks};
use crate::{AffordanceError, Result};

/// A Gustafson–Kessel clustering in progress (see [`GkParams::fit`] for one iteration's
/// steps), made by [`GkParams::start_from`]. [`step`](Self::step) runs one iteration, without
/// any convergence test; [`GkParams::fit`] is this loop with the test.
///
/// ```
/// use haunts_affordance::hypertime::GkParams;
/// let data = [0.0, 0.0, 0.1, 0.0, 0.0, 0.1, 5.0, 5.0, 5.1, 5.0, 5.0, 5.1];
/// let mut run = GkParams::default().with_clusters(2).start_from(&data, 2, &[0.0, 0.0, 5.0, 5.0])?;
/// for _ in 0..5 {
///     run.step()?;
/// }
/// let gk = run.into_clustering();
/// assert_eq!(gk.iterations(), 5);
/// approx::assert_abs_diff_eq!(gk.centre(1).unwrap()[0], 5.0 + 1.0 / 30.0, epsilon = 1e-3);
/// # Ok::<(), haunts_affordance::AffordanceError>(())
/// ```
pub struct GkRun<'a> {
    params: GkParams,
    data: &'a [f64],
    dim: usize,
    /// `det(F₀)^{1/d}`, the scale of the identity blending.
    nu: f64,
    /// Prototypes, flat (`clusters × dim`).
    pub(super) centres: Vec<f64>,
    /// Regularised fuzzy covariances `Fᵢ`.
    pub(super) covariances: Vec<DMatrix<f64>>,
    /// The norm-inducing matrices `Aᵢ`, packed (`clusters × p`), off-diagonal entries
    /// doubled so that `Σₑ normₑ·Sₑ = tr(AᵢS)` for a packed symmetric `S`.
    norms: Vec<f64>,
    /// The centres and factors of the `Aᵢ` in the layout of the pass.
    prototypes: Prototypes,
    pub(super) memberships: Vec<f64>,
    iterations: usize,
    objective: f64,
    change: f64,
}

impl std::fmt::Debug for GkRun<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("GkRun")
            .field("dim", &self.dim)
            .field("clusters", &self.params.clusters)
            .field("points", &(self.data.len() / self.dim))
            .field("iterations", &self.iterations)
            .field("objective", &self.objective)
            .field("change", &self.change)
            .finish_non_exhaustive()
    }
}

impl<'a> GkRun<'a> {
    /// The run before its first iteration: `centres` with identity covariances. `params`,
    /// `data` and `centres` have been checked.
    pub(super) fn new(params: GkParams, data: &'a [f64], dim: usize, centres: Vec<f64>) -> Self {
        let (k, n, p) = (params.clusters, data.len() / dim, packed_len(dim));
        // Aᵢ = ρ^{1/d} I, with the factor Rᵢ = ρ^{1/(2d)} I.
        let start = DMatrix::identity(dim, dim) * params.volume.powf(1.0 / dim as f64);
        let root = DMatrix::identity(dim, dim) * params.volume.powf(0.5 / dim as f64);
        let mut prototypes = Prototypes::new(dim, k);
        let mut norms = vec![0.0; k * p];
        for (c, centre) in centres.chunks_exact(dim).enumerate() {
            prototypes.set(c, centre, &root);
            pack_doubled(&start, &mut norms[c * p..(c + 1) * p]);
        }
        Self {
            params,
            data,
            dim,
            nu: data_scale(data, dim),
            centres,
            covariances: vec![DMatrix::identity(dim, dim); k],
            norms,
            prototypes,
            memberships: vec![0.0; n * k],
            iterations: 0,
            objective: f64::NAN,
            change: f64::INFINITY,
        }
    }

    /// Runs one iteration: memberships from the current prototypes, then new prototypes and
    /// regularised covariances. Returns the largest change of a membership (∞ on the first
    /// iteration).
    ///
    /// # Errors
    /// [`AffordanceError::DegenerateCovariance`] naming a cluster whose covariance overflowed;
    /// the run is then left mid-iteration and should be dropped.
    ///
    /// # Complexity
    /// `O(n·c·d²)` time, parallel over blocks of 512 rows with the `rayon` feature; no
    /// allocation per point.
    pub fn step(&mut self) -> Result<f64> {
        let (dim, k, m) = (self.dim, self.params.clusters, self.params.fuzzifier);
        let first = self.iterations == 0;
        let proto = &self.prototypes;
        let parts = map_blocks(self.data, dim, &mut self.memberships, k, |x, u| match dim {
            // The hypertime dimensions of no period (the static baseline and the fits
            // without a candidate period), one and two periods.
            2 => block_pass::<2>(x, u, proto, m, first),
            4 => block_pass::<4>(x, u, proto, m, first),
            6 => block_pass::<6>(x, u, proto, m, first),
            _ => block_pass::<0>(x, u, proto, m, first),
        });
        // Block sums in block order: the same result with any number of threads.
        let mut sums = Partial::zeros(proto.groups(), dim);
        for part in &parts {
            sums.add(part);
        }
        self.iterations += 1;
        self.objective = self.objective_of(&sums);
        self.change = sums.change.as_flattened()[..k]
            .iter()
            .copied()
            .fold(0.0, f64::max);
        self.update(&sums)?;
        Ok(self.change)
    }

    /// `J = Σᵢⱼ uᵢⱼᵐ d²ᵢⱼ = Σᵢ tr(Aᵢ Σⱼ uᵢⱼᵐ δδᵀ)`, from an iteration's sums and the prototypes
    /// they were taken with.
    fn objective_of(&self, sums: &Partial) -> f64 {
        let p = packed_len(self.dim);
        (0..self.params.clusters)
            .map(|c| {
                let (g, l) = (c / LANES, c % LANES);
                let norm = &self.norms[c * p..(c + 1) * p];
                let wdd = &sums.wdd[g * p..(g + 1) * p];
                norm.iter().zip(wdd).map(|(a, s)| a * s[l]).sum::<f64>()
            })
            .sum()
    }

    /// New prototypes and regularised covariances from an iteration's sums; a cluster whose
    /// total weight underflowed to 0 keeps its prototype and covariance.
    fn update(&mut self, sums: &Partial) -> Result<()> {
        let (dim, p) = (self.dim, packed_len(self.dim));
        for c in 0..self.params.clusters {
            let (g, l) = (c / LANES, c % LANES);
            let w = sums.w[g][l];
            if !(w > 0.0 && w.is_finite()) {
                continue;
            }
            // Sums about the old centre: shift to the new one.
            let delta = DVector::from_iterator(dim, (0..dim).map(|a| sums.wd[g * dim + a][l] / w));
            let mut f = DMatrix::zeros(dim, dim);
            let mut e = 0;
            for r in 0..dim {
                for s in r..dim {
                    f[(r, s)] = sums.wdd[g * p + e][l] / w;
                    f[(s, r)] = f[(r, s)];
                    e += 1;
                }
            }
            let f = f - &delta * delta.transpose();
            let (values, vectors) = self
                .params
                .regularisation
                .apply(f, self.nu)
                .ok_or(AffordanceError::DegenerateCovariance { cluster: c })?;
            let centre = &mut self.centres[c * dim..(c + 1) * dim];
            for (x, dx) in centre.iter_mut().zip(delta.iter()) {
                *x += dx;
            }
            // Aᵢ = (ρ det Fᵢ)^{1/d} Fᵢ⁻¹ = s Φ Λ⁻¹ Φᵀ from the eigen-decomposition Fᵢ = ΦΛΦᵀ;
            // the pass uses Aᵢ = BᵀB with B = (sΛ⁻¹)^{1/2} Φᵀ = QR, i.e. Aᵢ = RᵀR.
            let log_det: f64 = values.iter().map(|l| l.ln()).sum();
            let scale = ((self.params.volume.ln() + log_det) / dim as f64).exp();
            let norm =
                &vectors * DMatrix::from_diagonal(&values.map(|l| scale / l)) * vectors.transpose();
            pack_doubled(&norm, &mut self.norms[c * p..(c + 1) * p]);
            let root =
                DMatrix::from_diagonal(&values.map(|l| (scale / l).sqrt())) * vectors.transpose();
            self.prototypes.set(c, centre, &root.qr().r());
            self.covariances[c] = &vectors * DMatrix::from_diagonal(&values) * vectors.transpose();
        }
        Ok(())
    }

    /// The parameters, checked.
    pub fn params(&self) -> GkParams {
        self.params
    }

    /// Iterations run so far.
    pub fn iterations(&self) -> usize {
        self.iterations
    }

    /// The objective `J = Σᵢⱼ uᵢⱼᵐ d²ᵢⱼ` of the last iteration (NaN before the first).
    pub fn objective(&self) -> f64 {
        self.objective
    }

    /// The largest change of a membership in the last iteration (∞ before the second).
    pub fn change(&self) -> f64 {
        self.change
    }

    /// The clustering after the iterations run so far.
    pub fn into_clustering(self) -> GkClustering {
        GkClustering {
            dim: self.dim,
            clusters: self.params.clusters,
            centres: self.centres,
            covariances: self.covariances,
            memberships: self.memberships,
            iterations: self.iterations,
            objective: self.objective,
            change: self.change,
        }
    }
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
    let mut cov = DMatrix::zeros(dim, dim);
    let mut i = 0;
    for r in 0..dim {
        for c in r..dim {
            cov[(r, c)] = ss[i] / n;
            cov[(c, r)] = ss[i] / n;
            i += 1;
        }
    }
    let cov = cov - &mean * mean.transpose();
    let eig = cov.symmetric_eigen();
    if eig.eigenvalues.iter().all(|l| *l > 0.0) {
        (eig.eigenvalues.iter().map(|l| l.ln()).sum::<f64>() / dim as f64).exp()
    } else {
        (eig.eigenvalues.sum() / dim as f64).max(0.0)
    }
}

/// Packs a symmetric matrix's upper triangle, off-diagonal entries doubled.
fn pack_doubled(a: &DMatrix<f64>, out: &mut [f64]) {
    let d = a.nrows();
    let mut e = 0;
    for r in 0..d {
        for c in r..d {
            out[e] = if r == c {
                a[(r, c)]
            } else {
                a[(r, c)] + a[(c, r)]
            };
            e += 1;
        }
    }
}
