//! The crate's modules form no circle: each top-level module uses only those `src/lib.rs` lists before it, and
//! within each module's folder its files use one another without a circle. Read from the sources themselves:
//! `crate::name` paths between top-level modules, `super::name` and `crate::folder::name` between the files of
//! a folder, comments left out.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// Every `.rs` file under `dir`, depth first.
fn rust_files(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut entries: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    entries.sort();
    for path in entries {
        if path.is_dir() {
            out.extend(rust_files(&path));
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
    out
}

/// The code of a file without its comments (`//` to the end of a line; the sources hold no `/* */`).
fn code(text: &str) -> String {
    text.lines()
        .map(|line| line.split("//").next().unwrap_or(""))
        .collect::<Vec<_>>()
        .join("\n")
}

/// The names that follow `prefix` in `code`: `prefix::name`, and each name in `prefix::{a, b::c}` (the first
/// segment of each path in the braces).
fn names_after(code: &str, prefix: &str) -> BTreeSet<String> {
    let mut out = BTreeSet::new();
    let ident = |s: &str| -> String {
        s.chars()
            .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
            .collect()
    };
    let pattern = format!("{prefix}::");
    let mut rest = code;
    while let Some(at) = rest.find(&pattern) {
        // Not the tail of a longer path (`foo_crate::`).
        let before = rest[..at].chars().last();
        rest = &rest[at + pattern.len()..];
        if before.is_some_and(|c| c.is_ascii_alphanumeric() || c == '_') {
            continue;
        }
        if let Some(group) = rest.strip_prefix('{') {
            let group = &group[..group.find('}').unwrap_or(group.len())];
            for item in group.split(',') {
                let name = ident(item.trim());
                if !name.is_empty() {
                    out.insert(name);
                }
            }
        } else {
            let name = ident(rest);
            if !name.is_empty() {
                out.insert(name);
            }
        }
    }
    out
}

/// A circle in `graph`, as the names along it, if there is one.
fn circle(graph: &BTreeMap<String, BTreeSet<String>>) -> Option<Vec<String>> {
    fn visit(
        node: &str,
        graph: &BTreeMap<String, BTreeSet<String>>,
        path: &mut Vec<String>,
        done: &mut BTreeSet<String>,
    ) -> Option<Vec<String>> {
        if let Some(at) = path.iter().position(|n| n == node) {
            let mut c = path[at..].to_vec();
            c.push(node.to_owned());
            return Some(c);
        }
        if done.contains(node) {
            return None;
        }
        path.push(node.to_owned());
        for next in graph.get(node).into_iter().flatten() {
            if let Some(c) = visit(next, graph, path, done) {
                return Some(c);
            }
        }
        path.pop();
        done.insert(node.to_owned());
        None
    }
    let mut done = BTreeSet::new();
    graph
        .keys()
        .find_map(|n| visit(n, graph, &mut Vec::new(), &mut done))
}

#[test]
fn the_modules_form_no_circle_and_come_in_the_order_lib_rs_lists() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let lib = std::fs::read_to_string(src.join("lib.rs")).unwrap();
    // The order lib.rs documents: its list of `//! - [`name`]: ...` lines.
    let order: Vec<String> = lib
        .lines()
        .filter_map(|l| l.strip_prefix("//! - [`"))
        .map(|l| l[..l.find('`').unwrap()].to_owned())
        .collect();
    let declared: BTreeSet<String> = lib
        .lines()
        .filter_map(|l| l.strip_prefix("pub mod "))
        .map(|l| l.trim_end_matches(';').to_owned())
        .collect();
    assert_eq!(
        order.iter().cloned().collect::<BTreeSet<_>>(),
        declared,
        "lib.rs lists every module it declares, once"
    );
    let top: BTreeSet<String> = declared;
    // Edges between top-level modules, and between the files of each folder.
    let mut uses: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    let mut within: BTreeMap<String, BTreeMap<String, BTreeSet<String>>> = BTreeMap::new();
    for file in rust_files(&src) {
        let rel = file.strip_prefix(&src).unwrap();
        let parts: Vec<String> = rel
            .iter()
            .map(|p| p.to_string_lossy().trim_end_matches(".rs").to_owned())
            .collect();
        let module = parts[0].clone();
        if !top.contains(&module) {
            continue; // lib.rs, main.rs
        }
        let text = code(&std::fs::read_to_string(&file).unwrap());
        for used in names_after(&text, "crate") {
            if top.contains(&used) && used != module {
                uses.entry(module.clone()).or_default().insert(used);
            }
        }
        // A folder's file (not its mod.rs, which declares the others) and the siblings it names.
        if parts.len() == 2 && parts[1] != "mod" {
            let folder = within.entry(module.clone()).or_default();
            let mut named = names_after(&text, "super");
            named.extend(names_after(&text, &format!("crate::{module}")));
            folder.entry(parts[1].clone()).or_default().extend(named);
        }
    }
    for (module, used) in &uses {
        let at = order.iter().position(|m| m == module).unwrap();
        for u in used {
            let before = order.iter().position(|m| m == u).unwrap();
            assert!(
                before < at,
                "{module} uses {u}, which lib.rs lists after it: put {u} first (or break the use)"
            );
        }
    }
    assert_eq!(circle(&uses), None, "a circle of modules");
    for (folder, files) in &within {
        let names: BTreeSet<String> = files.keys().cloned().collect();
        let graph: BTreeMap<String, BTreeSet<String>> = files
            .iter()
            .map(|(f, used)| {
                let used = used
                    .iter()
                    .filter(|u| names.contains(*u) && *u != f)
                    .cloned()
                    .collect();
                (f.clone(), used)
            })
            .collect();
        assert_eq!(circle(&graph), None, "a circle of files in src/{folder}/");
    }
    // The reading finds what is there: the viewer uses the GPU, gpu's frame its object pass.
    assert!(uses["viewer"].contains("gpu") && uses["scene"].contains("objects"));
    assert!(within["gpu"]["frame"].contains("object_pass"));
}

#[test]
fn a_circle_is_found() {
    let graph: BTreeMap<String, BTreeSet<String>> =
        [("a", "b"), ("b", "c"), ("c", "a"), ("d", "a")]
            .into_iter()
            .fold(BTreeMap::new(), |mut g, (x, y)| {
                g.entry(x.to_owned())
                    .or_insert_with(BTreeSet::new)
                    .insert(y.to_owned());
                g
            });
    let c = circle(&graph).unwrap();
    assert_eq!(c.first(), c.last());
    assert_eq!(c.len(), 4);
    assert_eq!(
        names_after("use crate::{a, b::c};\nx_crate::z crate::d::e", "crate"),
        ["a", "b", "d"].map(String::from).into()
    );
}
