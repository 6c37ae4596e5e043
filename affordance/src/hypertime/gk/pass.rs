//! The fused pass of one Gustafson–Kessel iteration over one block of points: distances to
//! every prototype, memberships, and the block's weighted sums for the next prototypes.
//!
//! Clusters are taken [`LANES`] at a time from a "structure of arrays" copy of the prototypes
//! ([`Prototypes`]), so the arithmetic is written on fixed-size arrays that the compiler turns
//! into vector instructions, with no allocation per point. Every sum over clusters is taken in
//! a fixed order, so a block's result depends only on the block.

use nalgebra::DMatrix;

/// Clusters processed together: the width of every per-cluster array of the pass.
pub(super) const LANES: usize = 4;

/// One value per cluster of a group of [`LANES`] clusters.
pub(super) type Lanes = [f64; LANES];

/// Number of entries of a packed triangular `d × d` matrix (upper triangle, row by row:
/// `(0,0), (0,1), …, (0,d−1), (1,1), …`).
pub(super) fn packed_len(d: usize) -> usize {
    d * (d + 1) / 2
}

/// The prototypes as the pass reads them: cluster `c` is lane `c % LANES` of group
/// `c / LANES`; the lanes past the last cluster hold zeros and are never reported.
pub(super) struct Prototypes {
    dim: usize,
    clusters: usize,
    /// `centres[g·dim + a]`: coordinate `a` of the centres of group `g`.
    centres: Vec<Lanes>,
    /// `factors[g·p + e]`: packed entry `e` of the upper triangular factors `Rᵢ` of the
    /// norm-inducing matrices, `Aᵢ = RᵢᵀRᵢ`, of group `g`.
    factors: Vec<Lanes>,
}

impl Prototypes {
    /// `clusters` prototypes at the origin with zero factors; set each with
    /// [`set`](Self::set).
    pub(super) fn new(dim: usize, clusters: usize) -> Self {
        let groups = clusters.div_ceil(LANES);
        Self {
            dim,
            clusters,
            centres: vec![[0.0; LANES]; groups * dim],
            factors: vec![[0.0; LANES]; groups * packed_len(dim)],
        }
    }

    /// Number of groups of [`LANES`] clusters.
    pub(super) fn groups(&self) -> usize {
        self.clusters.div_ceil(LANES)
    }

    /// Sets cluster `c`'s centre and the upper triangle of its factor `r` (`dim × dim`,
    /// `Aᵢ = rᵀr`).
    pub(super) fn set(&mut self, c: usize, centre: &[f64], r: &DMatrix<f64>) {
        let (dim, p) = (self.dim, packed_len(self.dim));
        let (g, l) = (c / LANES, c % LANES);
        for (lanes, x) in self.centres[g * dim..(g + 1) * dim].iter_mut().zip(centre) {
            lanes[l] = *x;
        }
        let factors = &mut self.factors[g * p..(g + 1) * p];
        let mut e = 0;
        for a in 0..dim {
            for b in a..dim {
                factors[e][l] = r[(a, b)];
                e += 1;
            }
        }
    }
}

/// One block's sums, per cluster (in the layout of [`Prototypes`]), with `δ = x − c_old` and
/// `w = uᵐ`: `Σw`, the largest membership change, `Σw·δ` and `Σw·δδᵀ` (packed).
pub(super) struct Partial {
    pub(super) w: Vec<Lanes>,
    pub(super) change: Vec<Lanes>,
    pub(super) wd: Vec<Lanes>,
    pub(super) wdd: Vec<Lanes>,
}

impl Partial {
    pub(super) fn zeros(groups: usize, dim: usize) -> Self {
        let zeros = |len| vec![[0.0; LANES]; len];
        Self {
            w: zeros(groups),
            change: zeros(groups),
            wd: zeros(groups * dim),
            wdd: zeros(groups * packed_len(dim)),
        }
    }

    /// Adds `other`'s sums to these (and takes the larger change), lane by lane.
    pub(super) fn add(&mut self, other: &Self) {
        let add = |a: &mut Vec<Lanes>, b: &Vec<Lanes>| {
            for (a, b) in a.iter_mut().zip(b) {
                for l in 0..LANES {
                    a[l] += b[l];
                }
            }
        };
        add(&mut self.w, &other.w);
        add(&mut self.wd, &other.wd);
        add(&mut self.wdd, &other.wdd);
        for (a, b) in self.change.iter_mut().zip(&other.change) {
            *a = max(*a, *b);
        }
    }
}

/// One pass over a block: the memberships of its rows `x` (written to `u`, `clusters` per
/// row) from the prototypes, and the block's sums. `first` marks the first iteration (no
/// previous memberships to compare with). `D` is the dimension when known at compile time
/// (the loops over coordinates then unroll), 0 otherwise.
pub(super) fn block_pass<const D: usize>(
    x: &[f64],
    u: &mut [f64],
    proto: &Prototypes,
    m: f64,
    first: bool,
) -> Partial {
    let dim = if D == 0 { proto.dim } else { D };
    let (k, p, groups) = (proto.clusters, packed_len(dim), proto.groups());
    let mut part = Partial::zeros(groups, dim);
    // Per-point scratch, one entry per group: δ = x − c, d², and the old and new memberships.
    let mut delta = vec![[0.0; LANES]; groups * dim];
    let mut d2 = vec![[0.0; LANES]; groups];
    let mut old_u = vec![[0.0; LANES]; groups];
    let mut new_u = vec![[0.0; LANES]; groups];
    for (row, u_row) in x.chunks_exact(dim).zip(u.chunks_exact_mut(k)) {
        // 1. Squared distances d² = δᵀAδ = |Rδ|².
        for g in 0..groups {
            d2[g] = distances(
                row,
                &proto.centres[g * dim..(g + 1) * dim],
                &proto.factors[g * p..(g + 1) * p],
                &mut delta[g * dim..(g + 1) * dim],
            );
        }
        // Lanes past the last cluster are infinitely far: membership 0.
        for d in &mut d2.as_flattened_mut()[k..] {
            *d = f64::INFINITY;
        }

        // 2. Memberships.
        memberships(&d2, m, &mut new_u);
        if !first {
            old_u.as_flattened_mut()[..k].copy_from_slice(u_row);
            for ((c, o), n) in part.change.iter_mut().zip(&old_u).zip(&new_u) {
                *c = max(*c, std::array::from_fn(|l| (n[l] - o[l]).abs()));
            }
        }
        u_row.copy_from_slice(&new_u.as_flattened()[..k]);

        // 3. Sums with the weights w = uᵐ.
        for g in 0..groups {
            let w = if m == 2.0 {
                new_u[g].map(|v| v * v)
            } else {
                new_u[g].map(|v| v.powf(m))
            };
            accumulate(
                w,
                &delta[g * dim..(g + 1) * dim],
                &mut part.w[g],
                &mut part.wd[g * dim..(g + 1) * dim],
                &mut part.wdd[g * p..(g + 1) * p],
            );
        }
    }
    if first {
        part.change.fill([f64::INFINITY; LANES]);
    }
    part
}

/// Lane-wise minimum (`b` where the two are unordered), without the NaN handling of `f64::min`.
#[inline(always)]
fn min(a: Lanes, b: Lanes) -> Lanes {
    std::array::from_fn(|l| if a[l] < b[l] { a[l] } else { b[l] })
}

/// Lane-wise maximum (`b` where the two are unordered), without the NaN handling of `f64::max`.
#[inline(always)]
fn max(a: Lanes, b: Lanes) -> Lanes {
    std::array::from_fn(|l| if a[l] > b[l] { a[l] } else { b[l] })
}

/// `δ = x − c` (written to `delta`) and `d² = |Rδ|²` (0 if not a number) for one group of
/// prototypes. (A function of its own, so the compiler knows that its slices do not overlap.)
#[inline(always)]
fn distances(x: &[f64], centre: &[Lanes], factor: &[Lanes], delta: &mut [Lanes]) -> Lanes {
    let dim = delta.len();
    for a in 0..dim {
        for l in 0..LANES {
            delta[a][l] = x[a] - centre[a][l];
        }
    }
    let mut q = [0.0; LANES];
    let mut e = 0;
    for a in 0..dim {
        // y = (Rδ)ₐ = Σ_{b ≥ a} R_ab δ_b
        let mut y = [0.0; LANES];
        for db in &delta[a..] {
            for l in 0..LANES {
                y[l] += factor[e][l] * db[l];
            }
            e += 1;
        }
        for l in 0..LANES {
            q[l] += y[l] * y[l];
        }
    }
    max(q, [0.0; LANES])
}

/// Adds `w` to `sw`, `w·δ` to `wd` and `w·δδᵀ` (packed) to `wdd` for one group.
#[inline(always)]
fn accumulate(w: Lanes, delta: &[Lanes], sw: &mut Lanes, wd: &mut [Lanes], wdd: &mut [Lanes]) {
    let dim = delta.len();
    for l in 0..LANES {
        sw[l] += w[l];
    }
    let mut e = 0;
    for a in 0..dim {
        let wda: Lanes = std::array::from_fn(|l| w[l] * delta[a][l]);
        for l in 0..LANES {
            wd[a][l] += wda[l];
        }
        for db in &delta[a..] {
            for l in 0..LANES {
                wdd[e][l] += wda[l] * db[l];
            }
            e += 1;
        }
    }
}

/// The memberships of one point from its squared distances to every prototype (lanes past
/// the last cluster at +∞): `uᵢ = 1 / Σₖ (d²ᵢ / d²ₖ)^{1/(m−1)}`, computed as
/// `rᵢ / Σₖ rₖ` with `rᵢ = (min d² / d²ᵢ)^{1/(m−1)}`; a point on one or more prototypes shares
/// its membership equally among them.
#[inline(always)]
fn memberships(d2: &[Lanes], m: f64, u: &mut [Lanes]) {
    let lanes = d2.iter().fold([f64::INFINITY; LANES], |a, d| min(a, *d));
    let min = lanes.iter().copied().fold(f64::INFINITY, f64::min);
    if min <= 0.0 {
        let zeros = d2.as_flattened().iter().filter(|d| **d <= 0.0).count() as f64;
        for (u, d) in u.iter_mut().zip(d2) {
            *u = d.map(|d| if d <= 0.0 { 1.0 / zeros } else { 0.0 });
        }
        return;
    }
    for (u, d) in u.iter_mut().zip(d2) {
        *u = d.map(|d| min / d);
    }
    let exponent = 1.0 / (m - 1.0);
    if exponent != 1.0 {
        for u in u.iter_mut() {
            *u = u.map(|r| r.powf(exponent));
        }
    }
    let mut sum = [0.0; LANES];
    for u in u.iter() {
        for l in 0..LANES {
            sum[l] += u[l];
        }
    }
    // total ≥ 1: the nearest prototype contributes exactly 1.
    let inverse = 1.0 / sum.iter().sum::<f64>();
    for u in u.iter_mut() {
        *u = u.map(|v| v * inverse);
    }
}
