//! Scene files: the malformed corpus fails at the expected line and column,
//! the built-in scenes compile, and the mechanism scenes are exactly the
//! solver's builders.

use haptloop::scenes::{BUILTIN, resolve};
use haptloop_solver::mechanisms;
use std::path::Path;

/// Each file in `tests/data/bad-scenes/` starts with
/// `# expect: LINE:COLUMN text`: loading it must fail at exactly that place
/// with a message containing `text`.
#[test]
fn every_malformed_scene_fails_at_the_expected_place() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/bad-scenes");
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    files.sort();
    assert!(
        files.len() >= 25,
        "the corpus has only {} files",
        files.len()
    );
    let mut failures = Vec::new();
    for path in &files {
        let text = std::fs::read_to_string(path).unwrap();
        let expect = text
            .lines()
            .next()
            .unwrap()
            .strip_prefix("# expect: ")
            .expect("expect header");
        let (place, want) = expect.split_once(' ').unwrap_or((expect, ""));
        let (line, col) = place.split_once(':').unwrap();
        let (line, col): (usize, usize) = (line.parse().unwrap(), col.parse().unwrap());
        let arg = path.to_str().unwrap();
        match resolve(arg) {
            Ok(_) => failures.push(format!("{arg}: loaded, but should fail")),
            Err(e) => {
                if (e.line, e.column) != (line, col) || !e.message.contains(want) || e.file != arg {
                    failures.push(format!("{arg}: expected {line}:{col} `{want}`, got {e}"));
                }
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
}

#[test]
fn every_builtin_scene_compiles_with_a_device_per_finger() {
    for b in BUILTIN {
        let s = resolve(b.name).unwrap_or_else(|e| panic!("{e}"));
        let c = &s.compiled;
        assert!(!c.description.is_empty(), "{} needs a description", b.name);
        assert_eq!(c.fingers.len(), c.devices.len(), "{}", b.name);
        assert_eq!(c.model.fingers().len(), c.fingers.len());
        let on_disk = std::fs::read_to_string(
            Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("scenes/{}.toml", b.name)),
        )
        .unwrap();
        assert_eq!(on_disk, b.text, "the embedded copy of {} is stale", b.name);
    }
}

#[test]
fn mechanism_scenes_are_exactly_the_solver_builders() {
    for (name, model) in [
        ("four-bar", mechanisms::four_bar()),
        ("stewart", mechanisms::stewart()),
        ("sphere-toy", mechanisms::sphere_toy()),
        (
            "cluttered",
            mechanisms::cluttered_builder(100).build().unwrap(),
        ),
        (
            "sphere-toy-400",
            mechanisms::sphere_toy_sized(20, 20).build().unwrap(),
        ),
        ("piston", mechanisms::piston()),
        ("stewart-3rsu", mechanisms::stewart_3rsu()),
        ("four-bar-cardan", mechanisms::four_bar_cardan()),
        (
            "quarter-torus",
            mechanisms::quarter_torus_builder(mechanisms::TORUS_GAP_M)
                .build()
                .unwrap(),
        ),
    ] {
        let scene = resolve(name).unwrap();
        let m = &scene.compiled.model;
        assert_eq!(
            (m.n_coords(), m.n_rows()),
            (model.n_coords(), model.n_rows()),
            "{name}"
        );
        assert_eq!(m.q0(), model.q0(), "{name}: q0 differs");
        for (a, b) in m.bodies().iter().zip(model.bodies()) {
            assert_eq!(
                (&a.name, a.fixed, a.mass_kg, a.inertia_kg_m2),
                (&b.name, b.fixed, b.mass_kg, b.inertia_kg_m2),
                "{name}"
            );
        }
        assert_eq!(
            m.gravity_m_s2() == model.gravity_m_s2(),
            !name.starts_with("stewart"),
            "only the Stewart scenes turn gravity off"
        );
        for (a, b) in m.bodies().iter().zip(model.bodies()) {
            assert_eq!(
                (&a.shape, a.friction),
                (&b.shape, b.friction),
                "{name}: {}",
                a.name
            );
        }
        let (mut a, mut b) = (m.evaluation(), model.evaluation());
        a.evaluate(m, m.q0(), &m.initial_targets()).unwrap();
        b.evaluate(&model, model.q0(), &model.initial_targets())
            .unwrap();
        assert_eq!(a.values(), b.values(), "{name}: C differs");
        assert_eq!(
            a.jacobian().values(),
            b.jacobian().values(),
            "{name}: C_q differs"
        );
    }
}

#[test]
fn the_peaucellier_scene_is_assembled_and_q_lies_on_its_line() {
    let scene = resolve("peaucellier").unwrap();
    let m = &scene.compiled.model;
    let mut e = m.evaluation();
    e.evaluate(m, m.q0(), &m.initial_targets()).unwrap();
    let worst = e.values().iter().fold(0.0f64, |a, v| a.max(v.abs()));
    assert!(worst < 1e-12, "initial violation {worst:e}");
    let q = m
        .finger_point(m.q0(), haptloop_solver::FingerId(0))
        .unwrap();
    // x = (a² − b²)/(2r) = (0.01 − 0.0016)/0.1.
    assert!((q.x - 0.084).abs() < 1e-12, "Q at {q:?}");
}

/// Inputs that once crashed something (the fuzz target's crashes land here,
/// see `fuzz/run.sh`, beside hand-made ones for past panics): each loads or
/// fails with a located error whose text prints without panicking and without
/// raw control characters.
#[test]
fn every_fuzz_regression_loads_or_fails_cleanly() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/fuzz-regressions");
    let mut n = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        let bytes = std::fs::read(&path).unwrap();
        let Ok(text) = std::str::from_utf8(&bytes) else {
            continue;
        };
        n += 1;
        let loaded = haptloop_solver::scene::parse("fuzz.toml", text, None)
            .and_then(haptloop::scenes::check_loaded);
        if let Err(e) = loaded {
            let shown = e.to_string();
            assert!(
                !shown.chars().any(|c| c.is_control() && c != '\n'),
                "{}: {shown:?}",
                path.display()
            );
            assert!(shown.starts_with(&format!("fuzz.toml:{}:{}:", e.line, e.column)));
            assert!(shown.lines().nth(1).is_none_or(|l| l.chars().count() < 120));
        }
    }
    assert!(n >= 3, "only {n} regression inputs");
}
