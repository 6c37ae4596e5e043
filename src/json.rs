//! One rule for the JSON line every command and example prints last: no non-finite number,
//! and no silent `null`. JSON has no NaN or infinity; a figure that could not be computed is
//! left out, and the line's top-level `left_out` object names it (its path, dots between
//! keys and `[i]` for array positions) with the reason.
//!
//! [`finite`] applies the rule to a [`serde_json::Value`] (where `serde_json` has already
//! turned every NaN and infinity into `null`); [`finite_line`] to a line written by hand
//! with `format!`, where Rust wrote `NaN`, `inf` or `-inf`.
//!
//! ```
//! use haunts::json::{finite, finite_line};
//! use serde_json::json;
//!
//! let line = finite_line(r#"{"mota":NaN,"scans":873,"speeds":[1.5,inf],"name":"NaN"}"#);
//! let v: serde_json::Value = serde_json::from_str(&line)?;
//! assert!(v.get("mota").is_none());
//! assert_eq!(v["left_out"]["mota"], "NaN: not computable");
//! assert_eq!(v["speeds"], json!([1.5, null]));
//! assert_eq!(v["left_out"]["speeds[1]"], "inf: not a finite number");
//! assert_eq!(v["name"], "NaN"); // strings are data
//! // A value built with serde_json: its nulls (NaN, infinities, `None`) are left out.
//! let v = finite(json!({"residual": f64::NAN, "days": 2}));
//! assert_eq!(v, json!({"days": 2, "left_out": {"residual": "not computed (null)"}}));
//! # Ok::<(), serde_json::Error>(())
//! ```

use serde_json::{Map, Value};

/// The marker a non-finite token of a hand-written line becomes before the line is parsed
/// (a string no figure of ours holds; JSON strings cannot carry a raw control character).
const MARK: &str = "\u{2063}haunts-non-finite:";

/// `value` with every `null` left out and named in a top-level `left_out` object (an array's
/// null stays, to keep the positions, and is named too). A `value` without null comes back
/// as it was.
pub fn finite(mut value: Value) -> Value {
    let mut left_out = Map::new();
    prune(&mut value, "", &mut left_out);
    attach(value, left_out)
}

/// A JSON line written by hand, with each `NaN`, `inf` or `-inf` outside strings left out
/// as [`finite`] leaves nulls out (and its nulls too). A line that is valid JSON without a
/// null is returned as it was; one that does not parse even then is returned as it was.
pub fn finite_line(line: &str) -> String {
    if let Ok(v) = serde_json::from_str::<Value>(line) {
        if !has_null(&v) {
            return line.to_owned();
        }
        return finite(v).to_string();
    }
    match serde_json::from_str::<Value>(&marked(line)) {
        Ok(v) => finite(v).to_string(),
        Err(_) => line.to_owned(),
    }
}

/// `line` with each bare `NaN`, `inf`, `-inf` (and `+inf`, `infinity`) outside strings
/// replaced by a marked string.
fn marked(line: &str) -> String {
    let mut out = String::with_capacity(line.len() + 16);
    let mut chars = line.char_indices().peekable();
    let (mut in_string, mut escaped) = (false, false);
    while let Some((i, c)) = chars.next() {
        if in_string {
            out.push(c);
            match (escaped, c) {
                (true, _) => escaped = false,
                (false, '\\') => escaped = true,
                (false, '"') => in_string = false,
                _ => {}
            }
            continue;
        }
        if c == '"' {
            in_string = true;
            out.push(c);
            continue;
        }
        if c.is_ascii_alphabetic() || ((c == '-' || c == '+') && next_is_alpha(&line[i + 1..])) {
            let end = line[i + 1..]
                .find(|ch: char| !ch.is_ascii_alphanumeric())
                .map_or(line.len(), |k| i + 1 + k);
            let word = &line[i..end];
            let bare = word.trim_start_matches(['-', '+']).to_ascii_lowercase();
            if bare == "nan" || bare == "inf" || bare == "infinity" {
                out.push('"');
                out.push_str(MARK);
                out.push_str(word);
                out.push('"');
            } else {
                out.push_str(word);
            }
            while chars.peek().is_some_and(|&(k, _)| k < end) {
                chars.next();
            }
            continue;
        }
        out.push(c);
    }
    out
}

fn next_is_alpha(rest: &str) -> bool {
    rest.chars().next().is_some_and(|c| c.is_ascii_alphabetic())
}

fn has_null(v: &Value) -> bool {
    match v {
        Value::Null => true,
        Value::Array(a) => a.iter().any(has_null),
        Value::Object(o) => o.values().any(has_null),
        _ => false,
    }
}

/// Why `v` is left out, if it is.
fn reason(v: &Value) -> Option<String> {
    match v {
        Value::Null => Some("not computed (null)".to_owned()),
        Value::String(s) => s.strip_prefix(MARK).map(|token| {
            if token.to_ascii_lowercase().contains("nan") {
                format!("{token}: not computable")
            } else {
                format!("{token}: not a finite number")
            }
        }),
        _ => None,
    }
}

fn prune(v: &mut Value, path: &str, left_out: &mut Map<String, Value>) {
    let join = |key: &str| {
        if path.is_empty() {
            key.to_owned()
        } else {
            format!("{path}.{key}")
        }
    };
    match v {
        Value::Object(o) => {
            let gone: Vec<String> = o
                .iter()
                .filter_map(|(k, x)| reason(x).map(|r| (k.clone(), r)))
                .map(|(k, r)| {
                    left_out.insert(join(&k), Value::String(r));
                    k
                })
                .collect();
            for k in gone {
                o.remove(&k);
            }
            for (k, x) in o.iter_mut() {
                prune(x, &join(k), left_out);
            }
        }
        Value::Array(a) => {
            for (i, x) in a.iter_mut().enumerate() {
                let at = format!("{path}[{i}]");
                if let Some(r) = reason(x) {
                    left_out.insert(at, Value::String(r));
                    *x = Value::Null;
                } else {
                    prune(x, &at, left_out);
                }
            }
        }
        _ => {}
    }
}

/// `value` with `left_out` added to its top level (merged with a `left_out` it has); a value
/// that is not an object is wrapped as `{"value": …, "left_out": …}`.
fn attach(value: Value, left_out: Map<String, Value>) -> Value {
    if left_out.is_empty() {
        return value;
    }
    match value {
        Value::Object(mut o) => {
            match o.get_mut("left_out") {
                Some(Value::Object(existing)) => existing.extend(left_out),
                _ => {
                    o.insert("left_out".to_owned(), Value::Object(left_out));
                }
            }
            Value::Object(o)
        }
        other => {
            let mut o = Map::new();
            o.insert("value".to_owned(), other);
            o.insert("left_out".to_owned(), Value::Object(left_out));
            Value::Object(o)
        }
    }
}
