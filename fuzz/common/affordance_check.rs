//! What the `detections` and `layout_library` fuzz targets do with an input, shared with
//! `affordance/tests/fuzz_regressions.rs` so that saved inputs replay exactly as fuzzed.
//!
//! - `detections`: byte 0 is the configuration (bits 1–5 as in `text_check.rs`: delimiter,
//!   one header line, columns; the fourth column is unused), the rest the file, read by
//!   `hypertime::parse_detections`.
//! - `layout_library`: byte 0 bit 0 clear: the rest is a whole library file; set: the rest is
//!   a payload, wrapped by [`library_file`] in a valid header and SHA-256 (so that the fuzzer
//!   reaches the payload's fields past the checksum). Read by `LayoutLibrary::from_bytes`; an
//!   accepted library must write itself out and read back.
#![allow(dead_code)]

#[path = "text_check.rs"]
mod text_check;

use haunts_affordance::hypertime::{DetectionColumns, parse_detections};
use haunts_affordance::layout::file::MAGIC;
use haunts_affordance::{AffordanceError, LayoutLibrary};
use sha2::{Digest, Sha256};

/// A library file (version 1) around `payload`: magic, version, length, payload, SHA-256.
pub fn library_file(payload: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(payload.len() + 52);
    out.extend_from_slice(&MAGIC);
    out.extend_from_slice(&1u32.to_le_bytes());
    out.extend_from_slice(&(payload.len() as u64).to_le_bytes());
    out.extend_from_slice(payload);
    out.extend_from_slice(Sha256::digest(payload).as_slice());
    out
}

/// Runs the `detections` target on an input; returns (records, skipped).
pub fn detections(data: &[u8]) -> (usize, usize) {
    let (config, file) = text_check::split(data);
    let [time, x, y, _] = text_check::columns(config);
    let columns = DetectionColumns {
        time,
        x,
        y,
        delimiter: text_check::delimiter(config),
        header_lines: text_check::header_lines(config),
    };
    let parsed = parse_detections(file, &columns).expect("valid columns, in-memory read");
    let lines = text_check::line_count(file);
    text_check::check_parsed(&parsed, lines, |_| None);
    assert!(parsed.records.len() + parsed.skipped <= lines);
    for p in &parsed.records {
        assert!(p.time.is_finite() && p.position.x.is_finite() && p.position.y.is_finite());
    }
    (parsed.records.len(), parsed.skipped)
}

/// Runs the `layout_library` target on an input: `Ok(layouts)` when the library is accepted
/// (and it then round-trips through its own bytes), or the typed error.
pub fn layout_library(data: &[u8]) -> Result<usize, AffordanceError> {
    let (config, rest) = text_check::split(data);
    let library = if config & 1 == 1 {
        LayoutLibrary::from_bytes(&library_file(rest))?
    } else {
        LayoutLibrary::from_bytes(rest)?
    };
    let again = LayoutLibrary::from_bytes(&library.to_bytes())
        .expect("an accepted library reads back from its own bytes");
    assert_eq!(
        again.to_bytes(),
        library.to_bytes(),
        "bytes stable after one round trip"
    );
    Ok(library.layouts().len())
}
