//! Inputs shared by the benches: the real data beside the project root.
#![allow(dead_code)]

use std::path::PathBuf;

use haunts::occupancy::GridGeometry;
use haunts::occupancy::carmen::{CarmenLog, CarmenOptions, read_carmen};

/// `../shared/data/<relative>` from the project root, or exit with a notice if absent.
pub fn shared_data(relative: &str) -> PathBuf {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../shared/data")
        .join(relative);
    if !path.exists() {
        eprintln!(
            "{} is absent: these benches need ../shared/data beside the project",
            path.display()
        );
        std::process::exit(0);
    }
    path
}

/// A single-threaded rayon pool, for comparisons with single-threaded peers.
pub fn one_thread() -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("a rayon pool")
}

/// The Intel lab log (corrected poses) and a grid of `resolution` bounding its endpoints with
/// a 1 m margin.
pub fn intel(resolution: f64) -> (CarmenLog, GridGeometry) {
    let log = read_carmen(
        shared_data("carmen/intel-corrected.log.gz"),
        &CarmenOptions::default(),
    )
    .expect("intel log reads");
    let points = log
        .scans
        .iter()
        .flat_map(|s| s.scan.endpoints().map(move |p| s.laser_pose * p));
    let geometry = GridGeometry::bounding(points, resolution, 1.0).expect("geometry");
    (log, geometry)
}
