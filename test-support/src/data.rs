//! Where the real data of the tests lives: `../shared/data/` beside the workspace (CI always
//! has it; elsewhere the tests that need it skip with a notice).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// `../shared/data/<relative>` beside the workspace (the folder holding `Cargo.lock`, above
/// this crate), or `None` with a printed notice when it is absent.
pub fn shared_data(relative: &str) -> Option<PathBuf> {
    let manifest = Path::new(env!("CARGO_MANIFEST_DIR"));
    let root = manifest
        .ancestors()
        .find(|dir| dir.join("Cargo.lock").exists())
        .unwrap_or(manifest);
    let path = root.join("../shared/data").join(relative);
    if path.exists() {
        Some(path)
    } else {
        eprintln!("skipping: {} is absent", path.display());
        None
    }
}

/// The files of `dir`, by name; empty if the folder is absent. The fuzz regression tests read
/// their seeds and saved crash inputs with it, through [`crate::crate_files`] (a folder
/// relative to the calling crate).
pub fn files(dir: impl AsRef<Path>) -> BTreeMap<String, Vec<u8>> {
    let Ok(entries) = std::fs::read_dir(dir.as_ref()) else {
        return BTreeMap::new();
    };
    entries
        .map(|e| e.unwrap().path())
        .filter(|p| p.is_file())
        .map(|p| {
            let name = p.file_name().unwrap().to_string_lossy().into_owned();
            (name, std::fs::read(&p).unwrap())
        })
        .collect()
}

/// Asserts that the expectations of a fuzz regression test name exactly the seed files
/// present, so that a seed added without an expectation (or removed) fails the test.
pub fn assert_same_names<V>(files: &BTreeMap<String, Vec<u8>>, expected: &BTreeMap<&str, V>) {
    let have: Vec<&str> = files.keys().map(String::as_str).collect();
    let want: Vec<&str> = expected.keys().copied().collect();
    assert_eq!(have, want, "seed files and expectations differ");
}
