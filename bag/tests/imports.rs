//! The crate's modules import one way (issue 49, item 5): no circle among them. The graph is
//! read from the sources: an edge `a → b` for every path into module `b` named in `a`
//! (`crate::…`, `super::…`, `self::…`, a name the crate root re-exports from `b`), outside
//! comments, re-exports (`pub use b::Item` is `a`'s face, not its use of `b`) and `mod`
//! declarations. A
//! child using its parent's items is an edge like any other: the parent must then not use the
//! child's. Test code (from a file's first `#[cfg(test)]` on, and
//! modules named `tests`) is left out: tests look into what they test.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// `src/read/mcap_file.rs` → `read::mcap_file`; `src/read.rs` → `read`; `src/lib.rs` → ``.
fn module_of(src: &Path, file: &Path) -> String {
    let rel = file.strip_prefix(src).unwrap().with_extension("");
    let name = rel
        .components()
        .map(|c| c.as_os_str().to_string_lossy().into_owned())
        .collect::<Vec<_>>()
        .join("::");
    if name == "lib" { String::new() } else { name }
}

fn files(dir: &Path, out: &mut Vec<std::path::PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// The paths a text names after `crate::`, `super::` or `self::`, braces expanded: each as
/// (its anchor, its segments).
fn paths(text: &str) -> Vec<(&'static str, Vec<String>)> {
    fn expand(rest: &str, prefix: Vec<String>, out: &mut Vec<Vec<String>>) {
        let rest = rest.trim_start();
        if let Some(inner) = rest.strip_prefix('{') {
            // Split at top-level commas up to the matching brace.
            let (mut depth, mut start) = (0usize, 0usize);
            for (i, ch) in inner.char_indices() {
                match ch {
                    '{' => depth += 1,
                    '}' if depth == 0 => {
                        expand(&inner[start..i], prefix.clone(), out);
                        return;
                    }
                    '}' => depth -= 1,
                    ',' if depth == 0 => {
                        expand(&inner[start..i], prefix.clone(), out);
                        start = i + 1;
                    }
                    _ => {}
                }
            }
            return;
        }
        let end = rest
            .find(|c: char| !(c.is_alphanumeric() || c == '_' || c == ':'))
            .unwrap_or(rest.len());
        let mut segments = prefix;
        segments.extend(
            rest[..end]
                .split("::")
                .filter(|s| !s.is_empty())
                .map(str::to_owned),
        );
        let tail = &rest[end..];
        if rest[..end].ends_with("::") && tail.trim_start().starts_with('{') {
            expand(tail, segments, out);
        } else if !segments.is_empty() {
            out.push(segments);
        }
    }
    let mut found = Vec::new();
    for anchor in ["crate::", "super::", "self::"] {
        let mut from = 0;
        while let Some(i) = text[from..].find(anchor) {
            let at = from + i;
            from = at + anchor.len();
            // A whole word: not `foo_crate::` or `haunts_crate::`.
            if text[..at]
                .chars()
                .next_back()
                .is_some_and(|c| c.is_alphanumeric() || c == '_')
            {
                continue;
            }
            let mut out = Vec::new();
            expand(&text[from..], Vec::new(), &mut out);
            let name: &'static str = match anchor {
                "crate::" => "crate",
                "super::" => "super",
                _ => "self",
            };
            found.extend(out.into_iter().map(|p| (name, p)));
        }
    }
    found
}

#[test]
fn the_modules_import_one_way() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut all = Vec::new();
    files(&src, &mut all);
    let texts: BTreeMap<String, String> = all
        .iter()
        .map(|f| {
            let text = std::fs::read_to_string(f).unwrap();
            // Test code from the first `#[cfg(test)]` on.
            let text = text
                .find("#[cfg(test)]")
                .map_or(text.as_str(), |i| &text[..i])
                .to_owned();
            (module_of(&src, f), text)
        })
        .filter(|(m, _)| !m.split("::").any(|s| s == "tests"))
        .collect();
    let modules: BTreeSet<&str> = texts.keys().map(String::as_str).collect();
    // Names the crate root re-exports, by the module they come from (`pub use read::{Bag, …}`).
    let mut reexported: BTreeMap<String, String> = BTreeMap::new();
    for line in texts[""].lines().map(str::trim) {
        let Some(rest) = line
            .strip_prefix("pub use ")
            .or(line.strip_prefix("pub(crate) use "))
        else {
            continue;
        };
        let mut out = Vec::new();
        for (_, p) in paths(&format!("crate::{rest}")) {
            out.push(p);
        }
        for p in out {
            if p.len() >= 2 && modules.contains(p[0].as_str()) {
                reexported.insert(p.last().unwrap().clone(), p[0].clone());
            }
        }
    }
    // The module a path lands in: its longest prefix that is a module.
    let resolve = |segments: &[String]| -> Option<String> {
        (1..=segments.len()).rev().find_map(|n| {
            let m = segments[..n].join("::");
            modules.contains(m.as_str()).then_some(m)
        })
    };
    let mut edges: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for (module, text) in &texts {
        if module.is_empty() {
            continue; // the root holds only declarations and re-exports
        }
        let parent: Vec<String> = module
            .split("::")
            .map(str::to_owned)
            .collect::<Vec<_>>()
            .split_last()
            .map(|(_, p)| p.to_vec())
            .unwrap_or_default();
        let me: Vec<String> = module.split("::").map(str::to_owned).collect();
        let mut targets = BTreeSet::new();
        // A re-export (`pub use child::Item`) is the module's face, not something it uses:
        // left out, as are `mod` declarations.
        let used: String = text
            .lines()
            .filter(|l| {
                let l = l.trim_start();
                !(l.starts_with("pub use ")
                    || l.starts_with("pub(crate) use ")
                    || l.starts_with("//"))
            })
            .collect::<Vec<_>>()
            .join("\n");
        for (anchor, p) in paths(&used) {
            let full: Vec<String> = match anchor {
                "crate" => p,
                "super" => parent.iter().cloned().chain(p).collect(),
                _ => me.iter().cloned().chain(p).collect(),
            };
            match resolve(&full) {
                Some(m) => {
                    targets.insert(m);
                }
                // A name the root re-exports (`crate::Bag`, `crate::{BagError, Result}`).
                None => {
                    if let Some(m) = full.first().and_then(|n| reexported.get(n)) {
                        targets.insert(m.clone());
                    }
                }
            }
        }
        targets.remove(module);
        targets.retain(|t| modules.contains(t.as_str()));
        edges.insert(module.clone(), targets);
    }
    // A circle, if any, by depth-first search.
    fn visit(
        m: &str,
        edges: &BTreeMap<String, BTreeSet<String>>,
        state: &mut BTreeMap<String, u8>,
        stack: &mut Vec<String>,
    ) -> Option<Vec<String>> {
        state.insert(m.to_owned(), 1);
        stack.push(m.to_owned());
        for t in edges.get(m).into_iter().flatten() {
            match state.get(t.as_str()) {
                Some(1) => {
                    let from = stack.iter().position(|s| s == t).unwrap();
                    let mut circle = stack[from..].to_vec();
                    circle.push(t.clone());
                    return Some(circle);
                }
                Some(_) => {}
                None => {
                    if let Some(c) = visit(t, edges, state, stack) {
                        return Some(c);
                    }
                }
            }
        }
        stack.pop();
        state.insert(m.to_owned(), 2);
        None
    }
    let mut state = BTreeMap::new();
    for m in edges.keys() {
        if !state.contains_key(m.as_str()) {
            let circle = visit(m, &edges, &mut state, &mut Vec::new());
            assert!(
                circle.is_none(),
                "an import circle: {}",
                circle.unwrap().join(" → ")
            );
        }
    }
    // The graph was read at all: the readers are in it, with the edges they must have.
    assert!(edges["read"].contains("read::mcap_file"), "{edges:?}");
    assert!(
        edges["read::mcap_file"].contains("read::topic"),
        "{edges:?}"
    );
    assert!(edges["read::mcap_file"].contains("mcap_check"), "{edges:?}");
    assert!(edges["recording"].contains("read"), "{edges:?}");
}
