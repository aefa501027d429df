//! The module graph of `docs/architecture.md`, checked against the source: every `crate::…`
//! (and, inside `interaction`, `super::…`) path in code — not in comments or docs — must point
//! to a module *below* the one that uses it in the documented order. A new import that runs up
//! the stack, or a cycle, fails here with the file and the line. And the folders of `tests/`
//! mirror those of `src/`.

use std::collections::BTreeMap;
use std::fs;
use std::path::{Path, PathBuf};

/// The crate's top-level modules, bottom first (`docs/architecture.md`).
const LAYERS: &[&str] = &[
    "simd",
    "real",
    "error",
    "numerics",
    "stack",
    "jones",
    "stokes",
    "mueller",
    "frame",
    "fresnel",
    "spectral",
    "gaussian",
    "packet",
    "propagation",
    "psd",
    "matter",
    "interaction",
    "bsdf",
    "medium",
    "verify",
    "prelude",
    "guide",
];

/// The submodules of `interaction`, bottom first.
const INTERACTION: &[&str] = &[
    "geometry",
    "section",
    "attenuation",
    "coherence",
    "roughness",
    "pbsdf",
    "material",
    "prepared",
    "polarization",
    "kernel",
    "level",
    "exitant",
    "sampling",
    "batch",
];

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in fs::read_dir(dir).expect("readable src dir") {
        let path = entry.expect("dir entry").path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// The code of a line: `None` for comment and doc lines, the part before a trailing `//` else.
fn code(line: &str) -> Option<&str> {
    let t = line.trim_start();
    if t.starts_with("//") || t.starts_with("#![doc") || t.starts_with("#[doc") {
        return None;
    }
    Some(line.split("//").next().unwrap_or(line))
}

/// Every identifier that follows `prefix` in `code` (`crate::psd::Psd` → `psd`), including
/// the names of a brace group right after the prefix (`super::{coherence, geometry}`).
fn targets(code: &str, prefix: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut rest = code;
    while let Some(i) = rest.find(prefix) {
        // Not part of a longer path segment such as `my_crate::`.
        let before = rest[..i].chars().last();
        rest = &rest[i + prefix.len()..];
        if before.is_some_and(|c| c.is_alphanumeric() || c == '_') {
            continue;
        }
        if let Some(group) = rest.strip_prefix('{') {
            let end = group.find('}').unwrap_or(group.len());
            for item in group[..end].split(',') {
                let name: String = item
                    .trim()
                    .chars()
                    .take_while(|c| c.is_alphanumeric() || *c == '_')
                    .collect();
                if !name.is_empty() {
                    out.push(name);
                }
            }
        } else {
            let name: String = rest
                .chars()
                .take_while(|c| c.is_alphanumeric() || *c == '_')
                .collect();
            if !name.is_empty() {
                out.push(name);
            }
        }
    }
    out
}

/// The top-level module and (for `interaction`) the submodule a source file belongs to.
fn owner(src: &Path, file: &Path) -> (String, Option<String>) {
    let rel = file.strip_prefix(src).expect("file under src");
    let parts: Vec<String> = rel
        .iter()
        .map(|p| p.to_string_lossy().trim_end_matches(".rs").to_owned())
        .collect();
    let top = parts[0].clone();
    let sub = if top == "interaction" && parts.len() > 1 && parts[1] != "mod" {
        Some(parts[1].clone())
    } else {
        None
    };
    (top, sub)
}

/// `src/` and its Rust files, sorted.
fn sources() -> (PathBuf, Vec<PathBuf>) {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    files.sort();
    (src, files)
}

fn rank(order: &[&str], name: &str) -> Option<usize> {
    order.iter().position(|m| *m == name)
}

#[test]
fn every_import_points_down_the_documented_layers() {
    let (src, files) = sources();
    let mut violations = Vec::new();
    let mut edges: BTreeMap<(String, String), usize> = BTreeMap::new();
    for file in &files {
        let (top, sub) = owner(&src, file);
        if top == "lib" {
            continue; // the crate root declares the modules
        }
        let Some(from) = rank(LAYERS, &top) else {
            violations.push(format!(
                "{}: module `{top}` is not in LAYERS",
                file.display()
            ));
            continue;
        };
        let text = fs::read_to_string(file).expect("readable source");
        for (n, line) in text.lines().enumerate() {
            let Some(code) = code(line) else { continue };
            for target in targets(code, "crate::") {
                let Some(to) = rank(LAYERS, &target) else {
                    continue; // an item of the crate root (`crate::Error`) or a macro path
                };
                *edges.entry((top.clone(), target.clone())).or_default() += 1;
                if to > from {
                    violations.push(format!(
                        "{}:{}: `{top}` imports `{target}`, which is above it",
                        file.display(),
                        n + 1
                    ));
                }
            }
            // Inside `interaction`, sibling imports go through `super::` (or
            // `crate::interaction::`): check them against the submodule order.
            let Some(sub) = &sub else { continue };
            let Some(from_sub) = rank(INTERACTION, sub) else {
                violations.push(format!(
                    "{}: submodule `{sub}` is not in INTERACTION",
                    file.display()
                ));
                continue;
            };
            let depth = file
                .strip_prefix(src.join("interaction"))
                .map_or(0, |p| p.iter().count());
            // `super::` from interaction/x.rs is `interaction`; from interaction/x/y.rs it is
            // `x` (its own module): only the former names siblings.
            let siblings = if depth == 1 {
                targets(code, "super::")
            } else {
                targets(code, "super::super::")
            };
            for target in siblings
                .into_iter()
                .chain(targets(code, "crate::interaction::"))
            {
                let Some(to) = rank(INTERACTION, &target) else {
                    continue; // a re-exported item (`super::Geometry`)
                };
                if to > from_sub {
                    violations.push(format!(
                        "{}:{}: `interaction::{sub}` imports `interaction::{target}`, which is \
                         above it",
                        file.display(),
                        n + 1
                    ));
                }
            }
        }
    }
    assert!(
        violations.is_empty(),
        "imports against the layers of docs/architecture.md:\n{}",
        violations.join("\n")
    );
    // The check saw the crate's real structure (a parser that found nothing would pass).
    for (from, to) in [
        ("interaction", "psd"),
        ("psd", "gaussian"),
        ("mueller", "jones"),
    ] {
        assert!(
            edges.contains_key(&(from.to_owned(), to.to_owned())),
            "expected an import {from} → {to}; found {edges:?}"
        );
    }
}

#[test]
fn the_parser_sees_groups_and_ignores_comments() {
    assert_eq!(
        targets("use super::{coherence::X, geometry};", "super::"),
        ["coherence", "geometry"]
    );
    assert_eq!(targets("let x = crate::psd::two_pi();", "crate::"), ["psd"]);
    assert_eq!(
        targets("use my_crate::psd;", "crate::"),
        Vec::<String>::new()
    );
    assert_eq!(code("    /// see [`crate::interaction`]"), None);
    assert_eq!(code("let a = 1; // crate::x"), Some("let a = 1; "));
}

/// A source file's module path under `src/` (`interaction/batch/lobes.rs` →
/// `["interaction", "batch", "lobes"]`; a `mod.rs` is its folder's module).
fn module_path(src: &Path, file: &Path) -> Vec<String> {
    let rel = file.strip_prefix(src).expect("file under src");
    let mut parts: Vec<String> = rel
        .iter()
        .map(|p| p.to_string_lossy().trim_end_matches(".rs").to_owned())
        .collect();
    if parts.last().is_some_and(|p| p == "mod" || p == "lib") {
        parts.pop();
    }
    parts
}

/// The crate paths a line of code names through `crate::` and chains of `super::`, resolved
/// against the module `at` (`super::super::prep::X` in `a/b/c` → `a/prep/X`); a brace group
/// right after the prefix gives one path per name.
fn paths_named(code: &str, at: &[String]) -> Vec<Vec<String>> {
    let ident = |s: &str| -> String {
        s.chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_')
            .collect()
    };
    let mut out = Vec::new();
    let bytes = code.as_bytes();
    let mut i = 0;
    while i < code.len() {
        let rest = &code[i..];
        let starts = |p: &str| rest.starts_with(p);
        let boundary = i == 0 || !(bytes[i - 1].is_ascii_alphanumeric() || bytes[i - 1] == b'_');
        if !(boundary && (starts("crate::") || starts("super::"))) {
            i += rest.chars().next().map_or(1, char::len_utf8);
            continue;
        }
        let (mut base, mut tail) = if let Some(t) = rest.strip_prefix("crate::") {
            (Vec::new(), t)
        } else {
            (at.to_vec(), rest)
        };
        while let Some(t) = tail.strip_prefix("super::") {
            base.pop();
            tail = t;
        }
        // Segments up to a group, a glob or the end of the path.
        let mut path = base;
        loop {
            let name = ident(tail);
            if name.is_empty() {
                break;
            }
            tail = &tail[name.len()..];
            path.push(name);
            match tail.strip_prefix("::") {
                Some(t) => tail = t,
                None => break,
            }
        }
        if let Some(group) = tail.strip_prefix('{') {
            let end = group.find('}').unwrap_or(group.len());
            for item in group[..end].split(',') {
                let name = ident(item.trim());
                if !name.is_empty() {
                    let mut p = path.clone();
                    p.push(name);
                    out.push(p);
                }
            }
        } else if !path.is_empty() {
            out.push(path);
        }
        // `tail` is a suffix of `code` past at least one `crate::` or `super::`.
        i = code.len() - tail.len();
    }
    out
}

/// The cycles of a small directed graph, one per strongly connected component of two or more
/// nodes (or a self-loop), each listed from its smallest node.
fn cycles(edges: &BTreeMap<String, std::collections::BTreeSet<String>>) -> Vec<Vec<String>> {
    let nodes: Vec<&String> = edges.keys().collect();
    let reaches = |from: &String, to: &String| -> bool {
        let mut seen = std::collections::BTreeSet::new();
        let mut stack = vec![from.clone()];
        while let Some(n) = stack.pop() {
            for m in edges.get(&n).into_iter().flatten() {
                if m == to {
                    return true;
                }
                if seen.insert(m.clone()) {
                    stack.push(m.clone());
                }
            }
        }
        false
    };
    let mut done = std::collections::BTreeSet::new();
    let mut out = Vec::new();
    for a in &nodes {
        if done.contains(*a) || !reaches(a, a) {
            continue;
        }
        let component: Vec<String> = nodes
            .iter()
            .filter(|b| reaches(a, b) && reaches(b, a))
            .map(|b| (*b).clone())
            .collect();
        done.extend(component.iter().cloned());
        out.push(component);
    }
    out
}

/// No cycle between sibling modules in any folder of `src/` (the layer test above orders the
/// top level and `interaction`; this covers every folder, `interaction/batch/` and its
/// `stages/` included): an import from module `a/x…` of `a/y…` is an edge `x → y` of folder
/// `a`, taken at the first segment where the two paths part.
#[test]
fn no_folder_has_an_import_cycle() {
    let (src, files) = sources();
    let modules: std::collections::BTreeSet<Vec<String>> =
        files.iter().map(|f| module_path(&src, f)).collect();
    let mut graphs: BTreeMap<Vec<String>, BTreeMap<String, std::collections::BTreeSet<String>>> =
        BTreeMap::new();
    let mut edge_count = 0;
    for file in &files {
        let at = module_path(&src, file);
        let text = fs::read_to_string(file).expect("readable source");
        for line in text.lines() {
            let Some(code) = code(line) else { continue };
            for target in paths_named(code, &at) {
                let common = at.iter().zip(&target).take_while(|(a, b)| a == b).count();
                if common >= at.len() || common >= target.len() {
                    continue; // the module itself, or one of its ancestors
                }
                let folder = at[..common].to_vec();
                let mut child = folder.clone();
                child.push(target[common].clone());
                if !modules.iter().any(|m| m.starts_with(&child)) {
                    continue; // an item, not a sibling module
                }
                let (from, to) = (at[common].clone(), target[common].clone());
                if graphs
                    .entry(folder)
                    .or_default()
                    .entry(from)
                    .or_default()
                    .insert(to)
                {
                    edge_count += 1;
                }
            }
        }
    }
    let mut found = Vec::new();
    for (folder, edges) in &graphs {
        for c in cycles(edges) {
            found.push(format!("src/{}: {}", folder.join("/"), c.join(" ↔ ")));
        }
    }
    println!(
        "{} folders, {edge_count} sibling edges, {} cycles",
        graphs.len(),
        found.len()
    );
    assert!(found.is_empty(), "import cycles:\n{}", found.join("\n"));
    // The walk saw the real structure, sub-folders included.
    let batch = vec!["interaction".to_owned(), "batch".to_owned()];
    let sees = |folder: &[String], from: &str, to: &str| {
        graphs
            .get(folder)
            .and_then(|g| g.get(from))
            .is_some_and(|t| t.contains(to))
    };
    assert!(sees(&batch, "partial", "prep"), "{graphs:?}");
    assert!(sees(&batch, "lobes", "partial"), "{graphs:?}");
    assert!(sees(&[], "interaction", "psd"), "{graphs:?}");
    assert!(edge_count > 100, "{edge_count}");
}

#[test]
fn the_cycle_finder_and_path_resolver_work() {
    let g = |pairs: &[(&str, &str)]| {
        let mut m: BTreeMap<String, std::collections::BTreeSet<String>> = BTreeMap::new();
        for (a, b) in pairs {
            m.entry((*a).to_owned())
                .or_default()
                .insert((*b).to_owned());
            m.entry((*b).to_owned()).or_default();
        }
        m
    };
    assert!(cycles(&g(&[("a", "b"), ("b", "c")])).is_empty());
    assert_eq!(
        cycles(&g(&[("a", "b"), ("b", "c"), ("c", "a"), ("c", "d")])),
        [["a", "b", "c"]]
    );
    let at: Vec<String> = ["interaction", "batch", "stages", "rayleigh_rice"]
        .map(str::to_owned)
        .to_vec();
    assert_eq!(
        paths_named("use super::super::prep::{Incidence, Other};", &at),
        [
            ["interaction", "batch", "prep", "Incidence"],
            ["interaction", "batch", "prep", "Other"]
        ]
    );
    assert_eq!(
        paths_named("let x = crate::psd::two_pi(); my_crate::a::b", &at),
        [["psd", "two_pi"]]
    );
}

/// The folders of `tests/` that hold no module's tests: the shared helpers and the reference
/// values.
const NOT_MIRRORS: &[&str] = &["common", "data"];

/// The folders below `dir`, as paths relative to `root`, except those of `skip` (relative paths)
/// and everything under them.
fn folders(root: &Path, dir: &Path, skip: &[&str], out: &mut Vec<PathBuf>) {
    for entry in fs::read_dir(dir).expect("readable dir") {
        let path = entry.expect("dir entry").path();
        if !path.is_dir() {
            continue;
        }
        let rel = path
            .strip_prefix(root)
            .expect("dir under root")
            .to_path_buf();
        if skip.iter().any(|s| rel == Path::new(s)) {
            continue;
        }
        folders(root, &path, skip, out);
        out.push(rel);
    }
}

/// The folders of `folders` (paths relative to `tests/`) with no folder at the same relative
/// path under `src`.
fn unmirrored(src: &Path, folders: &[PathBuf]) -> Vec<String> {
    folders
        .iter()
        .filter(|f| !src.join(f).is_dir())
        .map(|f| f.display().to_string())
        .collect()
}

/// The folders of `tests/` mirror those of `src/`: every folder but `common/` and `data/` is
/// named after a folder of `src/` at the same relative path (`tests/interaction/roughness/`
/// holds the tests of `src/interaction/roughness/`), so a module's tests are where its source is.
#[test]
fn every_test_folder_mirrors_a_source_folder() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let tests = root.join("tests");
    let mut found = Vec::new();
    folders(&tests, &tests, NOT_MIRRORS, &mut found);
    found.sort();
    let bad = unmirrored(&root.join("src"), &found);
    assert!(
        bad.is_empty(),
        "folders of tests/ with no folder of src/ at the same path: {bad:?}"
    );
    // The walk saw the real structure, nested folders included, and left out the exceptions.
    for f in ["bsdf", "interaction", "interaction/roughness", "medium"] {
        assert!(found.contains(&PathBuf::from(f)), "{f} not in {found:?}");
    }
    for f in NOT_MIRRORS {
        assert!(!found.contains(&PathBuf::from(f)), "{f} in {found:?}");
    }
}

#[test]
fn the_mirror_check_rejects_a_made_up_folder() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let folders: Vec<PathBuf> = [
        "interaction/roughness",
        "interaction/made_up",
        "made_up",
        "psd/kcorrelation", // a file of src/, not a folder
    ]
    .iter()
    .map(PathBuf::from)
    .collect();
    assert_eq!(
        unmirrored(&src, &folders),
        ["interaction/made_up", "made_up", "psd/kcorrelation"]
    );
}
