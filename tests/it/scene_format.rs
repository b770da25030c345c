//! `docs/scene-format.md` and the loader cannot drift apart: for every section
//! the keys the reference lists are exactly the keys the loader accepts, and
//! every list of allowed values is exactly the loader's. The loader's side is
//! read from the loader itself: an unknown key (or value) injected into a valid
//! scene makes it answer with the list it expects.
//!
//! To document a new section, give it a `##`/`###` heading whose first
//! backticked word names it, and add a `(heading, injection)` case below.

use haptloop::scenes::{BUILTIN, check_loaded};
use haptloop_solver::scene;
use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// (section or values name) → the first-column entries of its table.
fn documented() -> BTreeMap<String, BTreeSet<String>> {
    let text =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/scene-format.md"))
            .unwrap();
    let mut out: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    let mut current: Option<String> = None;
    let mut in_table = false;
    let first_ticked = |l: &str| l.split('`').nth(1).map(str::to_owned);
    for line in text.lines() {
        if line.starts_with("## ") || line.starts_with("### ") {
            current = if line.contains("Top-level") {
                Some("top".into())
            } else {
                first_ticked(line)
            };
            in_table = false;
        } else if line.ends_with("values:") {
            // "Joint `kind` values:" → a table of values named "kind".
            current = first_ticked(line).map(|k| format!("{k} values"));
            in_table = false;
        } else if let Some(row) = line.strip_prefix("| `") {
            if let Some(name) = &current
                && !in_table
            {
                let key = row.split('`').next().unwrap().to_owned();
                out.entry(name.clone()).or_default().insert(key);
            }
        } else if !line.starts_with('|') && out.contains_key(current.as_deref().unwrap_or("")) {
            in_table = true; // only the first table after a heading counts
        }
    }
    out
}

/// The words the loader says it expected when given `text`.
fn expected_by_loader(text: &str) -> BTreeSet<String> {
    let err = match scene::parse("probe.toml", text, None) {
        Err(e) => e.message,
        Ok(loaded) => match check_loaded(loaded) {
            Err(e) => e.message,
            Ok(_) => panic!("the probe loaded:\n{text}"),
        },
    };
    // Two plain-list forms: the device crate's and toml's for enum variants.
    for marker in ["known models: ", "available keys: "] {
        if let Some(list) = err.split(marker).nth(1) {
            return list.split(", ").map(str::to_owned).collect();
        }
    }
    let after = err
        .split("expected")
        .nth(1)
        .unwrap_or_else(|| panic!("no list in `{err}`"));
    after
        .split('`')
        .skip(1)
        .step_by(2)
        .map(str::to_owned)
        .collect()
}

#[test]
fn the_reference_lists_exactly_the_keys_and_values_the_loader_accepts() {
    let base = BUILTIN.iter().find(|b| b.name == "four-bar").unwrap().text;
    let after = |anchor: &str, insert: &str| {
        assert!(base.contains(anchor), "{anchor}");
        base.replacen(anchor, &format!("{anchor}{insert}"), 1)
    };
    let replace = |from: &str, to: &str| {
        assert!(base.contains(from), "{from}");
        base.replacen(from, to, 1)
    };
    let hand = "hand = { circle = {";
    let cases: Vec<(&str, String)> = vec![
        ("[scene]", after("[scene]\n", "zz_unknown = 1\n")),
        ("[solver]", after("[solver]\n", "zz_unknown = 1\n")),
        ("[[body]]", after("[[body]]\n", "zz_unknown = 1\n")),
        ("[[joint]]", after("[[joint]]\n", "zz_unknown = 1\n")),
        ("[[device]]", after("[[device]]\n", "zz_unknown = 1\n")),
        ("[[finger]]", after("[[finger]]\n", "zz_unknown = 1\n")),
        (
            "[[body.offer]]",
            format!("{base}\n[[body.offer]]\nzz_unknown = 1\n"),
        ),
        ("top", format!("{base}\n[zz_unknown]\n")),
        (
            "[semantic]",
            format!("{base}\n[semantic]\nzz_unknown = 1\n"),
        ),
        (
            "holds",
            after("[[finger]]\n", "holds = [{ zz_unknown = 1 }]\n"),
        ),
        ("hand", replace(hand, "hand = { zz_unknown = 1, circle = {")),
        (
            "circle",
            replace(hand, "hand = { circle = { zz_unknown = 1,"),
        ),
        ("line", {
            let line = base.lines().find(|l| l.starts_with(hand)).unwrap();
            base.replacen(
                line,
                "hand = { line = { zz_unknown = 1, to = [0.0, 0.0, 0.0], seconds = 1.0 } }",
                1,
            )
        }),
        ("shape", after("[[body]]\n", "shape = { zz_unknown = 1 }\n")),
        (
            "flexible",
            after("[[body]]\n", "flexible = { zz_unknown = 1 }\n"),
        ),
        (
            "capsule",
            after(
                "[[body]]\n",
                "shape = { capsule = { zz_unknown = 1, half_height = 0.1, radius = 0.1 } }\n",
            ),
        ),
        (
            "kind values",
            replace("kind = \"revolute\"", "kind = \"zz_unknown\""),
        ),
        (
            "surface",
            after("[[joint]]\n", "surface = { zz_unknown = 1 }\n"),
        ),
        (
            "type values",
            after("[[joint]]\n", "surface = { type = \"zz_unknown\" }\n"),
        ),
        (
            "free values",
            after("[[joint]]\n", "free = [\"zz_unknown\"]\n"),
        ),
        (
            "[[objective]]",
            format!("{base}\n[[objective]]\nkind = \"finger\"\nzz_unknown = 1\n"),
        ),
        ("[[gear]]", format!("{base}\n[[gear]]\nzz_unknown = 1\n")),
        (
            "[[design_flag]]",
            format!("{base}\n[[design_flag]]\nzz_unknown = 1\n"),
        ),
        (
            "[[schedule]]",
            format!("{base}\n[[schedule]]\nzz_unknown = 1\n"),
        ),
        (
            "mode values",
            format!("{base}\n[[schedule]]\nat = 1.0\nmode = \"zz_unknown\"\n"),
        ),
        (
            "[[gear]] kind values",
            format!("{base}\n[[gear]]\nkind = \"zz_unknown\"\n"),
        ),
        (
            "[[objective]] kind values",
            format!("{base}\n[[objective]]\nkind = \"zz_unknown\"\n"),
        ),
        (
            "grasp values",
            replace("grasp = \"point\"", "grasp = \"zz_unknown\""),
        ),
        (
            "model values",
            replace("model = \"phantom-premium-1.5\"", "model = \"zz_unknown\""),
        ),
    ];
    let docs = documented();
    let mut drift = Vec::new();
    for (section, probe) in &cases {
        let loader = expected_by_loader(probe);
        let documented = docs.get(*section).cloned().unwrap_or_default();
        if loader != documented {
            drift.push(format!(
                "{section}: loader accepts {loader:?}, docs/scene-format.md lists {documented:?}"
            ));
        }
    }
    assert!(drift.is_empty(), "{}", drift.join("\n"));
    // Every documented section was probed.
    let probed: BTreeSet<&str> = cases.iter().map(|(s, _)| *s).collect();
    let unprobed: Vec<&String> = docs
        .keys()
        .filter(|k| !probed.contains(k.as_str()) && k.as_str() != "[labels]")
        .collect();
    assert!(
        unprobed.is_empty(),
        "documented but not checked: {unprobed:?}"
    );
}

/// The "Limits" table of `docs/scene-format.md` lists exactly the loader's
/// limits (`scene::limits::LIMITS`), with their values.
#[test]
fn the_reference_lists_exactly_the_loader_limits() {
    let text =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/scene-format.md"))
            .unwrap();
    let section = text
        .split("\n## Limits\n")
        .nth(1)
        .expect("a `## Limits` section");
    let documented: BTreeMap<String, f64> = section
        .lines()
        .take_while(|l| !l.starts_with("## "))
        .filter_map(|l| l.strip_prefix("| `"))
        .map(|row| {
            let cells: Vec<&str> = row.split('|').collect();
            let name = cells[0].trim().trim_end_matches('`').to_owned();
            let value: f64 = cells[1].trim().parse().unwrap_or_else(|_| panic!("{row}"));
            (name, value)
        })
        .collect();
    let code: BTreeMap<String, f64> = scene::limits::LIMITS
        .iter()
        .map(|l| (l.name.to_owned(), l.value))
        .collect();
    assert_eq!(documented, code);
}
