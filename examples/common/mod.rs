//! What the examples share.

#[allow(dead_code)]
pub mod recorded;

use std::error::Error;
use std::process::ExitCode;

use serde_json::Value;

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

#[allow(dead_code)]
/// The scalars of a JSON value as `(dotted.name, value)` rows.
pub fn json_rows(prefix: &str, value: &Value) -> Vec<(String, String)> {
    let name = |k: &str| {
        if prefix.is_empty() {
            k.to_string()
        } else {
            format!("{prefix}.{k}")
        }
    };
    match value {
        Value::Object(map) => map
            .iter()
            .flat_map(|(k, v)| json_rows(&name(k), v))
            .collect(),
        Value::Array(items) => items
            .iter()
            .enumerate()
            .flat_map(|(i, v)| json_rows(&name(&i.to_string()), v))
            .collect(),
        Value::Number(n) if n.is_f64() => vec![(
            prefix.to_string(),
            n.as_f64().map_or(n.to_string(), |v| format!("{v:.4}")),
        )],
        Value::String(text) => vec![(prefix.to_string(), text.clone())],
        other => vec![(prefix.to_string(), other.to_string())],
    }
}
