//! The ROS map_server YAML file: a flat mapping read with line numbers for every value, and
//! the map metadata it holds.

use std::path::Path;

use yaml_rust2::parser::{Event, MarkedEventReceiver, Parser};
use yaml_rust2::scanner::Marker;

use super::{LoadNote, MapLoadOptions, MapMetadata, MapMode};
use crate::{OccupancyError, Result};

/// A top-level value of the file: a scalar, a list of scalars, or something nested.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Value {
    Scalar(String),
    List(Vec<String>),
    Nested,
}

/// One `key: value` entry with the (1-based) line of its value.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Entry {
    pub key: String,
    pub value: Value,
    pub line: usize,
}

#[derive(Default)]
struct Events(Vec<(Event, Marker)>);

impl MarkedEventReceiver for Events {
    fn on_event(&mut self, ev: Event, mark: Marker) {
        self.0.push((ev, mark));
    }
}

/// The entries of a YAML document whose root is a mapping, in file order (repeated keys are
/// kept: the caller decides what a repetition means).
pub(crate) fn entries(text: &str, path: &Path) -> Result<Vec<Entry>> {
    let mut events = Events::default();
    Parser::new_from_str(text)
        .load(&mut events, false)
        .map_err(|e| OccupancyError::YamlSyntax {
            path: path.to_path_buf(),
            line: e.marker().line(),
            column: e.marker().col() + 1,
            message: e.info().to_owned(),
        })?;
    let not_a_mapping = |line| OccupancyError::InvalidField {
        path: path.to_path_buf(),
        line,
        field: "(document)".into(),
        value: String::new(),
        expected: "a mapping of `key: value` lines",
    };
    let mut it = events.0.into_iter().skip_while(|(e, _)| {
        matches!(
            e,
            Event::StreamStart | Event::DocumentStart | Event::Nothing
        )
    });
    match it.next() {
        Some((Event::MappingStart(..), _)) => {}
        Some((_, m)) => return Err(not_a_mapping(m.line())),
        None => return Err(not_a_mapping(1)),
    }
    let mut out = Vec::new();
    loop {
        let (key, line) = match it.next() {
            Some((Event::Scalar(k, ..), m)) => (k, m.line()),
            Some((Event::MappingEnd, _)) => return Ok(out),
            Some((_, m)) => return Err(not_a_mapping(m.line())),
            None => return Err(not_a_mapping(1)),
        };
        let (value, line) = match it.next() {
            Some((Event::Scalar(v, ..), m)) => (Value::Scalar(v), m.line()),
            Some((Event::SequenceStart(..), m)) => {
                let mut items = Vec::new();
                let mut nested = false;
                let mut depth = 1usize;
                for (e, _) in it.by_ref() {
                    match e {
                        Event::SequenceStart(..) | Event::MappingStart(..) => {
                            depth += 1;
                            nested = true;
                        }
                        Event::SequenceEnd | Event::MappingEnd => {
                            depth -= 1;
                            if depth == 0 {
                                break;
                            }
                        }
                        Event::Scalar(v, ..) if depth == 1 => items.push(v),
                        _ => {}
                    }
                }
                (
                    if nested {
                        Value::Nested
                    } else {
                        Value::List(items)
                    },
                    m.line(),
                )
            }
            Some((Event::MappingStart(..), m)) => {
                let mut depth = 1usize;
                for (e, _) in it.by_ref() {
                    match e {
                        Event::SequenceStart(..) | Event::MappingStart(..) => depth += 1,
                        Event::SequenceEnd | Event::MappingEnd => {
                            depth -= 1;
                            if depth == 0 {
                                break;
                            }
                        }
                        _ => {}
                    }
                }
                (Value::Nested, m.line())
            }
            Some((_, m)) => (Value::Nested, m.line()),
            None => return Err(not_a_mapping(line)),
        };
        out.push(Entry { key, value, line });
    }
}

/// Reads the text of a map YAML file into metadata, applying the options' defaults;
/// `yaml_path` names the file in errors and resolves a relative image path.
///
/// # Errors
/// As [`load_map`](super::load_map) for the YAML.
pub fn parse_map_yaml(
    text: &str,
    path: &Path,
    options: &MapLoadOptions,
) -> Result<(MapMetadata, Vec<LoadNote>)> {
    const KNOWN: [&str; 7] = [
        "image",
        "mode",
        "resolution",
        "origin",
        "negate",
        "occupied_thresh",
        "free_thresh",
    ];
    let mut notes = Vec::new();
    // Keys are looked up by name: a file with many keys stays linear.
    let mut fields: std::collections::HashMap<String, Entry> = std::collections::HashMap::new();
    for entry in entries(text, path)? {
        match fields.get(&entry.key) {
            Some(first) if first.value != entry.value => {
                return Err(OccupancyError::ConflictingField {
                    path: path.to_path_buf(),
                    line: entry.line,
                    field: entry.key,
                });
            }
            Some(_) => notes.push(LoadNote::RepeatedField {
                field: entry.key,
                line: entry.line,
            }),
            None => {
                if !KNOWN.contains(&entry.key.as_str()) {
                    notes.push(LoadNote::UnknownField {
                        field: entry.key.clone(),
                        line: entry.line,
                    });
                }
                fields.insert(entry.key.clone(), entry);
            }
        }
    }
    let get = |key: &str| fields.get(key);
    let invalid = |e: &Entry, expected| OccupancyError::InvalidField {
        path: path.to_path_buf(),
        line: e.line,
        field: e.key.clone(),
        value: match &e.value {
            Value::Scalar(s) => s.clone(),
            Value::List(items) => format!("[{}]", items.join(", ")),
            Value::Nested => "(nested)".into(),
        },
        expected,
    };
    let missing = |field| OccupancyError::MissingField {
        path: path.to_path_buf(),
        field,
    };
    let scalar = |e: &Entry, expected| match &e.value {
        Value::Scalar(s) => Ok(s.trim().to_owned()),
        _ => Err(invalid(e, expected)),
    };
    let number = |e: &Entry, expected| {
        scalar(e, expected)?
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(|| invalid(e, expected))
    };

    let image_entry = get("image").ok_or_else(|| missing("image"))?;
    let image = scalar(image_entry, "a file name").and_then(|s| {
        if s.is_empty() {
            Err(invalid(image_entry, "a file name"))
        } else {
            Ok(s)
        }
    })?;
    let image = match Path::new(&image) {
        p if p.is_absolute() => p.to_path_buf(),
        p => path.parent().unwrap_or(Path::new("")).join(p),
    };

    let e = get("resolution").ok_or_else(|| missing("resolution"))?;
    let resolution = number(e, "a positive number of metres per pixel")?;
    if resolution <= 0.0 {
        return Err(invalid(e, "a positive number of metres per pixel"));
    }

    let e = get("origin").ok_or_else(|| missing("origin"))?;
    const ORIGIN: &str = "a list [x, y, yaw] of finite numbers";
    let origin: [f64; 3] = match &e.value {
        Value::List(items) if items.len() == 3 => {
            let mut o = [0.0; 3];
            for (slot, item) in o.iter_mut().zip(items) {
                *slot = item
                    .trim()
                    .parse::<f64>()
                    .ok()
                    .filter(|v| v.is_finite())
                    .ok_or_else(|| invalid(e, ORIGIN))?;
            }
            o
        }
        _ => return Err(invalid(e, ORIGIN)),
    };
    if origin[2] != 0.0 && !options.keep_yaw {
        return Err(OccupancyError::NonZeroYaw {
            path: path.to_path_buf(),
            yaw: origin[2],
        });
    }

    const THRESH: &str = "a number in [0, 1]";
    let e = get("occupied_thresh").ok_or_else(|| missing("occupied_thresh"))?;
    let occupied_thresh = number(e, THRESH)?;
    if !(0.0..=1.0).contains(&occupied_thresh) {
        return Err(invalid(e, THRESH));
    }
    let free_thresh = match get("free_thresh") {
        Some(e) => {
            let v = number(e, "a number in [0, occupied_thresh)")?;
            if !(0.0..occupied_thresh).contains(&v) {
                return Err(invalid(e, "a number in [0, occupied_thresh)"));
            }
            v
        }
        None => {
            let v = options
                .default_free_thresh
                .ok_or_else(|| missing("free_thresh"))?;
            if !(0.0..occupied_thresh).contains(&v) {
                return Err(OccupancyError::InvalidParameter(
                    haunts_core::InvalidParameter {
                        name: "default_free_thresh",
                        value: v,
                        rule: "must be in [0, occupied_thresh) of the file",
                    },
                ));
            }
            notes.push(LoadNote::Defaulted {
                field: "free_thresh",
                value: v.to_string(),
            });
            v
        }
    };

    let negate = match get("negate") {
        Some(e) => match scalar(e, "0, 1, true or false")?.as_str() {
            "0" | "false" | "False" => false,
            "1" | "true" | "True" => true,
            _ => return Err(invalid(e, "0, 1, true or false")),
        },
        None => {
            let v = options.default_negate.ok_or_else(|| missing("negate"))?;
            notes.push(LoadNote::Defaulted {
                field: "negate",
                value: v.to_string(),
            });
            v
        }
    };

    let mode = match get("mode") {
        Some(e) => match scalar(e, "trinary, scale or raw")?.as_str() {
            "trinary" => MapMode::Trinary,
            "scale" => MapMode::Scale,
            "raw" => MapMode::Raw,
            _ => return Err(invalid(e, "trinary, scale or raw")),
        },
        None => {
            notes.push(LoadNote::Defaulted {
                field: "mode",
                value: "trinary".into(),
            });
            MapMode::Trinary
        }
    };

    let metadata = MapMetadata {
        image,
        mode,
        resolution,
        origin,
        negate,
        occupied_thresh,
        free_thresh,
    };
    Ok((metadata, notes))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_scalars_lists_and_repeats_with_lines() {
        let text =
            "image: a.pgm\norigin: [1.5, -2, 0.0]\nfree_thresh: 0.2\nfree_thresh: 0.2\nx: {a: 1}\n";
        let e = entries(text, Path::new("m.yaml")).unwrap();
        assert_eq!(
            e[0],
            Entry {
                key: "image".into(),
                value: Value::Scalar("a.pgm".into()),
                line: 1
            }
        );
        assert_eq!(
            e[1].value,
            Value::List(vec!["1.5".into(), "-2".into(), "0.0".into()])
        );
        assert_eq!((e[3].key.as_str(), e[3].line), ("free_thresh", 4));
        assert_eq!(e[4].value, Value::Nested);
    }

    #[test]
    fn syntax_errors_and_non_mappings_are_typed() {
        let r = entries("image: [a\nb: c", Path::new("m.yaml"));
        assert!(matches!(r, Err(OccupancyError::YamlSyntax { .. })), "{r:?}");
        let r = entries("- a\n- b\n", Path::new("m.yaml"));
        assert!(
            matches!(r, Err(OccupancyError::InvalidField { .. })),
            "{r:?}"
        );
        let r = entries("", Path::new("m.yaml"));
        assert!(
            matches!(r, Err(OccupancyError::InvalidField { .. })),
            "{r:?}"
        );
    }
}
