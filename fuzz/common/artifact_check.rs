//! What the `day_artifact` fuzz target does with an input, shared with the facade's
//! `tests/artifact_fuzz_regressions.rs` so that saved inputs replay exactly as fuzzed. Byte
//! 0 bit 0 clear: the rest is a whole artifact file; set: the rest is a payload, wrapped by
//! [`artifact_file`] in a valid header and SHA-256 (so that the fuzzer reaches the payload's
//! fields past the checksum). Read by `DayArtifact::from_bytes`; an accepted artifact must
//! write itself out, read back equal, and give the same bytes again.
#![allow(dead_code)]

use std::path::Path;

use haunts::artifact::{ArtifactError, DayArtifact, FORMAT_VERSION, MAGIC};
use sha2::{Digest, Sha256};

/// An artifact file of this version around `payload`: magic, version, length, payload,
/// SHA-256 of all before it.
pub fn artifact_file(payload: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(payload.len() + 52);
    out.extend_from_slice(&MAGIC);
    out.extend_from_slice(&FORMAT_VERSION.to_le_bytes());
    out.extend_from_slice(&(payload.len() as u64).to_le_bytes());
    out.extend_from_slice(payload);
    let sum = Sha256::digest(&out);
    out.extend_from_slice(sum.as_slice());
    out
}

/// Runs the `day_artifact` target on an input: `Ok(trajectories)` when the artifact is
/// accepted (and it then round-trips through its own bytes), or the typed error.
pub fn day_artifact(data: &[u8]) -> Result<usize, ArtifactError> {
    let (config, rest) = match data.split_first() {
        Some((&config, rest)) => (config, rest),
        None => (0, &[][..]),
    };
    let path = Path::new("(fuzz)");
    let artifact = if config & 1 == 1 {
        DayArtifact::from_bytes(&artifact_file(rest), path)?
    } else {
        DayArtifact::from_bytes(rest, path)?
    };
    let bytes = artifact.to_bytes();
    let again = DayArtifact::from_bytes(&bytes, path)
        .expect("an accepted artifact reads back from its own bytes");
    assert_eq!(again.to_bytes(), bytes, "bytes stable after one round trip");
    Ok(artifact.trajectories.len())
}
