//! Global registration of two occupancy maps without an initial guess: Harris corners,
//! rotation-invariant ring descriptors, RANSAC over pairs of matches with Umeyama, ICP
//! refinement, and a check of the result against the whole map.

use haunts_occupancy::distance_transform_with_nearest;
use haunts_occupancy::{Cell, Grid, OccupancyGrid, Pose2};
use nalgebra::Point2;
use rand::{RngExt, SeedableRng, rngs::StdRng};

use crate::difference::Length;
use crate::error::{Result, SimilarityError, rule};
use crate::icp::{IcpParams, IcpTarget, RobustLoss, icp_map_to_map};
use crate::umeyama::umeyama_rigid;

/// Parameters of global registration.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub struct GlobalParams {
    /// Smallest distance between two keypoints (default 0.5 m).
    pub keypoint_spacing: Length,
    /// Most keypoints per map, strongest first (default 400).
    pub max_keypoints: usize,
    /// Radius of the ring descriptor (default 3 m).
    pub descriptor_radius: Length,
    /// Rings of the descriptor (default 12).
    pub rings: usize,
    /// Candidate matches per source keypoint: its nearest target descriptors (default 3).
    pub candidates: usize,
    /// RANSAC hypotheses: pairs of matches whose keypoints lie as far apart in both maps
    /// (default 3000; at most 50 random pairs are drawn per hypothesis).
    pub ransac_iterations: usize,
    /// Seed of the RANSAC sampler.
    pub seed: u64,
    /// A match is consistent with a hypothesis within this distance (default 0.3 m).
    pub inlier_distance: Length,
    /// Fewest consistent matches to accept (default 6).
    pub min_inliers: usize,
    /// Fewest fraction of the source's occupied cells within two cells of the target's
    /// occupied cells after alignment, to accept (default 0.5).
    pub min_overlap: f64,
}

impl Default for GlobalParams {
    fn default() -> Self {
        Self {
            keypoint_spacing: Length::Metres(0.5),
            max_keypoints: 400,
            descriptor_radius: Length::Metres(3.0),
            rings: 12,
            candidates: 3,
            ransac_iterations: 3000,
            seed: 0x5eed,
            inlier_distance: Length::Metres(0.3),
            min_inliers: 6,
            min_overlap: 0.5,
        }
    }
}

impl GlobalParams {
    /// Sets the fewest consistent matches to accept.
    pub fn with_min_inliers(mut self, min_inliers: usize) -> Self {
        self.min_inliers = min_inliers;
        self
    }
    /// Sets the fewest overlap to accept.
    pub fn with_min_overlap(mut self, min_overlap: f64) -> Self {
        self.min_overlap = min_overlap;
        self
    }
    /// Sets the RANSAC seed.
    pub fn with_seed(mut self, seed: u64) -> Self {
        self.seed = seed;
        self
    }
    /// The parameters after checking each rule.
    ///
    /// # Errors
    /// [`SimilarityError::InvalidParameter`] naming the first parameter that is out of range.
    pub fn check(self) -> Result<Self> {
        for (name, l) in [
            ("keypoint_spacing", self.keypoint_spacing),
            ("descriptor_radius", self.descriptor_radius),
            ("inlier_distance", self.inlier_distance),
        ] {
            let v = match l {
                Length::Cells(v) | Length::Metres(v) => v,
            };
            rule(name, v, v.is_finite() && v > 0.0, "must be finite and > 0")?;
        }
        for (name, v, min) in [
            ("max_keypoints", self.max_keypoints, 2),
            ("rings", self.rings, 1),
            ("candidates", self.candidates, 1),
            ("ransac_iterations", self.ransac_iterations, 1),
            ("min_inliers", self.min_inliers, 2),
        ] {
            rule(name, v as f64, v >= min, "is too small")?;
        }
        let o = self.min_overlap;
        rule(
            "min_overlap",
            o,
            (0.0..=1.0).contains(&o),
            "must be in [0, 1]",
        )?;
        Ok(self)
    }
}

/// A transform found by global registration, with the evidence for it.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct GlobalMatch {
    /// Pose of the source map's frame in the target map's frame (after ICP refinement).
    pub pose: Pose2,
    /// Keypoint matches consistent with the transform.
    pub inliers: usize,
    /// Candidate keypoint matches considered.
    pub matches: usize,
    /// Fraction of the source's occupied cells within two cells of the target's occupied
    /// cells under `pose`: the confidence of the result (1 = the source lies entirely on the
    /// target's structure).
    pub overlap: f64,
    /// Root mean square distance, metres, from those overlapping source cells to the nearest
    /// occupied target cell under `pose` (Open3D's `inlier_rmse`, with `overlap` its
    /// `fitness`): about a third of a cell for walls on walls, more for a pose that only
    /// grazes the target's structure.
    #[cfg_attr(feature = "serde", serde(default))]
    pub residual: f64,
}

/// How well a source map lies on a target map under a pose: the evidence of a registration,
/// for a pose found or given.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Fit {
    /// Fraction of the source's occupied cells within two cells of the target's occupied
    /// cells (the inliers).
    pub overlap: f64,
    /// Root mean square distance of the inliers to the target's nearest occupied cell,
    /// metres.
    pub residual: f64,
    /// The source's occupied cells.
    pub occupied: usize,
}

/// How well `source` lies on `target` when its frame is at `pose` in the target's frame:
/// what [`register_maps`] measures of the transform it found, for a transform given (a user's
/// forced pose, a transform found elsewhere).
///
/// # Errors
/// [`SimilarityError::ResolutionMismatch`]; [`SimilarityError::EmptyMap`] (index 0 target,
/// 1 source).
///
/// # Complexity
/// O(cells of both maps): one distance transform of the target.
pub fn fit_at(target: &OccupancyGrid, source: &OccupancyGrid, pose: &Pose2) -> Result<Fit> {
    check_resolution(target, source)?;
    let (tmask, smask) = (target.occupied_mask(), source.occupied_mask());
    if !tmask.data().contains(&true) {
        return Err(SimilarityError::EmptyMap { index: 0 });
    }
    if !smask.data().contains(&true) {
        return Err(SimilarityError::EmptyMap { index: 1 });
    }
    overlap(&tmask, &smask, pose)
}

struct Keypoint {
    position: Point2<f64>,
    descriptor: Vec<f64>,
}

/// Registers `source` onto `target` without an initial guess.
///
/// Keypoints are Harris corners of the occupied mask (window 5×5, k = 0.04) kept strongest
/// first at least `keypoint_spacing` apart; each is described by the density of occupied
/// cells in `rings` concentric rings (rotation invariant, L2-normalised). Each source
/// keypoint is matched to its `candidates` nearest target descriptors; RANSAC draws pairs of
/// matches, keeps those whose two points are as far apart in both maps, solves the rigid
/// transform with Umeyama and counts matches within `inlier_distance`. The best hypothesis is
/// refitted on its inliers, refined by map-to-map ICP, and accepted only when at least
/// `min_overlap` of the source's occupied cells then lie within two cells of the target's.
///
/// # Errors
/// [`SimilarityError::NoReliableMatch`] when no hypothesis passes (e.g. maps of different
/// places) — never a wrong transform knowingly returned;
/// [`SimilarityError::EmptyMap`] (index 0 target, 1 source); [`SimilarityError::ResolutionMismatch`];
/// [`SimilarityError::InvalidParameter`].
///
/// # Complexity
/// O(cells + keypoints · (descriptor area + keypoints) + iterations · matches).
pub fn register_maps(
    target: &OccupancyGrid,
    source: &OccupancyGrid,
    params: &GlobalParams,
) -> Result<GlobalMatch> {
    let params = params.check()?;
    check_resolution(target, source)?;
    let source = SourceFeatures::new(source, &params)?;
    register_prepared(target, &source, &params)
}

/// Registers `source` onto each of `targets` (as [`register_maps`] onto each in turn), its
/// keypoints and descriptors computed once: a day registered onto every layout of a library.
/// The `k`-th result is `source` onto `targets[k]`, the same as [`register_maps`] gives.
///
/// # Errors
/// Of the whole call, before any target: [`SimilarityError::InvalidParameter`] and
/// [`SimilarityError::EmptyMap`] (index 1) for a source without structure. Per target: those
/// of [`register_maps`].
///
/// # Complexity
/// One [`register_maps`] per target, less the source's keypoints after the first.
pub fn register_maps_onto_each(
    targets: &[&OccupancyGrid],
    source: &OccupancyGrid,
    params: &GlobalParams,
) -> Result<Vec<Result<GlobalMatch>>> {
    let params = params.check()?;
    let source = SourceFeatures::new(source, &params)?;
    Ok(targets
        .iter()
        .map(|target| {
            check_resolution(target, source.map)?;
            register_prepared(target, &source, &params)
        })
        .collect())
}

/// [`SimilarityError::ResolutionMismatch`] (index 1) unless `source` has `target`'s
/// resolution.
fn check_resolution(target: &OccupancyGrid, source: &OccupancyGrid) -> Result<()> {
    let res = target.geometry().resolution();
    let sres = source.geometry().resolution();
    if (res - sres).abs() > 1e-9 * res {
        return Err(SimilarityError::ResolutionMismatch {
            index: 1,
            expected: res,
            found: sres,
        });
    }
    Ok(())
}

/// A source map with its occupied mask and keypoints: what [`register_prepared`] needs of it
/// whatever the target.
struct SourceFeatures<'a> {
    map: &'a OccupancyGrid,
    mask: Grid<bool>,
    keypoints: Vec<Keypoint>,
}

impl<'a> SourceFeatures<'a> {
    /// # Errors
    /// [`SimilarityError::EmptyMap`] (index 1) for a map without occupied cells.
    fn new(map: &'a OccupancyGrid, params: &GlobalParams) -> Result<Self> {
        let mask = map.occupied_mask();
        if !mask.data().contains(&true) {
            return Err(SimilarityError::EmptyMap { index: 1 });
        }
        let keypoints = keypoints(&mask, params);
        Ok(Self {
            map,
            mask,
            keypoints,
        })
    }
}

/// [`register_maps`] of a prepared source onto `target`, of the same resolution, `params`
/// checked.
fn register_prepared(
    target: &OccupancyGrid,
    source: &SourceFeatures<'_>,
    params: &GlobalParams,
) -> Result<GlobalMatch> {
    let res = target.geometry().resolution();
    let tmask = target.occupied_mask();
    if !tmask.data().contains(&true) {
        return Err(SimilarityError::EmptyMap { index: 0 });
    }
    let (smask, sk) = (&source.mask, &source.keypoints);
    let tk = keypoints(&tmask, params);
    let matches = candidate_matches(sk, &tk, params.candidates);
    let inlier_m = params.inlier_distance.cells(res) * res;
    let mut rng = StdRng::seed_from_u64(params.seed);
    let mut best: Vec<usize> = Vec::new();
    if matches.len() >= 2 {
        // A pair of matches is a hypothesis only when both keypoint pairs lie as far apart
        // in both maps (a rigid transform keeps lengths): most random pairs fail that cheap
        // test, so `ransac_iterations` counts hypotheses, with at most
        // `DRAWS_PER_HYPOTHESIS` draws each. With 2 % of matches right (two halves of a
        // real log, 130° apart) a pair of right matches is 1 in 2500 draws but about 1 in
        // 20 hypotheses.
        const DRAWS_PER_HYPOTHESIS: usize = 50;
        let (mut hypotheses, mut draws) = (0usize, 0usize);
        while hypotheses < params.ransac_iterations
            && draws
                < params
                    .ransac_iterations
                    .saturating_mul(DRAWS_PER_HYPOTHESIS)
        {
            draws += 1;
            let a = rng.random_range(0..matches.len());
            let b = rng.random_range(0..matches.len());
            let ((sa, ta), (sb, tb)) = (matches[a], matches[b]);
            if sa == sb || ta == tb {
                continue;
            }
            let (ps, pt) = (
                [sk[sa].position, sk[sb].position],
                [tk[ta].position, tk[tb].position],
            );
            let ds = (ps[0] - ps[1]).norm();
            if ds < 4.0 * inlier_m || (ds - (pt[0] - pt[1]).norm()).abs() > inlier_m {
                continue;
            }
            hypotheses += 1;
            let Ok(fit) = umeyama_rigid(&ps, &pt) else {
                continue;
            };
            let inliers = consistent(&matches, sk, &tk, &fit.pose, inlier_m);
            if inliers.len() > best.len() {
                best = inliers;
            }
        }
    }
    let reject =
        |inliers: usize, overlap: f64| SimilarityError::NoReliableMatch { inliers, overlap };
    if best.len() < params.min_inliers {
        return Err(reject(best.len(), 0.0));
    }
    let (src, dst): (Vec<Point2<f64>>, Vec<Point2<f64>>) = best
        .iter()
        .map(|&m| (sk[matches[m].0].position, tk[matches[m].1].position))
        .unzip();
    let coarse = umeyama_rigid(&src, &dst)?.pose;
    let inliers = consistent(&matches, sk, &tk, &coarse, inlier_m)
        .len()
        .max(best.len());
    let icp_target = IcpTarget::from_mask(&tmask)?;
    let icp_params = IcpParams::default()
        .with_loss(RobustLoss::Tukey { c: 0.3 })
        .with_max_correspondence_distance(1.0);
    let pose = match icp_map_to_map(&icp_target, source.map, &coarse, &icp_params) {
        Ok(r) => r.pose,
        Err(SimilarityError::NotConverged { partial }) => partial.pose,
        Err(_) => coarse,
    };
    let fit = overlap(&tmask, smask, &pose)?;
    if fit.overlap < params.min_overlap {
        return Err(reject(inliers, fit.overlap));
    }
    Ok(GlobalMatch {
        pose,
        inliers,
        matches: matches.len(),
        overlap: fit.overlap,
        residual: fit.residual,
    })
}

/// Indices of the matches whose source keypoint lands within `tol` of its target keypoint.
fn consistent(
    matches: &[(usize, usize)],
    sk: &[Keypoint],
    tk: &[Keypoint],
    pose: &Pose2,
    tol: f64,
) -> Vec<usize> {
    let mut used_s = std::collections::BTreeSet::new();
    matches
        .iter()
        .enumerate()
        .filter(|(_, (s, t))| (pose * sk[*s].position - tk[*t].position).norm() <= tol)
        .filter(|(_, (s, _))| used_s.insert(*s))
        .map(|(i, _)| i)
        .collect()
}

/// The fraction of the occupied cells of `smask` that `pose` puts within two cells of an
/// occupied cell of `tmask`, and their RMS distance to it: from the moved centre itself to
/// the centre of the occupied target cell nearest the cell holding it (the exact distance
/// field's nearest cell), so that sub-cell offsets count.
fn overlap(tmask: &Grid<bool>, smask: &Grid<bool>, pose: &Pose2) -> Result<Fit> {
    let field = distance_transform_with_nearest(tmask)?;
    let (tg, sg) = (tmask.geometry(), smask.geometry());
    let (mut near, mut total, mut squares) = (0usize, 0usize, 0.0f64);
    for (c, &o) in smask.cells() {
        if !o {
            continue;
        }
        total += 1;
        let p = pose * sg.cell_center(c);
        let Some(t) = tg.world_to_cell(p) else {
            continue;
        };
        let Some(d) = field.distance_cells(t) else {
            continue;
        };
        if d <= 2.0 {
            near += 1;
            let nearest = field.nearest(t).map_or(p, |n| tg.cell_center(n));
            squares += (p - nearest).norm_squared();
        }
    }
    let residual = if near > 0 {
        (squares / near as f64).sqrt()
    } else {
        0.0
    };
    Ok(Fit {
        overlap: near as f64 / total.max(1) as f64,
        residual,
        occupied: total,
    })
}

/// Each source keypoint with its `k` nearest target descriptors.
fn candidate_matches(sk: &[Keypoint], tk: &[Keypoint], k: usize) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    for (i, s) in sk.iter().enumerate() {
        let mut d: Vec<(f64, usize)> = tk
            .iter()
            .enumerate()
            .map(|(j, t)| {
                let dist: f64 = s
                    .descriptor
                    .iter()
                    .zip(&t.descriptor)
                    .map(|(a, b)| (a - b) * (a - b))
                    .sum();
                (dist, j)
            })
            .collect();
        d.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        out.extend(d.iter().take(k).map(|&(_, j)| (i, j)));
    }
    out
}

/// Harris corners of `mask`, strongest first, spaced, with ring descriptors.
fn keypoints(mask: &Grid<bool>, params: &GlobalParams) -> Vec<Keypoint> {
    let g = *mask.geometry();
    let (w, h) = (g.width(), g.height());
    let v = |c: usize, r: usize| f64::from(u8::from(mask.data()[r * w + c]));
    // Gradients (central differences, zero at the border) and their products.
    let mut prods = vec![[0.0f64; 3]; w * h];
    for r in 1..h.saturating_sub(1) {
        for c in 1..w.saturating_sub(1) {
            let ix = 0.5 * (v(c + 1, r) - v(c - 1, r));
            let iy = 0.5 * (v(c, r + 1) - v(c, r - 1));
            prods[r * w + c] = [ix * ix, iy * iy, ix * iy];
        }
    }
    // Box sums over 5×5 windows through a summed-area table.
    let mut sat = vec![[0.0f64; 3]; (w + 1) * (h + 1)];
    for r in 0..h {
        for c in 0..w {
            let i = (r + 1) * (w + 1) + c + 1;
            for k in 0..3 {
                sat[i][k] = prods[r * w + c][k] + sat[i - 1][k] + sat[i - (w + 1)][k]
                    - sat[i - (w + 1) - 1][k];
            }
        }
    }
    let rad = 2usize;
    let mut response: Vec<(f64, usize)> = Vec::new();
    for r in 0..h {
        for c in 0..w {
            let (c0, c1) = (c.saturating_sub(rad), (c + rad + 1).min(w));
            let (r0, r1) = (r.saturating_sub(rad), (r + rad + 1).min(h));
            let s = |k: usize| {
                sat[r1 * (w + 1) + c1][k] - sat[r0 * (w + 1) + c1][k] - sat[r1 * (w + 1) + c0][k]
                    + sat[r0 * (w + 1) + c0][k]
            };
            let (a, b, cc) = (s(0), s(1), s(2));
            let resp = a * b - cc * cc - 0.04 * (a + b) * (a + b);
            if resp > 0.0 {
                response.push((resp, r * w + c));
            }
        }
    }
    let max = response.iter().map(|x| x.0).fold(0.0, f64::max);
    response.retain(|x| x.0 >= 0.01 * max);
    response.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
    let res = g.resolution();
    let spacing = params.keypoint_spacing.cells(res) * res;
    let mut kept: Vec<Point2<f64>> = Vec::new();
    for (_, i) in response {
        if kept.len() >= params.max_keypoints {
            break;
        }
        let p = g.cell_center(Cell::new(i % w, i / w));
        if kept.iter().all(|q| (q - p).norm() >= spacing) {
            kept.push(p);
        }
    }
    let radius = params.descriptor_radius.cells(res);
    kept.into_iter()
        .map(|p| Keypoint {
            position: p,
            descriptor: rings(mask, p, radius, params.rings),
        })
        .collect()
}

/// Density of occupied cells in `n` rings of total radius `radius` cells around `p`,
/// L2-normalised.
fn rings(mask: &Grid<bool>, p: Point2<f64>, radius: f64, n: usize) -> Vec<f64> {
    let g = mask.geometry();
    let mut hist = vec![0.0; n];
    let (pc, pr) = g.world_to_grid(p);
    let (pc, pr) = (pc.floor() as i64, pr.floor() as i64);
    let r = radius.ceil() as i64;
    let step = radius / n as f64;
    for dr in -r..=r {
        for dc in -r..=r {
            let d = ((dc * dc + dr * dr) as f64).sqrt();
            if d >= radius {
                continue;
            }
            if let Some(c) = g.checked_cell(pc + dc, pr + dr) {
                if mask[c] {
                    hist[((d / step) as usize).min(n - 1)] += 1.0;
                }
            }
        }
    }
    for (k, v) in hist.iter_mut().enumerate() {
        let area = std::f64::consts::PI * step * step * ((k + 1).pow(2) - k.pow(2)) as f64;
        *v /= area;
    }
    let norm = hist.iter().map(|v| v * v).sum::<f64>().sqrt();
    if norm > 0.0 {
        hist.iter_mut().for_each(|v| *v /= norm);
    }
    hist
}

#[cfg(test)]
mod tests {
    use super::*;
    use haunts_occupancy::{GridGeometry, OCCUPIED};
    use nalgebra::Vector2;

    /// The test-support floor plan drawn into `geometry` with its frame at `pose`.
    fn render(pose: &Pose2, geometry: GridGeometry) -> OccupancyGrid {
        let mut m = OccupancyGrid::unknown(geometry);
        for [x, y] in haunts_test_support::plan::wall_points() {
            if let Some(c) = geometry.world_to_cell(pose * Point2::new(x, y)) {
                m.set(c, OCCUPIED);
            }
        }
        m
    }

    #[test]
    fn recovers_a_large_rotation_and_rejects_a_different_place() {
        let target = render(
            &Pose2::identity(),
            GridGeometry::new(0.05, Point2::new(-1.0, -1.0), 280, 200).unwrap(),
        );
        // The source frame sees the plan turned by 100° and moved.
        let truth = Pose2::new(Vector2::new(3.0, -2.0), 100f64.to_radians());
        let source = render(
            &truth.inverse(),
            GridGeometry::new(0.05, Point2::new(-12.0, -16.0), 400, 400).unwrap(),
        );
        let m = register_maps(&target, &source, &GlobalParams::default()).unwrap();
        let err_t = (m.pose.translation.vector - truth.translation.vector).norm();
        let err_r = m.pose.rotation.angle_to(&truth.rotation).abs();
        assert!(
            err_t < 0.1 && err_r < 1f64.to_radians(),
            "{m:?}: {err_t} m, {err_r} rad"
        );
        assert!(m.overlap > 0.9 && m.inliers >= 6, "{m:?}");

        // A different place: a plain 6 m corridor with doors.
        let g = GridGeometry::new(0.05, Point2::origin(), 200, 100).unwrap();
        let mut other = OccupancyGrid::unknown(g);
        for col in 0..200 {
            for row in [10, 60] {
                if col % 50 > 10 {
                    other.set(Cell::new(col, row), OCCUPIED);
                }
            }
        }
        assert!(matches!(
            register_maps(&target, &other, &GlobalParams::default()),
            Err(SimilarityError::NoReliableMatch { .. })
        ));
        assert!(matches!(
            register_maps(
                &target,
                &OccupancyGrid::unknown(g),
                &GlobalParams::default()
            ),
            Err(SimilarityError::EmptyMap { index: 1 })
        ));
    }

    /// Onto several targets at once is onto each in turn, result for result: the source's
    /// keypoints are only computed once. A target of another resolution or without structure
    /// fails alone; a source without structure fails the whole call.
    #[test]
    fn onto_each_target_is_each_registration_in_turn() {
        let g = GridGeometry::new(0.05, Point2::new(-1.0, -1.0), 280, 200).unwrap();
        let truth = Pose2::new(Vector2::new(3.0, -2.0), 100f64.to_radians());
        let source = render(
            &truth.inverse(),
            GridGeometry::new(0.05, Point2::new(-12.0, -16.0), 400, 400).unwrap(),
        );
        let plain = render(&Pose2::identity(), g);
        let shifted = render(&Pose2::new(Vector2::new(0.5, 0.25), 0.3), g);
        let coarse = render(
            &Pose2::identity(),
            GridGeometry::new(0.1, Point2::new(-1.0, -1.0), 140, 100).unwrap(),
        );
        let empty = OccupancyGrid::unknown(g);
        let params = GlobalParams::default();
        let targets = [&plain, &coarse, &shifted, &empty];
        let each = register_maps_onto_each(&targets, &source, &params).unwrap();
        assert_eq!(each.len(), 4);
        for (target, found) in targets.iter().zip(&each) {
            // SimilarityError has no PartialEq: results compare by their debug forms.
            let alone = register_maps(target, &source, &params);
            assert_eq!(format!("{found:?}"), format!("{alone:?}"));
        }
        assert!(each[0].is_ok() && each[2].is_ok(), "{each:?}");
        assert!(matches!(
            each[1],
            Err(SimilarityError::ResolutionMismatch { index: 1, .. })
        ));
        assert!(matches!(
            each[3],
            Err(SimilarityError::EmptyMap { index: 0 })
        ));
        assert!(matches!(
            register_maps_onto_each(&targets, &empty, &params),
            Err(SimilarityError::EmptyMap { index: 1 })
        ));
    }
}
