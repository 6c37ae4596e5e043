//! The ROS map_server YAML file: a flat mapping read with line numbers for every value.

use std::path::Path;

use yaml_rust2::parser::{Event, MarkedEventReceiver, Parser};
use yaml_rust2::scanner::Marker;

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
