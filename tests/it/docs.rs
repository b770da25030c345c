//! The docs stay true: every path ARCHITECTURE.md and docs/internals.md name exists,
//! ARCHITECTURE.md stays one page, and the README
//! opens with the two commands CI runs.

use std::path::Path;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// Backticked tokens that look like repository paths (contain a `/` or end in
/// `.md`/`.rs`/`.toml`), with any `::item` suffix dropped.
fn named_paths(text: &str) -> Vec<String> {
    text.split('`')
        .skip(1)
        .step_by(2)
        .filter(|t| !t.contains(' ') && !t.contains("::"))
        .filter(|t| {
            t.contains('/') || t.ends_with(".md") || t.ends_with(".rs") || t.ends_with(".toml")
        })
        .map(|t| t.to_string())
        .collect()
}

fn assert_named_paths_exist(doc: &str) -> usize {
    let text = std::fs::read_to_string(root().join(doc)).unwrap();
    let paths = named_paths(&text);
    assert!(
        paths.len() >= 10,
        "expected {doc} to name its files: {paths:?}"
    );
    let missing: Vec<&String> = paths.iter().filter(|p| !root().join(p).exists()).collect();
    assert!(missing.is_empty(), "{doc} names missing paths: {missing:?}");
    text.lines().count()
}

#[test]
fn every_path_in_architecture_md_exists() {
    let lines = assert_named_paths_exist("ARCHITECTURE.md");
    // One page: the long form belongs in docs/internals.md.
    assert!(
        lines <= 80,
        "ARCHITECTURE.md is {lines} lines, not one page"
    );
}

#[test]
fn every_path_in_the_internals_exists() {
    assert_named_paths_exist("docs/internals.md");
}

#[test]
fn readme_opens_with_the_main_command_and_the_ci_test_command() {
    let readme = std::fs::read_to_string(root().join("README.md")).unwrap();
    let block = readme
        .split("```sh")
        .nth(1)
        .expect("a ```sh block")
        .split("```")
        .next()
        .unwrap();
    let commands: Vec<&str> = block
        .lines()
        .map(|l| l.split('#').next().unwrap().trim())
        .filter(|l| !l.is_empty())
        .collect();
    assert_eq!(commands.len(), 2, "{commands:?}");
    assert_eq!(commands[0], "cargo run --release");
    let ci = std::fs::read_to_string(root().join(".ci/run")).unwrap();
    assert!(
        ci.lines().any(|l| l.trim() == commands[1]),
        "`.ci/run` must run the README's test command `{}`",
        commands[1]
    );
}

/// What a newcomer needs is in the README: the requirements, how to grant
/// real-time rights (or what changes without them), every exit status the
/// binary uses, and a glossary with the three papers.
#[test]
fn the_readme_says_what_a_newcomer_needs() {
    let readme = std::fs::read_to_string(root().join("README.md")).unwrap();
    let cargo = std::fs::read_to_string(root().join("Cargo.toml")).unwrap();
    for needed in [
        "## Requirements",
        "**Linux**",
        "rtprio",
        "memlock",
        "**Without them**",
        "### Exit status",
        "## Glossary",
        "**Augmented Lagrangian**",
        "**Eq. 7**",
        "**Newton-KKT**",
        "**Witness**",
        "**Least astonishment**",
        "**Virtual coupling**",
        "Donald D. Nelson and Elaine Cohen, \"Interactive Mechanical Design Variation for\n  Haptics and CAD\"",
        "Min-Hyung Choi and James F. Cremer, \"Geometrically-Aware Interactive Object\n  Manipulation\"",
        "Michael Gösele and Wolfgang Stuerzlinger, \"Semantic Constraints for Scene\n  Manipulation\"",
    ] {
        assert!(readme.contains(needed), "README lacks {needed:?}");
    }
    // The Rust version and edition are the workspace's own.
    let field = |key: &str| {
        cargo
            .lines()
            .find_map(|l| l.strip_prefix(&format!("{key} = \"")))
            .and_then(|v| v.strip_suffix('"'))
            .unwrap()
            .to_string()
    };
    assert!(readme.contains(&format!("**Rust {} or newer**", field("rust-version"))));
    assert!(readme.contains(&format!("edition {}", field("edition"))));
    // The exit-status table lists exactly the statuses the binary uses.
    let table: Vec<u8> = readme
        .split("### Exit status")
        .nth(1)
        .unwrap()
        .lines()
        .filter_map(|l| l.strip_prefix("| "))
        .filter_map(|l| l.split(' ').next()?.parse().ok())
        .collect();
    assert_eq!(
        table,
        [
            0,
            1,
            2,
            haptloop::cli::EXIT_FAILED_TICKS,
            haptloop::cli::EXIT_SIGNAL
        ]
    );
}

/// The scene reference's contact example is a complete scene: it loads,
/// `check` finds nothing, and a run pushes the box (contact rows active,
/// penetration kept within the tolerance).
#[test]
fn the_contact_example_in_the_scene_reference_runs() {
    let doc = std::fs::read_to_string(root().join("docs/scene-format.md")).unwrap();
    let example = doc
        .split("## A complete contact example")
        .nth(1)
        .unwrap()
        .split("```toml\n")
        .nth(1)
        .unwrap()
        .split("```")
        .next()
        .unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("push-a-box.toml");
    std::fs::write(&path, example).unwrap();
    let haptloop = || std::process::Command::new(env!("CARGO_BIN_EXE_haptloop"));
    let check = haptloop().arg("check").arg(&path).output().unwrap();
    assert_eq!(
        check.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&check.stderr)
    );
    let out = dir.path().join("run");
    let run = haptloop()
        .args([
            "run",
            "--deterministic",
            "--seconds",
            "2.5",
            "--quiet",
            "--out",
        ])
        .arg(&out)
        .arg(&path)
        .output()
        .unwrap();
    assert_eq!(run.status.code(), Some(0));
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["contact"]["verdict"], "kept", "{summary}");
    assert!(summary["contact"]["max_active"].as_u64().unwrap() > 0);
    // The box moved along x with the hand: its last pose in bodies.csv.
    let bodies = std::fs::read_to_string(out.join("bodies.csv")).unwrap();
    let head: Vec<&str> = bodies.lines().next().unwrap().split(',').collect();
    let col = |n: &str| head.iter().position(|h| *h == n).unwrap();
    let last_x = bodies
        .lines()
        .rev()
        .find(|l| l.split(',').nth(col("body")) == Some("box"))
        .map(|l| {
            l.split(',')
                .nth(col("x_m"))
                .unwrap()
                .parse::<f64>()
                .unwrap()
        })
        .unwrap();
    assert!(last_x > 0.03, "the box ended at x = {last_x} m");
}

/// The device table of the scene reference holds the models' own figures:
/// peak and continuous force, and the workspace box's half extents.
#[test]
fn the_device_table_is_the_models_figures() {
    let doc = std::fs::read_to_string(root().join("docs/scene-format.md")).unwrap();
    for name in haptloop_devices::KNOWN_MODELS {
        let m = haptloop_devices::PhantomModel::by_name(name).unwrap();
        let row = doc
            .lines()
            .find(|l| l.starts_with(&format!("| `{name}` |")))
            .unwrap_or_else(|| panic!("no row for {name}"));
        let cells: Vec<&str> = row.split('|').map(str::trim).collect();
        assert_eq!(cells[3], format!("{} N", m.peak_force_n), "{row}");
        assert_eq!(cells[4], format!("{} N", m.continuous_force_n), "{row}");
        let [x, y, z] = m.workspace_half_extent_m;
        assert!(
            cells[5].starts_with(&format!("±{x} × ±{y} × ±{z} m")),
            "{row}"
        );
    }
    // The virtual device's row: its own defaults.
    let v = haptloop_devices::VirtualParams::default();
    let row = doc
        .lines()
        .find(|l| l.starts_with("| `virtual` |"))
        .expect("no row for virtual");
    let cells: Vec<&str> = row.split('|').map(str::trim).collect();
    assert_eq!(cells[3], format!("{} N", v.peak_force_n), "{row}");
    assert!(
        cells[4].starts_with(&format!("{} N", v.peak_force_n)),
        "{row}"
    );
    let h = v.workspace_half_extent_m;
    assert!(
        cells[5].starts_with(&format!("±{h} × ±{h} × ±{h} m")),
        "{row}"
    );
}
