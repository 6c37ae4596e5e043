//! What the examples share.

#[allow(dead_code)]
pub mod recorded;

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
