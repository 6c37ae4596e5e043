//! The JSON line rule (issue 49, item 3): no non-finite number and no silent `null` in what a
//! command or an example prints; a figure that cannot be computed is left out and named with
//! its reason in `left_out`.
#![cfg(any(feature = "serde", feature = "figures"))]
#![allow(clippy::unwrap_used)]

use haunts::json::{finite, finite_line};
use serde_json::{Value, json};

fn parse(line: &str) -> Value {
    serde_json::from_str(line).unwrap_or_else(|e| panic!("not JSON ({e}): {line}"))
}

#[test]
fn every_non_finite_token_rust_writes_is_left_out_with_its_reason() {
    // What `format!` writes for f64::NAN, INFINITY and NEG_INFINITY, at any depth.
    let line = format!(
        "{{\"a\":{},\"b\":{{\"c\":{},\"d\":1.5e-3}},\"e\":[{},2,-1],\"f\":\"inf and NaN\",\"g\":{:.4}}}",
        f64::NAN,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::NAN
    );
    assert!(serde_json::from_str::<Value>(&line).is_err(), "{line}");
    let v = parse(&finite_line(&line));
    assert_eq!(
        v,
        json!({
            "b": {"d": 1.5e-3},
            "e": [null, 2, -1],
            "f": "inf and NaN",
            "left_out": {
                "a": "NaN: not computable",
                "b.c": "inf: not a finite number",
                "e[0]": "-inf: not a finite number",
                "g": "NaN: not computable",
            }
        })
    );
}

#[test]
fn a_valid_line_without_null_is_printed_as_it_was() {
    let line = r#"{"z":1,"a":[true,false],"s":"a \"NaN\" in quotes","n":-0.5,"e":1E+9}"#;
    assert_eq!(finite_line(line), line);
    // Its keys keep their order: nothing was parsed and written again.
    assert!(finite_line(line).starts_with("{\"z\""));
}

#[test]
fn nulls_are_left_out_and_an_existing_left_out_is_kept() {
    let v = finite(json!({
        "x": null,
        "y": {"z": f64::INFINITY, "w": [1, null]},
        "left_out": {"q": "no ground truth"},
    }));
    assert_eq!(
        v,
        json!({
            "y": {"w": [1, null]},
            "left_out": {
                "q": "no ground truth",
                "x": "not computed (null)",
                "y.z": "not computed (null)",
                "y.w[1]": "not computed (null)",
            }
        })
    );
    // Nothing to leave out: the same value.
    let clean = json!({"a": 1, "b": [2.5]});
    assert_eq!(finite(clean.clone()), clean);
    // A line that is not JSON even with its non-finite numbers marked comes back as it was.
    assert_eq!(finite_line("{broken NaN"), "{broken NaN");
}
