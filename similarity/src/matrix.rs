//! The similarity matrix of many maps: every directed distance-field difference, each
//! distance field computed once.

use haunts_occupancy::OccupancyGrid;

use crate::difference::{
    DifferenceParams, PreparedMap, Symmetrisation, check_same, min_squared_above, sum_above,
};
use crate::error::{Result, SimilarityError};

/// The full, asymmetric matrix of directed differences: entry `(x, y)` is `cmapXmapY`, the
/// occupied cells of map `y` measured in the distance field of map `x` (cells², see
/// [`crate::directed_difference`]). The diagonal is zero.
///
/// With the `serde` feature it (de)serialises as `values`, `occupied` and `resolution`, and
/// deserialising checks them as [`SimilarityMatrix::from_values`] does.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(try_from = "SimilarityMatrixFields"))]
pub struct SimilarityMatrix {
    /// Number of maps: `occupied.len()`, not serialised.
    #[cfg_attr(feature = "serde", serde(skip_serializing))]
    n: usize,
    values: Vec<f64>,
    occupied: Vec<usize>,
    resolution: f64,
}

impl SimilarityMatrix {
    /// A matrix from row-major values (`values[x·n + y]` = difference from `x` to `y`), the
    /// occupied-cell count of every map, and the cell side in metres: for matrices computed
    /// elsewhere, or fixtures.
    ///
    /// # Errors
    /// [`SimilarityError::LengthMismatch`] unless `values` has `n²` elements for
    /// `n = occupied.len()`; [`SimilarityError::InvalidParameter`] for a negative or NaN value
    /// or a resolution that is not finite and positive.
    pub fn from_values(values: Vec<f64>, occupied: Vec<usize>, resolution: f64) -> Result<Self> {
        let n = occupied.len();
        if n.checked_mul(n) != Some(values.len()) {
            return Err(SimilarityError::LengthMismatch {
                what: "matrix values vs maps²",
                left: values.len(),
                right: n.saturating_mul(n),
            });
        }
        if let Some(v) = values.iter().find(|v| v.is_nan() || **v < 0.0) {
            return Err(SimilarityError::InvalidParameter(
                haunts_core::InvalidParameter {
                    name: "values",
                    value: *v,
                    rule: "must be >= 0",
                },
            ));
        }
        crate::error::rule(
            "resolution",
            resolution,
            resolution.is_finite() && resolution > 0.0,
            "must be finite and > 0",
        )?;
        Ok(Self {
            n,
            values,
            occupied,
            resolution,
        })
    }

    /// Number of maps.
    pub fn len(&self) -> usize {
        self.n
    }
    /// Whether there are no maps.
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }
    /// The difference from map `x` to map `y` (`cmapXmapY`), or `None` out of range.
    pub fn get(&self, x: usize, y: usize) -> Option<f64> {
        (x < self.n && y < self.n).then(|| self.values[x * self.n + y])
    }
    /// Row-major values.
    pub fn values(&self) -> &[f64] {
        &self.values
    }
    /// Occupied-cell count of each map.
    pub fn occupied_counts(&self) -> &[usize] {
        &self.occupied
    }
    /// Side of a cell of the compared maps, metres.
    pub fn resolution(&self) -> f64 {
        self.resolution
    }
    /// The symmetric combination of both directions, row-major.
    pub fn symmetrised(&self, how: Symmetrisation) -> Vec<f64> {
        let n = self.n;
        let mut out = vec![0.0; n * n];
        for x in 0..n {
            for y in 0..n {
                out[x * n + y] = how.combine(self.values[x * n + y], self.values[y * n + x]);
            }
        }
        out
    }
}

/// The fields of a [`SimilarityMatrix`] as deserialised, before
/// [`SimilarityMatrix::from_values`] checks them.
#[cfg(feature = "serde")]
#[derive(serde::Deserialize)]
struct SimilarityMatrixFields {
    values: Vec<f64>,
    occupied: Vec<usize>,
    resolution: f64,
}

#[cfg(feature = "serde")]
impl TryFrom<SimilarityMatrixFields> for SimilarityMatrix {
    type Error = SimilarityError;
    fn try_from(f: SimilarityMatrixFields) -> Result<Self> {
        Self::from_values(f.values, f.occupied, f.resolution)
    }
}

/// The similarity matrix of `maps`, all on one geometry.
///
/// Each map is thresholded and distance-transformed once (in parallel with the `rayon`
/// feature), then every ordered pair is summed (rows in parallel). Each entry is summed in a
/// fixed order by one task, so the result does not depend on the number of threads.
///
/// # Errors
/// [`SimilarityError::GeometryMismatch`] naming the first map whose geometry differs from map
/// 0's; [`SimilarityError::EmptyMap`] naming the first map with no occupied cell;
/// [`SimilarityError::InvalidParameter`] for a bad cutoff;
/// [`OccupancyError::WorkTooLarge`](haunts_occupancy::OccupancyError::WorkTooLarge) (in
/// [`SimilarityError::Occupancy`]) when n × the occupied cells of all maps exceeds the work
/// budget ([`haunts_occupancy::budget`]), checked before any pair is summed.
///
/// # Complexity
/// O(n · cells + n² · occupied cells per map) time, O(n · cells) memory.
///
/// # Example
/// ```
/// use haunts_occupancy::{GridGeometry, OccupancyGrid, OCCUPIED, Cell};
/// use haunts_similarity::{similarity_matrix, DifferenceParams};
/// let g = GridGeometry::new(0.05, nalgebra::Point2::origin(), 50, 50).unwrap();
/// let wall_at = |col| {
///     let mut m = OccupancyGrid::unknown(g);
///     for row in 0..50 { m.set(Cell::new(col, row), OCCUPIED); }
///     m
/// };
/// let m = similarity_matrix(&[wall_at(5), wall_at(7), wall_at(40)], &DifferenceParams::default()).unwrap();
/// assert_eq!(m.get(0, 1), Some(0.0)); // 2 cells apart: below ct = 10 cells
/// assert_eq!(m.get(0, 2), Some(50.0 * 35.0));
/// assert_eq!(m.get(2, 1), Some(50.0 * 33.0));
/// ```
pub fn similarity_matrix(
    maps: &[OccupancyGrid],
    params: &DifferenceParams,
) -> Result<SimilarityMatrix> {
    if let Some(first) = maps.first() {
        for (index, m) in maps.iter().enumerate() {
            check_same(index, first.geometry(), m.geometry())?;
        }
    }
    let prepared = in_parallel(maps.iter().enumerate().collect(), |(index, m)| {
        PreparedMap::new(m).map_err(|e| match e {
            SimilarityError::EmptyMap { .. } => SimilarityError::EmptyMap { index },
            e => e,
        })
    })
    .into_iter()
    .collect::<Result<Vec<_>>>()?;
    similarity_matrix_prepared(&prepared, params)
}

/// [`similarity_matrix`] of maps already prepared (their distance fields kept for reuse).
///
/// # Errors
/// As [`similarity_matrix`], except for empty maps (a [`PreparedMap`] never is).
pub fn similarity_matrix_prepared(
    maps: &[PreparedMap],
    params: &DifferenceParams,
) -> Result<SimilarityMatrix> {
    let params = params.check()?;
    let Some(first) = maps.first() else {
        return Ok(SimilarityMatrix {
            n: 0,
            values: Vec::new(),
            occupied: Vec::new(),
            resolution: 1.0,
        });
    };
    for (index, m) in maps.iter().enumerate() {
        check_same(index, first.geometry(), m.geometry())?;
    }
    let resolution = first.geometry().resolution();
    let min_sq = min_squared_above(params.cutoff.cells(resolution));
    let n = maps.len();
    // Each map's occupied cells are looked up in every other map's distance field.
    let occupied: usize = maps.iter().map(|m| m.occupied_indices().len()).sum();
    haunts_occupancy::budget::check_work(
        "similarity matrix",
        &[
            ("maps", n as f64),
            ("occupied cells of all maps", occupied as f64),
        ],
    )?;
    let rows = in_parallel((0..n).collect(), |x| {
        (0..n)
            .map(|y| {
                if x == y {
                    0.0
                } else {
                    sum_above(maps[x].field(), maps[y].occupied_indices(), min_sq)
                }
            })
            .collect::<Vec<f64>>()
    });
    Ok(SimilarityMatrix {
        n,
        values: rows.concat(),
        occupied: maps.iter().map(PreparedMap::occupied_count).collect(),
        resolution,
    })
}

/// `f` over every task, in parallel with the `rayon` feature; results in task order.
pub(crate) fn in_parallel<T: Send, R: Send>(
    tasks: Vec<T>,
    f: impl Fn(T) -> R + Sync + Send,
) -> Vec<R> {
    #[cfg(feature = "rayon")]
    {
        use rayon::prelude::*;
        tasks.into_par_iter().map(f).collect()
    }
    #[cfg(not(feature = "rayon"))]
    tasks.into_iter().map(f).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::directed_difference;
    use haunts_occupancy::{Cell, GridGeometry, OCCUPIED};
    use nalgebra::Point2;
    use rand::{RngExt, SeedableRng, rngs::StdRng};

    fn random_maps(n: usize, seed: u64) -> Vec<OccupancyGrid> {
        let g = GridGeometry::new(0.05, Point2::origin(), 60, 45).unwrap();
        let mut rng = StdRng::seed_from_u64(seed);
        (0..n)
            .map(|_| {
                let mut m = OccupancyGrid::unknown(g);
                for _ in 0..40 {
                    let c = Cell::new(rng.random_range(0..60), rng.random_range(0..45));
                    m.set(c, OCCUPIED);
                }
                m
            })
            .collect()
    }

    #[test]
    fn entries_equal_the_pairwise_function() {
        let maps = random_maps(6, 1);
        let p = DifferenceParams::default().with_cutoff(crate::Length::Cells(3.0));
        let m = similarity_matrix(&maps, &p).unwrap();
        assert_eq!(m.len(), 6);
        let prepared: Vec<_> = maps.iter().map(|m| PreparedMap::new(m).unwrap()).collect();
        let mut nonzero = 0;
        for x in 0..6 {
            for y in 0..6 {
                let want = directed_difference(&prepared[x], &prepared[y], &p).unwrap();
                assert_eq!(m.get(x, y), Some(want));
                nonzero += usize::from(want > 0.0);
            }
        }
        assert!(nonzero > 20, "the fixture should exercise the cutoff");
        let sym = m.symmetrised(Symmetrisation::Max);
        assert_eq!(sym[6 + 4], sym[4 * 6 + 1]);
        assert_eq!(sym[6 + 4], m.get(1, 4).unwrap().max(m.get(4, 1).unwrap()));
    }

    #[test]
    fn same_result_with_one_or_many_threads() {
        let maps = random_maps(9, 2);
        let p = DifferenceParams::default().with_cutoff(crate::Length::Cells(2.0));
        let run = |threads| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| similarity_matrix(&maps, &p).unwrap())
        };
        let one = run(1);
        let four = run(4);
        assert!(
            one.values()
                .iter()
                .zip(four.values())
                .all(|(a, b)| a.to_bits() == b.to_bits())
        );
        assert!(one.values().iter().any(|v| *v > 0.0));
    }

    #[test]
    fn errors_name_the_offending_map() {
        let mut maps = random_maps(4, 3);
        maps[2] = OccupancyGrid::unknown(*maps[0].geometry());
        assert!(matches!(
            similarity_matrix(&maps, &DifferenceParams::default()),
            Err(SimilarityError::EmptyMap { index: 2 })
        ));
        maps[3] = OccupancyGrid::unknown(GridGeometry::new(0.1, Point2::origin(), 60, 45).unwrap());
        assert!(matches!(
            similarity_matrix(&maps, &DifferenceParams::default()),
            Err(SimilarityError::GeometryMismatch { index: 3, .. })
        ));
        assert!(
            similarity_matrix(&[], &DifferenceParams::default())
                .unwrap()
                .is_empty()
        );
        assert!(matches!(
            SimilarityMatrix::from_values(vec![0.0; 3], vec![1, 1], 0.05),
            Err(SimilarityError::LengthMismatch { .. })
        ));
        assert!(matches!(
            SimilarityMatrix::from_values(vec![0.0, f64::NAN, 0.0, 0.0], vec![1, 1], 0.05),
            Err(SimilarityError::InvalidParameter(
                haunts_core::InvalidParameter { .. }
            ))
        ));
    }
}
