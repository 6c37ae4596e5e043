//! Prediction on a regular 2-D grid: the TA map's hot path.
//!
//! A fitted model's posterior is `mean(x) = m + f(x)ᵀ w` and
//! `var(x) = k(x, x) − f(x)ᵀ M f(x)` with `f(x) = k(B, x)` over a basis `B` (the training
//! points of an exact GP, the inducing points of a sparse one). Two modes:
//!
//! - [`GridMode::Exact`]: every grid point goes through the model's own prediction (blocked,
//!   parallel); for an exact GP this is the O(n²·m) triangular solve.
//! - [`GridMode::Fast`]: `f` is interpolated along each axis by barycentric Chebyshev
//!   interpolation on `p` nodes per axis (the tensor grid Z of p² nodes). Then
//!   `f(x) ≈ F w(x)` with `F = k(B, Z)` and `w(x) = u(x₀) ⊗ v(x₁)`, so
//!   `mean(x) ≈ m + w(x)ᵀ (Fᵀw)` and `var(x) ≈ k(x, x) − w(x)ᵀ S w(x)` with the p² × p²
//!   matrix `S = Fᵀ M F` computed once (for an exact GP, `S = VᵀV` with `V = L⁻¹F`: n²p² flops
//!   instead of n²·m). The tensor structure makes every grid point cost O(p²).
//!
//! **Error.** For a kernel analytic in x (RBF, periodic) the Chebyshev interpolation error
//! of `k(·, b)` on an interval decays geometrically in p; `p` is chosen per axis as the
//! smallest of a ladder (8 … 64) whose interpolation of `k(·, b)` along that axis, for a
//! sample of basis points `b`, stays under `tolerance × k(x, x)` on a dense check set (the
//! *truncation bound* used here). The resulting mean error is ≤ ε‖w‖₁ and the variance error
//! ≤ 2ε‖M f‖₁ + O(ε²) with ε that bound; rather than trusting that product, the fast result
//! also **measures** its largest error against the exact prediction at a sample of grid
//! points (reported in [`GridPrediction::checked`]). An axis with no more grid lines than
//! nodes uses the grid lines themselves as nodes, which is exact along that axis. Matérn
//! kernels are not analytic at r = 0: their interpolation converges only algebraically and
//! the ladder may end above the tolerance (then `p` = 64 and the check tells the error).

use faer::Mat;

use crate::error::{GpError, Result};
use crate::kernel::Kernel;
use crate::linalg::{col, fill_cross, map_range};

/// A regular 2-D grid of points `(x0 + i·dx, y0 + j·dy)`, `i < nx`, `j < ny`, listed with `i`
/// fastest (the order of `haunts_occupancy::GridGeometry` cell centres).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Grid2 {
    /// The first point (e.g. the centre of cell (0, 0)).
    pub origin: [f64; 2],
    /// Spacing along x and y (> 0).
    pub step: [f64; 2],
    /// Number of points along x and y (≥ 1 each).
    pub shape: [usize; 2],
}

impl Grid2 {
    /// The most points a grid may have: 2²⁸, the default cell budget of
    /// `haunts_occupancy::budget` (a grid laid over a geometry within that budget always
    /// fits). The mean and variance alone take 4 GiB at this size.
    pub const MAX_POINTS: usize = 1 << 28;

    /// Checks the grid.
    ///
    /// # Errors
    /// [`GpError::InvalidParameter`] for a non-finite origin, a non-positive or non-finite
    /// step, an empty shape, or more than [`Grid2::MAX_POINTS`] points (checked before
    /// anything is allocated).
    ///
    /// ```
    /// use haunts_gp::Grid2;
    /// let grid = Grid2 { origin: [0.0, 0.0], step: [1e-9, 1e-9], shape: [1 << 20, 1 << 20] };
    /// assert!(grid.check().is_err());
    /// ```
    pub fn check(&self) -> Result<()> {
        for d in 0..2 {
            if !self.origin[d].is_finite() {
                return Err(GpError::invalid("grid.origin", self.origin[d], "finite"));
            }
            if !(self.step[d].is_finite() && self.step[d] > 0.0) {
                return Err(GpError::invalid(
                    "grid.step",
                    self.step[d],
                    "finite and > 0",
                ));
            }
            if self.shape[d] == 0 {
                return Err(GpError::invalid("grid.shape", 0.0, ">= 1 per axis"));
            }
        }
        let points = self.shape[0] as f64 * self.shape[1] as f64;
        if points > Self::MAX_POINTS as f64 {
            return Err(GpError::invalid(
                "grid.shape",
                points,
                "at most Grid2::MAX_POINTS = 2^28 points",
            ));
        }
        Ok(())
    }

    /// The coordinates of axis `d`'s grid lines.
    pub fn axis(&self, d: usize) -> Vec<f64> {
        (0..self.shape[d])
            .map(|i| self.origin[d] + i as f64 * self.step[d])
            .collect()
    }

    /// Every point, flat (`[x, y, x, y, …]`), `i` fastest.
    pub fn points(&self) -> Vec<f64> {
        let (xs, ys) = (self.axis(0), self.axis(1));
        let mut out = Vec::with_capacity(2 * xs.len() * ys.len());
        for y in &ys {
            for x in &xs {
                out.push(*x);
                out.push(*y);
            }
        }
        out
    }

    /// The number of points.
    pub fn len(&self) -> usize {
        self.shape[0] * self.shape[1]
    }

    /// Whether the grid has no point (never, once checked).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// How [`crate::ExactGp::predict_grid`] predicts.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum GridMode {
    /// Every point through the exact prediction.
    Exact,
    /// Chebyshev interpolation of the kernel (see the module documentation).
    Fast {
        /// Largest interpolation error of the kernel, relative to the prior variance, that
        /// the choice of nodes aims at (e.g. 1e-10).
        tolerance: f64,
        /// Grid points (spread over the grid) at which the result is compared with the
        /// exact prediction; 0 skips the check.
        check_points: usize,
    },
}

impl GridMode {
    /// The fast mode with tolerance 1e-10 and 64 checked points.
    pub fn fast() -> Self {
        GridMode::Fast {
            tolerance: 1e-10,
            check_points: 64,
        }
    }
}

/// The measured error of a fast prediction at a sample of grid points.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct GridCheck {
    /// Points compared.
    pub points: usize,
    /// Largest |mean − exact mean|.
    pub max_mean_error: f64,
    /// Largest |variance − exact variance| divided by the prior variance k(x, x).
    pub max_relative_variance_error: f64,
}

/// Mean and variance on a [`Grid2`], in its point order.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct GridPrediction {
    /// Posterior mean per grid point.
    pub mean: Vec<f64>,
    /// Posterior latent variance per grid point (≥ 0).
    pub variance: Vec<f64>,
    /// Chebyshev nodes per axis (`None` for the exact mode).
    pub nodes: Option<[usize; 2]>,
    /// The measured error of the fast mode (`None` for the exact mode or no check).
    pub checked: Option<GridCheck>,
}

/// What the fast grid prediction needs of a fitted model.
pub(crate) trait Posterior {
    fn kernel(&self) -> &dyn Kernel;
    /// The dimension of the model's points.
    fn dim(&self) -> usize;
    /// The basis B (flat, 2-D).
    fn basis(&self) -> &[f64];
    /// The mean weights over B.
    fn weights(&self) -> &[f64];
    /// The prior mean value.
    fn offset(&self) -> f64;
    /// `S = Fᵀ M F` for `F = k(B, Z)` (basis × nodes).
    fn reduction(&self, f: Mat<f64>) -> Mat<f64>;
    /// The exact prediction at flat points.
    fn exact(&self, xs: &[f64]) -> Result<(Vec<f64>, Vec<f64>)>;
}

/// The node-count ladder of the fast mode.
const LADDER: [usize; 9] = [8, 12, 16, 24, 32, 40, 48, 56, 64];

/// Chebyshev points of the first kind on [a, b] and their barycentric weights.
fn chebyshev(a: f64, b: f64, p: usize) -> (Vec<f64>, Vec<f64>) {
    let (mid, half) = (0.5 * (a + b), 0.5 * (b - a));
    (0..p)
        .map(|k| {
            let t = (2 * k + 1) as f64 * std::f64::consts::PI / (2 * p) as f64;
            let sign = if k % 2 == 0 { 1.0 } else { -1.0 };
            (mid + half * t.cos(), sign * t.sin())
        })
        .unzip()
}

/// The barycentric interpolation weights of the point `t` on `nodes` (a unit vector when `t`
/// is a node).
fn interpolation_row(t: f64, nodes: &[f64], bary: &[f64]) -> Vec<f64> {
    if let Some(k) = nodes.iter().position(|&z| z == t) {
        let mut row = vec![0.0; nodes.len()];
        row[k] = 1.0;
        return row;
    }
    let q: Vec<f64> = nodes.iter().zip(bary).map(|(z, w)| w / (t - z)).collect();
    let s: f64 = q.iter().sum();
    q.into_iter().map(|v| v / s).collect()
}

/// The nodes of axis `d`: the grid lines themselves when there are few, else the smallest
/// Chebyshev ladder entry meeting the tolerance (or the largest).
fn axis_nodes(
    post: &dyn Posterior,
    grid: &Grid2,
    d: usize,
    tolerance: f64,
) -> (Vec<f64>, Vec<f64>) {
    let lines = grid.axis(d);
    let (a, b) = (lines[0], lines[lines.len() - 1]);
    if lines.len() <= LADDER[0] || a == b {
        return (lines.clone(), Vec::new());
    }
    let kernel = post.kernel();
    let basis = post.basis();
    let nb = basis.len() / 2;
    // A sample of basis points and the other coordinate at a grid line near the middle.
    let sample: Vec<&[f64]> = (0..16.min(nb))
        .map(|i| &basis[(i * nb / 16.min(nb)) * 2..][..2])
        .collect();
    let other = grid.axis(1 - d)[grid.shape[1 - d] / 2];
    let checks: Vec<f64> = (0..=400).map(|i| a + (b - a) * i as f64 / 400.0).collect();
    let point = |t: f64| if d == 0 { [t, other] } else { [other, t] };
    for &p in &LADDER {
        if p >= lines.len() {
            return (lines.clone(), Vec::new());
        }
        let (nodes, bary) = chebyshev(a, b, p);
        let mut worst = 0.0f64;
        for s in &sample {
            let at_nodes: Vec<f64> = nodes.iter().map(|&z| kernel.value(&point(z), s)).collect();
            for &t in &checks {
                let x = point(t);
                let row = interpolation_row(t, &nodes, &bary);
                let approx: f64 = row.iter().zip(&at_nodes).map(|(r, v)| r * v).sum();
                let prior = kernel.value(&x, &x).abs().max(f64::MIN_POSITIVE);
                worst = worst.max((approx - kernel.value(&x, s)).abs() / prior);
            }
        }
        if worst <= tolerance || p == LADDER[LADDER.len() - 1] {
            return (nodes, bary);
        }
    }
    (lines, Vec::new())
}

/// Barycentric interpolation from `p` Chebyshev nodes (first kind) spanning `lines` to each
/// line: the nodes and one row of weights per line (`Σ row[k]·f(nodes[k]) ≈ f(line)`). With
/// no more lines than `p`, or a single position, the lines themselves are the nodes and the
/// rows are the identity. What [`GridMode::Fast`] does along each axis, for callers that
/// interpolate something else than the posterior (a mean-only raster, say).
pub fn chebyshev_interpolation(lines: &[f64], p: usize) -> (Vec<f64>, Vec<Vec<f64>>) {
    let (a, b) = (
        lines.first().copied().unwrap_or(0.0),
        lines.last().copied().unwrap_or(0.0),
    );
    if lines.len() <= p || a == b {
        let nodes = lines.to_vec();
        let rows = axis_matrix(lines, &nodes, &[]);
        return (nodes, rows);
    }
    let (nodes, bary) = chebyshev(a, b, p);
    let rows = axis_matrix(lines, &nodes, &bary);
    (nodes, rows)
}

/// The interpolation matrix (grid lines × nodes) of one axis.
fn axis_matrix(lines: &[f64], nodes: &[f64], bary: &[f64]) -> Vec<Vec<f64>> {
    if bary.is_empty() {
        // Nodes are the grid lines: identity.
        return (0..lines.len())
            .map(|i| {
                (0..nodes.len())
                    .map(|k| if k == i { 1.0 } else { 0.0 })
                    .collect()
            })
            .collect();
    }
    lines
        .iter()
        .map(|&t| interpolation_row(t, nodes, bary))
        .collect()
}

pub(crate) fn predict_grid(
    post: &dyn Posterior,
    grid: &Grid2,
    mode: GridMode,
) -> Result<GridPrediction> {
    grid.check()?;
    if post.dim() != 2 {
        return Err(GpError::DimensionMismatch {
            expected: post.dim(),
            found: 2,
        });
    }
    let (tolerance, check_points) = match mode {
        GridMode::Exact => {
            let (mean, variance) = post.exact(&grid.points())?;
            return Ok(GridPrediction {
                mean,
                variance,
                nodes: None,
                checked: None,
            });
        }
        GridMode::Fast {
            tolerance,
            check_points,
        } => {
            if !(tolerance.is_finite() && tolerance > 0.0) {
                return Err(GpError::invalid("tolerance", tolerance, "finite and > 0"));
            }
            (tolerance, check_points)
        }
    };
    let kernel = post.kernel();
    let (nx, ny) = (grid.shape[0], grid.shape[1]);
    let (n0, b0) = axis_nodes(post, grid, 0, tolerance);
    let (n1, b1) = axis_nodes(post, grid, 1, tolerance);
    let (p0, p1) = (n0.len(), n1.len());
    // Z in (a, b) order with a (axis 0) fastest: index a + p0·b.
    let mut z = Vec::with_capacity(2 * p0 * p1);
    for y in &n1 {
        for x in &n0 {
            z.push(*x);
            z.push(*y);
        }
    }
    let basis = post.basis();
    let mut f = Mat::<f64>::zeros(basis.len() / 2, p0 * p1);
    fill_cross(kernel, basis, &z, 2, f.as_mut());
    let mu: Vec<f64> = (0..p0 * p1)
        .map(|j| {
            col(f.as_ref(), j)
                .iter()
                .zip(post.weights())
                .map(|(a, b)| a * b)
                .sum()
        })
        .collect();
    let s = post.reduction(f);
    let u = axis_matrix(&grid.axis(0), &n0, &b0);
    let v = axis_matrix(&grid.axis(1), &n1, &b1);
    let offset = post.offset();
    // Per grid column i: T_i[b, b'] = Σ_{a,a'} u_i[a] u_i[a'] S[(a,b),(a',b')], then each
    // point (i, j) is v_jᵀ T_i v_j; the mean is u_iᵀ Mu v_j with Mu[a, b] = mu[a + p0 b].
    let columns = map_range(nx, |i| {
        let ui = &u[i];
        // h[(b), (a', b')] = Σ_a u_i[a] S[(a, b), (a', b')]
        let r = p0 * p1;
        let mut t = vec![0.0; p1 * p1];
        let mut h = vec![0.0; r];
        for b in 0..p1 {
            h.iter_mut().for_each(|x| *x = 0.0);
            for (a, &ua) in ui.iter().enumerate() {
                if ua == 0.0 {
                    continue;
                }
                let scol = col(s.as_ref(), a + p0 * b);
                for (hv, sv) in h.iter_mut().zip(scol) {
                    *hv += ua * sv;
                }
            }
            for b2 in 0..p1 {
                t[b * p1 + b2] = ui
                    .iter()
                    .enumerate()
                    .map(|(a2, &ua2)| ua2 * h[a2 + p0 * b2])
                    .sum();
            }
        }
        let mean_i: Vec<f64> = (0..p1)
            .map(|b| {
                ui.iter()
                    .enumerate()
                    .map(|(a, &ua)| ua * mu[a + p0 * b])
                    .sum()
            })
            .collect();
        let mut out = Vec::with_capacity(ny);
        for (j, vj) in v.iter().enumerate() {
            let x = [
                grid.origin[0] + i as f64 * grid.step[0],
                grid.origin[1] + j as f64 * grid.step[1],
            ];
            let mean = offset + vj.iter().zip(&mean_i).map(|(a, b)| a * b).sum::<f64>();
            let mut red = 0.0;
            for (b, &vb) in vj.iter().enumerate() {
                if vb != 0.0 {
                    red += vb
                        * vj.iter()
                            .zip(&t[b * p1..(b + 1) * p1])
                            .map(|(a, c)| a * c)
                            .sum::<f64>();
                }
            }
            out.push((mean, (kernel.value(&x, &x) - red).max(0.0)));
        }
        out
    });
    let mut mean = vec![0.0; nx * ny];
    let mut variance = vec![0.0; nx * ny];
    for (i, c) in columns.into_iter().enumerate() {
        for (j, (m, v)) in c.into_iter().enumerate() {
            mean[j * nx + i] = m;
            variance[j * nx + i] = v;
        }
    }
    let checked = (check_points > 0).then(|| -> Result<GridCheck> {
        let total = nx * ny;
        let k = check_points.min(total);
        // Spread over the grid with a stride coprime-ish to the row length.
        let idx: Vec<usize> = (0..k)
            .map(|s| (s * total / k + (s * 7919) % (total / k).max(1)) % total)
            .collect();
        let pts: Vec<f64> = idx
            .iter()
            .flat_map(|&q| {
                [
                    grid.origin[0] + (q % nx) as f64 * grid.step[0],
                    grid.origin[1] + (q / nx) as f64 * grid.step[1],
                ]
            })
            .collect();
        let (em, ev) = post.exact(&pts)?;
        let mut check = GridCheck {
            points: k,
            max_mean_error: 0.0,
            max_relative_variance_error: 0.0,
        };
        for (c, &q) in idx.iter().enumerate() {
            let x = &pts[2 * c..2 * c + 2];
            let prior = kernel.value(x, x).abs().max(f64::MIN_POSITIVE);
            check.max_mean_error = check.max_mean_error.max((mean[q] - em[c]).abs());
            check.max_relative_variance_error = check
                .max_relative_variance_error
                .max((variance[q] - ev[c]).abs() / prior);
        }
        Ok(check)
    });
    let checked = checked.transpose()?;
    Ok(GridPrediction {
        mean,
        variance,
        nodes: Some([p0, p1]),
        checked,
    })
}

#[cfg(test)]
mod tests {
    use super::chebyshev_interpolation;

    #[test]
    fn chebyshev_interpolation_is_exact_on_low_degree_polynomials() {
        let lines: Vec<f64> = (0..50).map(|i| -1.0 + 0.1 * i as f64).collect();
        let f = |t: f64| 3.0 - 2.0 * t + 0.5 * t.powi(3) - 0.1 * t.powi(5);
        let (nodes, rows) = chebyshev_interpolation(&lines, 8);
        assert_eq!((nodes.len(), rows.len()), (8, 50));
        let at_nodes: Vec<f64> = nodes.iter().map(|&z| f(z)).collect();
        for (t, row) in lines.iter().zip(&rows) {
            let v: f64 = row.iter().zip(&at_nodes).map(|(r, y)| r * y).sum();
            assert!((v - f(*t)).abs() < 1e-11, "{t}: {v} vs {}", f(*t));
        }
        // Few lines: the lines are the nodes, the rows the identity.
        let (nodes, rows) = chebyshev_interpolation(&lines[..5], 8);
        assert_eq!(nodes, lines[..5]);
        assert!(
            rows.iter()
                .enumerate()
                .all(|(i, r)| r[i] == 1.0 && r.iter().sum::<f64>() == 1.0)
        );
    }
}
