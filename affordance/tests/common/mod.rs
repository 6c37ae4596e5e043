//! Helpers shared by the integration tests.

use std::path::PathBuf;

/// A file of `../shared/data/` (beside the project root), or `None` with a printed notice.
pub fn shared_data(relative: &str) -> Option<PathBuf> {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../shared/data")
        .join(relative);
    if path.exists() {
        Some(path)
    } else {
        eprintln!("skipping: {} is absent", path.display());
        None
    }
}
