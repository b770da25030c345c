//! Values that were silently ignored and messages that did not say what or
//! where (issue 21, items 11 and 12, the solver and scene side). The
//! refusals at a file's line and column are in `tests/data/bad-scenes/`
//! (`scenes.rs` checks each); these are the cases that need more than a
//! file: command-line flags, an objective's pull, the built-in files.

use haptloop::scenes::resolve;
use haptloop_solver::scene::{self, SceneError};
use haptloop_solver::{BodySpec, ModelBuilder, ObjectiveSpec, Objectives, ObstacleSpec};

fn four_bar() -> scene::LoadedScene {
    let text = haptloop::scenes::BUILTIN
        .iter()
        .find(|b| b.name == "four-bar")
        .unwrap()
        .text;
    scene::parse("four-bar.toml", text, None).unwrap()
}

fn flags(free: &[&str], objectives: &[&str]) -> SceneError {
    let free: Vec<String> = free.iter().map(|s| s.to_string()).collect();
    let objectives: Vec<String> = objectives.iter().map(|s| s.to_string()).collect();
    match four_bar().with_flags(&free, &objectives) {
        Err(e) => e,
        Ok(f) => haptloop::scenes::check_loaded(f.loaded.clone())
            .map(|_| ())
            .map_err(|e| f.attribute(e))
            .expect_err("the flags loaded"),
    }
}

/// `--objective` errors pointed at column 1 whatever was wrong; now at the
/// value or key within the flag. Names that are not ASCII letters are names
/// (they gave "missing comma"), and a key given twice is named.
#[test]
fn objective_flag_errors_point_into_the_flag() {
    let value = "dexterity:chain=[ground,crank],point=[0.1,0.0]";
    let e = flags(&[], &[value]);
    assert_eq!(e.file, "--objective");
    assert_eq!(e.column, value.find("[0.1").unwrap() + 1, "{e}");
    assert!(e.message.contains("invalid length 2"), "{e}");

    let value = "dexterity:chain=[ground,crank,bäse→2]";
    let e = flags(&[], &[value]);
    assert!(e.message.contains("names unknown body `bäse→2`"), "{e}");
    assert_eq!(
        e.column,
        value[..value.find("bäse").unwrap()].chars().count() + 1,
        "{e}"
    );

    let value = "dexterity:chain=[ground,crank],weight=2,chain=[ground]";
    let e = flags(&[], &[value]);
    assert_eq!(e.message, "key `chain` is given twice");
    assert_eq!(e.column, value.rfind("chain").unwrap() + 1, "{e}");
}

/// `--free X` twice was one `--free X`; a variable the file already frees
/// was silently freed "again".
#[test]
fn a_design_variable_freed_twice_is_refused() {
    let e = flags(&["crank-pivot.anchor_i", "crank-pivot.anchor_i"], &[]);
    assert_eq!(e.file, "--free");
    assert!(e.message.contains("is given twice"), "{e}");
    let design = haptloop::scenes::BUILTIN
        .iter()
        .find(|b| b.name == "four-bar-design")
        .unwrap();
    let loaded = scene::parse("four-bar-design.toml", design.text, None).unwrap();
    let e = loaded
        .with_flags(&["coupler-rocker.anchor_j".to_string()], &[])
        .err()
        .unwrap();
    assert!(e.message.contains("already free in the scene file"), "{e}");
}

/// An obstacle's activation distance of 1 km switched it off (every point
/// nearer than its floor, D/1000 = 1 m, where the barrier is flat): the
/// same gradient as no obstacle. Now a point 10 cm from the obstacle is
/// pushed straight away from it at D = 1 km as at D = 0.4 m, and the
/// analytic gradient matches central finite differences.
#[test]
fn a_far_reaching_obstacle_still_pushes() {
    let grad = |d: f64| {
        let mut b = ModelBuilder::new();
        b.body(BodySpec::new("a").at([0.1, 0.0, 0.0]));
        let spec = ObjectiveSpec::Obstacle {
            name: None,
            weight: 1.0,
            points: vec![("a".into(), [0.0; 3])],
            obstacle: ObstacleSpec::World([0.0; 3]),
            distance_m: d,
        };
        let m = b.build().unwrap();
        let o = std::sync::Arc::new(Objectives::compile(&[spec], &m).unwrap());
        let q = m.q0().to_vec();
        let mut ev = o.evaluation(&m);
        let mut g = vec![0.0; m.n_coords()];
        let f = ev.gradient(&m, &q, &mut g).unwrap();
        // Central differences of F along x.
        let h = 1e-7;
        let value = |x: f64| {
            let mut qq = q.clone();
            qq[0] = x;
            let mut gg = vec![0.0; m.n_coords()];
            o.evaluation(&m).gradient(&m, &qq, &mut gg).unwrap()
        };
        let fd = (value(q[0] + h) - value(q[0] - h)) / (2.0 * h);
        (f, g, fd)
    };
    for d in [0.4, 1000.0] {
        let (f, g, fd) = grad(d);
        assert!(f > 0.0, "D = {d}: F = {f}");
        // Pushed away: F falls as x grows (the point is at +x).
        assert!(g[0] < 0.0, "D = {d}: ∂F/∂x = {}", g[0]);
        assert!(g[1].abs() + g[2].abs() <= 1e-12 * g[0].abs(), "{g:?}");
        assert!(
            (g[0] - fd).abs() <= 1e-5 * g[0].abs(),
            "D = {d}: analytic {}, finite difference {fd}",
            g[0]
        );
    }
}

/// `scenes/four-bar-design.toml` frees the rocker's far anchor; its
/// description said the crank's length was free.
#[test]
fn the_design_scene_describes_the_link_it_frees() {
    let s = resolve("four-bar-design").unwrap();
    let m = &s.compiled.model;
    let freed: Vec<String> = m
        .layout()
        .design_vars()
        .iter()
        .map(|d| d.name.clone())
        .collect();
    assert_eq!(freed, ["coupler-rocker.anchor_j"]);
    // Its joint's body j is the rocker.
    assert!(s.compiled.description.contains("rocker's length free"));
    assert!(
        !s.compiled.description.contains("crank"),
        "{}",
        s.compiled.description
    );
}
