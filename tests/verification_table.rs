//! The table "Every numbered result, its test and its oracle" (`docs/results.md`, the guide
//! `gmueller::guide::results`) against the tests: every
//! `file::function` it names is a function of `tests/<file>.rs` (`file` a path under `tests/`,
//! `medium/born::…` for `tests/medium/born.rs`, `frame::…` for `tests/frame.rs`), and every
//! numbered result of the supplemental — S1.1–S1.7, S2.1–S2.20, Lemma S2.1, Corollary S2.2 — has
//! a row.

use std::fs;
use std::path::Path;

/// The table's rows (lines starting with `|` after the section heading).
fn rows() -> Vec<String> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let readme = fs::read_to_string(root.join("docs/results.md")).expect("docs/results.md");
    let start = readme
        .find("# Every numbered result, its test and its oracle")
        .expect("docs/results.md has the table's section");
    readme[start..]
        .lines()
        .skip(1)
        .skip_while(|l| !l.starts_with('|'))
        .take_while(|l| l.starts_with('|'))
        .skip(2) // header and rule
        .map(str::to_owned)
        .collect()
}

/// The `file::function` names in backticks in `text` (`file` a path under `tests/` whose
/// segments are joined by `/`: `medium/born::function`).
fn tests_named(text: &str) -> Vec<(String, String)> {
    let mut out = Vec::new();
    for chunk in text.split('`').skip(1).step_by(2) {
        if let Some((file, function)) = chunk.split_once("::") {
            let ident = |s: &str| {
                !s.is_empty()
                    && s.chars()
                        .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_')
            };
            if file.split('/').all(ident) && ident(function) {
                out.push((file.to_owned(), function.to_owned()));
            }
        }
    }
    out
}

#[test]
fn every_test_in_the_table_exists() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let rows = rows();
    assert!(rows.len() >= 25, "the table has {} rows", rows.len());
    let mut missing = Vec::new();
    let mut count = 0;
    for row in &rows {
        for (file, function) in tests_named(row) {
            count += 1;
            let source = fs::read_to_string(root.join("tests").join(format!("{file}.rs")))
                .unwrap_or_default();
            if !source.contains(&format!("fn {function}(")) {
                missing.push(format!("{file}::{function}"));
            }
        }
    }
    assert!(count > 50, "only {count} tests named");
    assert!(
        missing.is_empty(),
        "named in docs/results.md's table but not found: {missing:?}"
    );
}

#[test]
fn every_numbered_result_has_a_row() {
    let labels: Vec<String> = rows()
        .iter()
        .map(|r| r.split('|').nth(1).unwrap_or("").trim().to_owned())
        .collect();
    // A label covers "S1.4" itself, or a range "S1.4–S1.6".
    let covers = |label: &str, part: u32, n: u32| -> bool {
        let label = label.split(',').next().unwrap_or("").trim();
        let parse = |s: &str| -> Option<(u32, u32)> {
            let s = s.trim().strip_prefix('S')?;
            let (a, b) = s.split_once('.')?;
            Some((a.parse().ok()?, b.parse().ok()?))
        };
        match label.split_once('–') {
            Some((lo, hi)) => {
                matches!((parse(lo), parse(hi)), (Some((p, a)), Some((q, b))) if p == part && q == part && a <= n && n <= b)
            }
            None => parse(label) == Some((part, n)),
        }
    };
    let mut absent = Vec::new();
    for (part, last) in [(1, 7), (2, 20)] {
        for n in 1..=last {
            if !labels.iter().any(|l| covers(l, part, n)) {
                absent.push(format!("S{part}.{n}"));
            }
        }
    }
    for extra in ["Lemma S2.1", "Corollary S2.2"] {
        if !labels.iter().any(|l| l == extra) {
            absent.push(extra.to_owned());
        }
    }
    assert!(absent.is_empty(), "no row for {absent:?}");
}
