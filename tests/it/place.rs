//! `haptloop place` end to end on the Stewart platform: the written scene
//! loads, holds the platform at its goal (read back from the file, compared
//! with the goal given) and is assembled (its joint rows evaluated at the
//! file's configuration, independently of the placement that produced it);
//! a goal past the stroke limits exits 3 with an assembled file; bad input
//! is named.

use haptloop_solver::Evaluation;
use std::path::Path;
use std::process::{Command, Output};

fn place(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_haptloop"))
        .arg("place")
        .args(args)
        .output()
        .unwrap()
}

fn text(o: &Output) -> String {
    format!(
        "status {:?}\nstdout:\n{}\nstderr:\n{}",
        o.status.code(),
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

/// The platform's position in the written scene, and the largest joint-row
/// residual of its configuration.
fn read_back(path: &Path) -> ([f64; 3], f64) {
    let loaded = haptloop_solver::scene::load(path).unwrap_or_else(|e| panic!("{e}"));
    let compiled = loaded.compile().unwrap_or_else(|e| panic!("{e}"));
    let m = &compiled.joints_only;
    let id = m.body_id("platform").unwrap();
    let p = m.body_position(m.q0(), id).unwrap();
    let mut e = Evaluation::new(m);
    e.evaluate_values(m, m.q0(), &[]).unwrap();
    // Equality rows vanish; inequality rows (stroke limits) only must not
    // be violated.
    let v = e.values();
    let eq = v[m.equality_rows()]
        .iter()
        .fold(0.0_f64, |w, v| w.max(v.abs()));
    let ineq = v[m.inequality_rows()]
        .iter()
        .fold(0.0_f64, |w, v| w.max(-v));
    let worst = eq.max(ineq);
    (p.into(), worst)
}

#[test]
fn a_placed_scene_holds_its_goal_and_stays_assembled() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("placed.toml");
    let o = place(&[
        "stewart",
        "--body",
        "platform",
        "--goal",
        "0.01,0.005,0.14",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    assert!(text(&o).contains("placed at the goal"), "{}", text(&o));
    let (p, worst) = read_back(&out);
    for (got, want) in p.iter().zip([0.01, 0.005, 0.14]) {
        assert!((got - want).abs() < 1e-9, "{p:?}");
    }
    assert!(worst < 1e-9, "joint rows {worst}");

    // 8 cm up: past the ±4 cm strokes. Exit 3, the file at the last
    // converged subgoal, still assembled, the platform partway up.
    let o = place(&[
        "stewart",
        "--body",
        "platform",
        "--goal",
        "0,0,0.2",
        "--mode",
        "solve",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(3), "{}", text(&o));
    assert!(text(&o).contains("NOT REACHED"), "{}", text(&o));
    let (p, worst) = read_back(&out);
    assert!(p[2] > 0.12 && p[2] < 0.2, "{p:?}");
    assert!(worst < 1e-9, "joint rows {worst}");
}

#[test]
fn a_wrong_body_or_goal_is_named() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("p.toml");
    let out = out.to_str().unwrap();
    let o = place(&[
        "stewart", "--body", "base", "--goal", "0,0,0.13", "--out", out,
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    assert!(
        text(&o).contains("body `base`") && text(&o).contains("platform"),
        "{}",
        text(&o)
    );
    let o = place(&[
        "stewart", "--body", "platform", "--goal", "0,0.13", "--out", out,
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(text(&o).contains("expected 3 (x,y,z)"), "{}", text(&o));
    assert!(!Path::new(out).exists());
}
