//! Where the real data of the tests lives: `../shared/data/` beside the workspace (CI always
//! has it; elsewhere the tests that need it skip with a notice). Included by the tests of every
//! crate with `#[path = "…/tests/support/data.rs"] mod data;`, one copy instead of one per
//! crate.
#![allow(dead_code)]

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// `../shared/data/<relative>` beside the workspace (the folder holding `Cargo.lock`, above
/// the including crate), or `None` with a printed notice when it is absent.
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

/// The files of `folder` (relative to the including crate), by name; empty if the folder is
/// absent. The fuzz regression tests read their seeds and saved crash inputs with it.
pub fn files(folder: &str) -> BTreeMap<String, Vec<u8>> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join(folder);
    let Ok(entries) = std::fs::read_dir(&dir) else {
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
