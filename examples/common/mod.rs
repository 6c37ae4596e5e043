//! What the examples share.

#[allow(dead_code)]
pub mod recorded;
#[allow(dead_code)]
pub mod trajectories;

use std::error::Error;
use std::process::ExitCode;

/// An example's outcome as its exit code: on error, the error's message (its `Display`, e.g.
/// "no transform chain from left_laser to base_footprint") on stderr and a failing code,
/// rather than the `Debug` dump a `main` returning `Result` prints.
pub fn report(outcome: Result<(), Box<dyn Error>>) -> ExitCode {
    match outcome {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

/// Says on standard error how many malformed lines of `path` its reader skipped, and the
/// first few with their reasons.
#[allow(dead_code)] // not every example reads a text file
pub fn report_malformed<T>(path: &std::path::Path, parsed: &haunts::tracking::Parsed<T>) {
    if parsed.skipped > 0 {
        eprintln!(
            "{}: skipped {} malformed lines",
            path.display(),
            parsed.skipped
        );
        for s in &parsed.first_skipped {
            eprintln!("  line {}: {}", s.line, s.reason);
        }
    }
}
