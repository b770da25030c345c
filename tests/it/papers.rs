//! `docs/papers.md` stays true: every file it names exists, every
//! `path::test_name` names a `fn test_name` in that file, and every scene in
//! its tables' Scene column is a built-in scene. Reads files only.

use haptloop::scenes::BUILTIN;
use std::path::Path;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn page() -> String {
    std::fs::read_to_string(root().join("docs/papers.md")).unwrap()
}

/// The backticked tokens of `text`.
fn backticked(text: &str) -> Vec<&str> {
    text.split('`').skip(1).step_by(2).collect()
}

/// A token that names a file of the repository: no spaces, a top-level
/// folder of the workspace, an extension.
fn is_path(token: &str) -> bool {
    const TOP: [&str; 9] = [
        "src/", "solver/", "devices/", "rt/", "tests/", "benches/", "docs/", "scenes/", "fuzz/",
    ];
    !token.contains(' ') && TOP.iter().any(|t| token.starts_with(t))
}

/// Whether `source` defines a function `name` (`fn name(` after any
/// qualifiers).
fn defines_fn(source: &str, name: &str) -> bool {
    let needle = format!("fn {name}(");
    source.lines().any(|l| l.trim_start().contains(&needle))
}

#[test]
fn every_file_and_test_named_in_papers_md_exists() {
    let text = page();
    let mut files = 0;
    let mut tests = 0;
    let mut problems = Vec::new();
    for token in backticked(&text).into_iter().filter(|t| is_path(t)) {
        let (path, test) = match token.split_once("::") {
            Some((p, t)) => (p, Some(t)),
            None => (token, None),
        };
        let Ok(source) = std::fs::read_to_string(root().join(path)) else {
            problems.push(format!("`{token}`: no file {path}"));
            continue;
        };
        files += 1;
        if let Some(test) = test {
            tests += 1;
            if !defines_fn(&source, test) {
                problems.push(format!("`{token}`: {path} has no `fn {test}`"));
            }
        }
    }
    assert!(problems.is_empty(), "docs/papers.md: {problems:#?}");
    // The page maps three papers: a parse that found almost nothing is a bug
    // here, not a true page.
    assert!(files >= 100 && tests >= 80, "{files} paths, {tests} tests");
}

#[test]
fn every_scene_in_papers_md_is_a_builtin_scene() {
    let text = page();
    let mut scenes = 0;
    let mut unknown = Vec::new();
    let mut column = None;
    for line in text.lines() {
        let cells: Vec<&str> = line.trim().trim_matches('|').split('|').collect();
        if !line.starts_with('|') {
            column = None;
            continue;
        }
        if let Some(i) = cells.iter().position(|c| c.trim() == "Scene") {
            column = Some(i);
            continue;
        }
        let Some(cell) = column.and_then(|i| cells.get(i)) else {
            continue;
        };
        for name in backticked(cell) {
            scenes += 1;
            if !BUILTIN.iter().any(|b| b.name == name) {
                unknown.push(name.to_string());
            }
        }
    }
    assert!(
        unknown.is_empty(),
        "docs/papers.md names scenes that are not built in: {unknown:?}"
    );
    assert!(
        scenes >= 20,
        "only {scenes} scenes found in the Scene columns"
    );
}

#[test]
fn the_checks_catch_a_missing_test_and_a_missing_file() {
    let source = "#[test]\nfn a_real_test() {}\n    pub(crate) fn helper(x: f64) {}\n";
    assert!(defines_fn(source, "a_real_test"));
    assert!(defines_fn(source, "helper"));
    assert!(!defines_fn(source, "a_real"));
    assert!(!defines_fn(source, "a_missing_test"));
    assert!(is_path("solver/src/lib.rs::x"));
    assert!(!is_path("[solver] dynamics"));
}
