//! The layers a [`LayeredCostmap`](crate::LayeredCostmap) is built from: static map,
//! inflation around lethal cells, and density of people.

mod density;
mod inflation;
mod static_layer;

pub use density::{Combine, DensityLayer, DensityLayerParams};
pub use inflation::{InflationLayer, InflationParams};
pub use static_layer::StaticLayer;

/// Rows per parallel task when a layer sweeps the grid.
const ROWS_PER_TASK: usize = 64;

/// Calls `f(first_index, costs_chunk)` on chunks of whole rows of `costs`, in parallel with the
/// `rayon` feature. Each cell is written by exactly one call, so the result does not depend on
/// the number of threads.
pub(crate) fn for_row_chunks(costs: &mut [u8], width: usize, f: impl Fn(usize, &mut [u8]) + Sync) {
    let chunk = width * ROWS_PER_TASK;
    #[cfg(feature = "rayon")]
    {
        use rayon::prelude::*;
        costs
            .par_chunks_mut(chunk)
            .enumerate()
            .for_each(|(k, c)| f(k * chunk, c));
    }
    #[cfg(not(feature = "rayon"))]
    for (k, c) in costs.chunks_mut(chunk).enumerate() {
        f(k * chunk, c);
    }
}
