//! JSON round trips for the `tests/serde.rs` of every crate of the workspace.

use std::fmt::{Debug, Display};

use serde::Serialize;
use serde::de::DeserializeOwned;

/// `value` written to JSON and read back (for types without `PartialEq`: compare what
/// matters yourself).
pub fn trip<T: Serialize + DeserializeOwned>(value: &T) -> T {
    serde_json::from_str(&serde_json::to_string(value).unwrap()).unwrap()
}

/// `value` through JSON and back, checked equal to the original.
pub fn round_trip<T: Serialize + DeserializeOwned + PartialEq + Debug>(value: &T) -> T {
    let text = serde_json::to_string(value).unwrap();
    let back: T = serde_json::from_str(&text).unwrap();
    assert_eq!(&back, value, "{text}");
    back
}

/// The error of reading `json` (text, or a `serde_json::Value`) as a `T`, as text; panics
/// if it is accepted.
pub fn rejection<T: DeserializeOwned>(json: impl Display) -> String {
    let text = json.to_string();
    match serde_json::from_str::<T>(&text) {
        Ok(_) => panic!("{text} was accepted"),
        Err(e) => e.to_string(),
    }
}

/// Variants of the JSON `value`, each with one change a corrupted or hand-edited file might
/// hold: a number replaced by 0, −1, 1e300, −1e−300 or 2⁶³; an array with its last element
/// dropped or its first one repeated; an object with one field removed; a string emptied.
/// Every place is changed in turn, in document order, and at most `limit` variants are
/// returned, spread evenly over all of them (deterministic).
pub fn mutations(value: &serde_json::Value, limit: usize) -> Vec<serde_json::Value> {
    let mut all = Vec::new();
    mutate(value, &mut Vec::new(), &mut all);
    if all.len() <= limit || limit == 0 {
        return all
            .into_iter()
            .map(|(path, change)| apply(value, &path, &change))
            .collect();
    }
    let stride = all.len() as f64 / limit as f64;
    (0..limit)
        .map(|k| {
            let (path, change) = &all[(k as f64 * stride) as usize];
            apply(value, path, change)
        })
        .collect()
}

/// One step into a JSON document.
#[derive(Clone)]
enum Step {
    Key(String),
    Index(usize),
}

/// What a variant changes at its place.
enum Change {
    Replace(serde_json::Value),
    DropLast,
    RepeatFirst,
    Remove(String),
}

fn mutate(value: &serde_json::Value, path: &mut Vec<Step>, out: &mut Vec<(Vec<Step>, Change)>) {
    use serde_json::{Value, json};
    match value {
        Value::Number(_) => {
            for v in [
                json!(0),
                json!(-1),
                json!(1e300),
                json!(-1e-300),
                json!(1u64 << 63),
            ] {
                out.push((path.clone(), Change::Replace(v)));
            }
        }
        Value::String(s) if !s.is_empty() => {
            out.push((path.clone(), Change::Replace(json!(""))));
        }
        Value::Array(items) => {
            if !items.is_empty() {
                out.push((path.clone(), Change::DropLast));
                out.push((path.clone(), Change::RepeatFirst));
            }
            for (i, item) in items.iter().enumerate() {
                path.push(Step::Index(i));
                mutate(item, path, out);
                path.pop();
            }
        }
        Value::Object(fields) => {
            for (key, item) in fields {
                out.push((path.clone(), Change::Remove(key.clone())));
                path.push(Step::Key(key.clone()));
                mutate(item, path, out);
                path.pop();
            }
        }
        _ => {}
    }
}

fn apply(value: &serde_json::Value, path: &[Step], change: &Change) -> serde_json::Value {
    let mut copy = value.clone();
    let mut place = &mut copy;
    for step in path {
        place = match step {
            Step::Key(k) => &mut place[k.as_str()],
            Step::Index(i) => &mut place[*i],
        };
    }
    match change {
        Change::Replace(v) => *place = v.clone(),
        Change::DropLast => {
            if let Some(items) = place.as_array_mut() {
                items.pop();
            }
        }
        Change::RepeatFirst => {
            if let Some(items) = place.as_array_mut() {
                let first = items[0].clone();
                items.insert(0, first);
            }
        }
        Change::Remove(key) => {
            if let Some(fields) = place.as_object_mut() {
                fields.remove(key);
            }
        }
    }
    copy
}

/// How many corrupted variants of a document were refused, and how many were accepted.
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq)]
pub struct Tally {
    /// Loaded and usable.
    pub accepted: usize,
    /// Refused on load, or where the loaded value is used.
    pub refused: usize,
}

impl Tally {
    /// Reads each of `variants` as a `T`. One refused on load counts as refused; one accepted
    /// goes to `exercise` (with its JSON), which says whether it was usable (`false`: refused
    /// where it is used, as a simulator refuses an office) and must not panic — a panic fails
    /// naming the variant — and is then written and read back, which must succeed.
    pub fn read<T: Serialize + DeserializeOwned>(
        &mut self,
        variants: Vec<serde_json::Value>,
        mut exercise: impl FnMut(&T, &serde_json::Value) -> bool,
    ) {
        use std::panic::{AssertUnwindSafe, catch_unwind};
        for variant in variants {
            let Ok(loaded) = serde_json::from_value::<T>(variant.clone()) else {
                self.refused += 1;
                continue;
            };
            match catch_unwind(AssertUnwindSafe(|| exercise(&loaded, &variant))) {
                Ok(true) => self.accepted += 1,
                Ok(false) => self.refused += 1,
                Err(_) => panic!(
                    "{}: the corrupted file {variant} loaded, then panicked",
                    std::any::type_name::<T>()
                ),
            }
            let again = serde_json::to_value(&loaded).unwrap();
            if let Err(e) = serde_json::from_value::<T>(again) {
                panic!("{variant} loaded, but not once written again: {e}");
            }
        }
    }
}

/// Reads up to `limit` one-change corruptions ([`mutations`]) of `value` as a `T` (see
/// [`Tally::read`]); `exercise` uses each accepted one, and must not panic.
pub fn corrupt<T: Serialize + DeserializeOwned>(
    value: &T,
    limit: usize,
    mut exercise: impl FnMut(&T),
) -> Tally {
    let mut tally = Tally::default();
    let variants = mutations(&serde_json::to_value(value).unwrap(), limit);
    tally.read(variants, |loaded: &T, _| {
        exercise(loaded);
        true
    });
    tally
}
