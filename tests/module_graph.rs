//! The crate's modules form no circle: each top-level module uses only those `src/lib.rs` lists before it, and
//! within every folder, at any depth, its files and subfolders use one another without a circle (a subfolder
//! counted as one, with everything under it). Read from the sources themselves: every `crate::`, `super::` and
//! `self::` path, resolved to the module it names, comments left out.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// Every file under `dir` whose name ends in `.ext`, depth first.
fn files_with(dir: &Path, ext: &str) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut entries: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    entries.sort();
    for path in entries {
        if path.is_dir() {
            out.extend(files_with(&path, ext));
        } else if path.extension().is_some_and(|e| e == ext) {
            out.push(path);
        }
    }
    out
}

/// Every `.rs` file under `dir`, depth first.
fn rust_files(dir: &Path) -> Vec<PathBuf> {
    files_with(dir, "rs")
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

/// The module a file under `src` is (`a/b.rs` and `a/b/mod.rs` are both `a::b`).
fn module_of(rel: &Path) -> Vec<String> {
    let mut parts: Vec<String> = rel
        .iter()
        .map(|p| p.to_string_lossy().trim_end_matches(".rs").to_owned())
        .collect();
    if parts.last().is_some_and(|p| p == "mod") {
        parts.pop();
    }
    parts
}

/// Every module path `code` (a file of module `module`) names: `crate::a::b`, `super::c`, `self::d`, each item of
/// a group `{e, f::g}`, resolved from the crate's root.
fn paths_in(code: &str, module: &[String]) -> Vec<Vec<String>> {
    fn tail(rest: &str, mut base: Vec<String>, out: &mut Vec<Vec<String>>) {
        let mut rest = rest;
        loop {
            if let Some(group) = rest.strip_prefix('{') {
                let (mut depth, mut start) = (0, 0);
                for (i, c) in group.char_indices() {
                    match c {
                        '{' => depth += 1,
                        '}' if depth == 0 => {
                            tail(group[start..i].trim(), base.clone(), out);
                            return;
                        }
                        '}' => depth -= 1,
                        ',' if depth == 0 => {
                            tail(group[start..i].trim(), base.clone(), out);
                            start = i + 1;
                        }
                        _ => {}
                    }
                }
                return;
            }
            let ident: String = rest
                .chars()
                .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
                .collect();
            if ident.is_empty() {
                out.push(base);
                return;
            }
            match ident.as_str() {
                "super" => {
                    base.pop();
                }
                "self" => {}
                _ => base.push(ident.clone()),
            }
            rest = &rest[ident.len()..];
            match rest.strip_prefix("::") {
                Some(r) => rest = r,
                None => {
                    out.push(base);
                    return;
                }
            }
        }
    }
    let mut out = Vec::new();
    for (at, _) in code.match_indices("::") {
        let head: String = code[..at]
            .chars()
            .rev()
            .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
            .collect::<String>()
            .chars()
            .rev()
            .collect();
        let before = code[..at - head.len()].chars().last();
        // A path's first segment: not the middle of a path (`a::super`), nor the tail of a longer name.
        if before.is_some_and(|c| c == ':' || c.is_ascii_alphanumeric() || c == '_') {
            continue;
        }
        let base = match head.as_str() {
            "crate" => Vec::new(),
            "super" => module[..module.len().saturating_sub(1)].to_vec(),
            "self" => module.to_vec(),
            _ => continue,
        };
        tail(&code[at + 2..], base, &mut out);
    }
    out
}

/// Every circle among the files and subfolders of each folder under `src` (at any depth), as
/// `folder: a -> b -> a`.
fn circles_in_folders(src: &Path) -> Vec<String> {
    // What each file's module names, by the file's module.
    let mut named: Vec<(Vec<String>, Vec<Vec<String>>)> = Vec::new();
    for file in rust_files(src) {
        let rel = file.strip_prefix(src).unwrap();
        if rel.components().count() == 1
            && (rel == Path::new("lib.rs") || rel == Path::new("main.rs"))
        {
            continue;
        }
        let module = module_of(rel);
        let text = code(&std::fs::read_to_string(&file).unwrap());
        named.push((module.clone(), paths_in(&text, &module)));
    }
    // Every folder (a module with files of its own below it), the root's top-level modules included.
    let mut folders: BTreeSet<Vec<String>> = BTreeSet::new();
    for (module, _) in &named {
        for depth in 0..module.len() {
            folders.insert(module[..depth].to_vec());
        }
    }
    let mut found = Vec::new();
    for folder in &folders {
        // Its units: the modules directly in it (a file, or a subfolder with everything under it); its own
        // mod.rs, which declares them, is none of them.
        let units: BTreeSet<String> = (named.iter())
            .filter(|(m, _)| m.len() > folder.len() && m.starts_with(folder))
            .map(|(m, _)| m[folder.len()].clone())
            .collect();
        let mut graph: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
        for (module, paths) in &named {
            if module.len() <= folder.len() || !module.starts_with(folder) {
                continue;
            }
            let unit = &module[folder.len()];
            let uses = graph.entry(unit.clone()).or_default();
            for p in paths {
                if p.len() > folder.len()
                    && p.starts_with(folder)
                    && units.contains(&p[folder.len()])
                    && p[folder.len()] != *unit
                {
                    uses.insert(p[folder.len()].clone());
                }
            }
        }
        if let Some(c) = circle(&graph) {
            found.push(format!("src/{}: {}", folder.join("/"), c.join(" -> ")));
        }
    }
    found
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
    let circles = circles_in_folders(&src);
    assert!(circles.is_empty(), "circles of files: {circles:#?}");
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

#[test]
fn a_circle_planted_in_a_subfolder_is_found() {
    let dir = std::env::temp_dir().join(format!("energywave-module-graph-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let src = dir.join("src");
    let write = |path: &str, text: &str| {
        let path = src.join(path);
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(path, text).unwrap();
    };
    write("lib.rs", "pub mod a;\n");
    write("a/mod.rs", "pub mod b;\npub mod p;\n");
    write(
        "a/p.rs",
        "use super::b::x::X; // a use of the subfolder b\n",
    );
    write("a/b/mod.rs", "pub mod x;\npub mod y;\npub mod z;\n");
    // Two files of a/b/ that use each other: one by `super`, one by its whole path.
    write("a/b/x.rs", "use super::{y::Y, z};\npub struct X;\n");
    write("a/b/y.rs", "pub struct Y(crate::a::b::x::X);\n");
    write("a/b/z.rs", "// crate::a::b::x is named in a comment only\n");
    let circles = circles_in_folders(&src);
    assert_eq!(circles, vec!["src/a/b: x -> y -> x".to_owned()]);
    // A circle through a subfolder: a file of a/b/ uses a/p.rs, which uses a/b/.
    write("a/b/z.rs", "use super::super::p;\n");
    let circles = circles_in_folders(&src);
    assert!(
        circles.contains(&"src/a: b -> p -> b".to_owned()),
        "{circles:?}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Every process-wide static in `src` that can hold what a frame resolved (a `Mutex`, `RwLock`, `OnceLock`,
/// `LazyLock`, `RefCell` or a `thread_local!`), as `file: line`. What a frame resolves is kept in the frame cache
/// its renderer owns (`frame::FrameCache`); a flag (an atomic) is no cache.
fn static_caches(src: &Path) -> Vec<String> {
    let mut found = Vec::new();
    for file in rust_files(src) {
        let text = code(&std::fs::read_to_string(&file).unwrap());
        for line in text.lines() {
            let t = line.trim_start();
            let t = t.strip_prefix("pub ").unwrap_or(t);
            let t = t.strip_prefix("pub(crate) ").unwrap_or(t);
            let holds = [
                "Mutex", "RwLock", "OnceLock", "LazyLock", "RefCell", "OnceCell",
            ]
            .iter()
            .any(|k| line.contains(k));
            if (t.starts_with("static ") && holds) || t.contains("thread_local!") {
                let rel = file.strip_prefix(src).unwrap().display();
                found.push(format!("{rel}: {}", line.trim()));
            }
        }
    }
    found
}

#[test]
fn no_static_cache_in_src() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let found = static_caches(&src);
    assert!(found.is_empty(), "static caches: {found:#?}");
    // The reading finds one where there is one.
    let dir = std::env::temp_dir().join(format!("energywave-statics-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(
        dir.join("kept.rs"),
        "fn f() {\n    static CACHE: Mutex<Vec<u8>> = Mutex::new(Vec::new());\n}\nstatic STOP: AtomicBool = AtomicBool::new(false);\n",
    )
    .unwrap();
    assert_eq!(
        static_caches(&dir),
        vec!["kept.rs: static CACHE: Mutex<Vec<u8>> = Mutex::new(Vec::new());".to_owned()]
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn every_wgsl_file_has_its_twin_named() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let table = std::fs::read_to_string(root.join("src/reference/mod.rs")).unwrap();
    let named: BTreeSet<String> = table
        .lines()
        .filter_map(|l| l.strip_prefix("//! | `"))
        .map(|l| l[..l.find('`').unwrap()].to_owned())
        .collect();
    let shaders = root.join("shaders");
    let files: Vec<String> = (files_with(&shaders, "wgsl").iter())
        .map(|f| {
            f.strip_prefix(&shaders)
                .unwrap()
                .to_string_lossy()
                .replace('\\', "/")
        })
        .collect();
    assert!(files.len() > 20, "{files:?}");
    let missing: Vec<&String> = files.iter().filter(|f| !named.contains(*f)).collect();
    assert!(
        missing.is_empty(),
        "WGSL files without a row in reference/mod.rs's table: {missing:?}"
    );
    let gone: Vec<&String> = named.iter().filter(|n| !files.contains(n)).collect();
    assert!(gone.is_empty(), "rows naming no WGSL file: {gone:?}");
}
