//! Inputs shared by the benches: the real data beside the project root.
#![allow(dead_code)]

use std::path::PathBuf;

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
