//! The design scenes of issue 12: each improves its objective against the
//! same hands without the design (variables held, or the objective's weight
//! 0), keeps its joints within the tolerance it states, and keeps its design
//! variables within their bounds. Deterministic runs; the numbers asserted
//! are the objectives' own reported values.

use haptloop::report::summary::Summary;
use haptloop::scenes::{BUILTIN, Scene, check_loaded, resolve};
use haptloop::session::{self, Plan, SessionOptions, SessionOutcome};
use haptloop_rt::schedule::StopFlag;
use haptloop_solver::scene;

fn run(scene: &Scene, seconds: f64) -> (SessionOutcome, Summary) {
    let options = SessionOptions {
        seconds,
        deterministic: true,
        ..SessionOptions::default()
    };
    let plan = Plan::new(scene, &options).unwrap();
    let o = session::run(scene, plan, &StopFlag::new(), &mut |_| {}).unwrap();
    let s = Summary::of(&o);
    (o, s)
}

/// A built-in scene's text with `from` replaced by `to` (each must occur).
fn variant(name: &str, edits: &[(&str, &str)]) -> Scene {
    let mut text = BUILTIN
        .iter()
        .find(|b| b.name == name)
        .unwrap()
        .text
        .to_string();
    for (from, to) in edits {
        assert!(text.contains(from), "{name}: no `{from}`");
        text = text.replace(from, to);
    }
    check_loaded(scene::parse(&format!("{name}-variant.toml"), &text, None).unwrap()).unwrap()
}

/// Every tick within the stated tolerance, none failed, every design
/// component within the bounds the scene gives it (pinned ones where they
/// are pinned, to the initial assembly's round-off); `expect` lists
/// components that must have bounds.
fn sound(scene: &Scene, s: &Summary, expect: &[&str]) {
    let name = &scene.compiled.name;
    let tol = s.violation.tolerance.unwrap();
    assert!(
        s.violation.max <= tol && s.safety.solver_failures == 0,
        "{name}: violation {:e} (tolerance {tol:e}), {} failed ticks",
        s.violation.max,
        s.safety.solver_failures
    );
    let mut bounded = Vec::new();
    for d in scene.compiled.model.layout().design_vars() {
        let Some(b) = d.bounds else { continue };
        for (k, &[lo, hi]) in b.iter().take(d.width).enumerate() {
            let var = d.component_name(k);
            let f = &s.design[&var];
            assert!(
                f.min >= lo - 1e-12 && f.max <= hi + 1e-12,
                "{name}: {var} left [{lo}, {hi}]: {f:?}"
            );
            if lo == hi {
                // Exactly, to the initial assembly's round-off.
                assert!(
                    (f.min - lo).abs() < 1e-15 && (f.max - lo).abs() < 1e-15 && f.end == lo,
                    "{name}: {var} pinned at {lo}: {f:?}"
                );
            }
            bounded.push(var);
        }
    }
    for e in expect {
        assert!(bounded.iter().any(|v| v == e), "{name}: {e} is not bounded");
    }
}

/// Fig. 14: with the rocker's length free, the coupler follows the hand's
/// circle: the RMS tracking error falls from 3.5 mm (the rigid four-bar,
/// which cannot follow the circle's ±1 cm across its path) below 1 mm.
#[test]
fn four_bar_design_follows_the_hand_the_rigid_linkage_cannot() {
    let scene = resolve("four-bar-design").unwrap();
    let (_, design) = run(&scene, 4.0);
    let fixed = variant(
        "four-bar-design",
        &[
            ("free = [\"anchor_j\"]\n", ""),
            ("bounds = [[0.0, 0.0, 0.02], [0.0, 0.0, 0.07]]\n", ""),
        ],
    );
    let (_, rigid) = run(&fixed, 4.0);
    assert!(rigid.design.is_empty());
    sound(
        &scene,
        &design,
        &[
            "coupler-rocker.anchor_j.x",
            "coupler-rocker.anchor_j.y",
            "coupler-rocker.anchor_j.z",
        ],
    );
    let (d, r) = (design.tracking_m.rms, rigid.tracking_m.rms);
    assert!(
        r > 3e-3 && d < 1e-3 && d < 0.3 * r,
        "tracking RMS {d:e} with the design, {r:e} without"
    );
    // The rocker's length did move: by centimetres over the circle.
    let z = &design.design["coupler-rocker.anchor_j.z"];
    assert!(z.max - z.min > 0.02, "{z:?}");
}

/// Fig. 10: Q's distance from the line x = 9 cm falls from the fixed
/// design's 6 mm to under 1 mm RMS (last 2 s) while the hand swings the
/// linkage.
#[test]
fn peaucellier_design_keeps_q_on_the_new_line() {
    let scene = resolve("peaucellier-design").unwrap();
    let (o, design) = run(&scene, 8.0);
    sound(
        &scene,
        &design,
        &["O2.anchor_i.x", "O2.anchor_i.y", "P-crank.anchor_i.z"],
    );
    let q = o
        .recorder
        .design_names
        .iter()
        .position(|n| n == "objective_Q-on-line")
        .unwrap();
    let late: Vec<f64> = o.recorder.design_series[q]
        .points
        .iter()
        .filter(|p| p.0 > 6.0)
        .map(|p| p.1)
        .collect();
    let rms = (late.iter().map(|v| v * v).sum::<f64>() / late.len() as f64).sqrt();
    let held = variant(
        "peaucellier-design",
        &[
            ("free = [\"anchor_i\"]\n", ""),
            ("bounds = [[0.03, 0.0, 0.0], [0.07, 0.0, 0.0]]\n", ""),
            ("bounds = [[0.0, 0.0, 0.005], [0.0, 0.0, 0.045]]\n", ""),
        ],
    );
    let (_, fixed) = run(&held, 8.0);
    let f = &fixed.objectives["Q-on-line"].value;
    assert!(
        (f.start - 6e-3).abs() < 1e-9 && f.min > 5.9e-3,
        "fixed design: {f:?}"
    );
    assert!(
        rms < 1e-3 && late.len() > 100,
        "design: Q off the line by {rms:e} RMS"
    );
    assert_eq!(design.objectives["Q-on-line"].value.start, f.start);
}

/// Fig. 15: the feet slide in under the rising platform; the strokes' RMS
/// distance from their middles ends lower than with the feet moved only by
/// the joints' pull (objective weight 0).
#[test]
fn stewart_feet_keep_the_strokes_from_their_limits() {
    let scene = resolve("stewart-feet").unwrap();
    let (_, design) = run(&scene, 6.0);
    let (_, idle) = run(
        &variant("stewart-feet", &[("weight = 0.5\n", "weight = 0.0\n")]),
        6.0,
    );
    let feet: Vec<String> = (0..6)
        .flat_map(|k| ["x", "y", "z"].map(|a| format!("foot{k}.position.{a}")))
        .collect();
    let feet: Vec<&str> = feet.iter().map(String::as_str).collect();
    sound(&scene, &design, &feet);
    // The feet slid: most by more than a centimetre.
    let moved = (0..6)
        .filter(|k| {
            let d = &design.design[&format!("foot{k}.position.y")];
            (d.end - d.start).abs() > 0.01
        })
        .count();
    assert!(moved >= 4, "only {moved} feet moved more than 1 cm");
    let (with, without) = (
        &design.objectives["strokes"].value,
        &idle.objectives["strokes"].value,
    );
    assert!(
        with.end < 0.9 && without.end > 0.95 && with.end < without.end - 0.08,
        "strokes RMS at the end: {} with the objective, {} without",
        with.end,
        without.end
    );
}

/// App. C: Eq. 14's f at the hand falls to under half its start as the base
/// slides toward the hand; the hand point stays in the user's hand.
#[test]
fn dexterity_arm_moves_its_base_to_a_dexterous_pose() {
    let scene = resolve("dexterity-arm").unwrap();
    let (_, s) = run(&scene, 8.0);
    sound(
        &scene,
        &s,
        &["base.position.x", "base.position.y", "base.position.z"],
    );
    let f = &s.objectives["hand"].value;
    assert!(f.start > 10.0 && f.end < 0.5 * f.start, "f: {f:?}");
    assert!(f.end.is_finite() && f.max <= f.start + 1e-9);
    let x = &s.design["base.position.x"];
    assert!(x.end > 0.02, "the base did not move toward the hand: {x:?}");
    assert!(s.tracking_m.max < 1e-4, "{:?}", s.tracking_m);
}

/// Fig. 13: the chain's elbows and link middles stay 4.5 cm from the
/// bullet; without the objective the bullet passes through the middle joint.
#[test]
fn dodge_keeps_the_chain_away_from_the_bullet() {
    let scene = resolve("dodge").unwrap();
    let (_, with) = run(&scene, 5.0);
    let (_, without) = run(
        &variant("dodge", &[("weight = 0.05\n", "weight = 0.0\n")]),
        5.0,
    );
    sound(&scene, &with, &[]);
    let (a, b) = (
        &with.objectives["bullet"].value,
        &without.objectives["bullet"].value,
    );
    assert!(
        a.min > 0.045 && b.min < 0.005,
        "nearest distance {} with, {} without",
        a.min,
        b.min
    );
    assert!(
        with.tracking_m.max < 1e-4,
        "the chain's end left the hand: {:?}",
        with.tracking_m
    );
}

fn haptloop() -> std::process::Command {
    std::process::Command::new(env!("CARGO_BIN_EXE_haptloop"))
}

/// `--free` and `--objective` free a variable and add an objective without
/// editing the scene: summary.json, trace.csv and design.svg show them.
#[test]
fn design_flags_add_variables_and_objectives_to_any_scene() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    let r = haptloop()
        .args([
            "run",
            "four-bar",
            "--deterministic",
            "--seconds",
            "0.5",
            "--quiet",
        ])
        .args([
            "--free",
            "coupler-rocker.anchor_j",
            "--free",
            "ground.position",
        ])
        .args([
            "--objective",
            "dexterity:chain=[ground,crank,coupler],weight=0.01",
            "--objective",
            "joint_limit_distance:joints=[],weight=0",
        ])
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&r.stderr);
    // joint_limit_distance on a model without limits is refused, naming the flag.
    assert_eq!(r.status.code(), Some(2), "{err}");
    assert!(
        err.starts_with("--objective:1:29: objective `joint_limit_distance`"),
        "{err}"
    );
    let r = haptloop()
        .args([
            "run",
            "four-bar",
            "--deterministic",
            "--seconds",
            "0.5",
            "--quiet",
        ])
        .args([
            "--free",
            "coupler-rocker.anchor_j",
            "--free",
            "ground.position",
        ])
        .args([
            "--objective",
            "dexterity:chain=[ground,crank,coupler],weight=0.01",
        ])
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let s: Summary =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let keys: Vec<&String> = s.design.keys().collect();
    assert_eq!(
        keys,
        [
            "coupler-rocker.anchor_j.x",
            "coupler-rocker.anchor_j.y",
            "coupler-rocker.anchor_j.z",
            "ground.position.x",
            "ground.position.y",
            "ground.position.z",
        ]
    );
    let d = &s.objectives["dexterity"];
    assert_eq!((d.kind.as_str(), d.weight), ("dexterity", 0.01));
    assert!(d.value.start.is_finite() && d.value.end.is_finite());
    let trace = std::fs::read_to_string(out.join("trace.csv")).unwrap();
    let header = trace.lines().next().unwrap();
    assert!(
        header.ends_with(",violation_m,failed,ground.position.x_m,ground.position.y_m,ground.position.z_m,coupler-rocker.anchor_j.x_m,coupler-rocker.anchor_j.y_m,coupler-rocker.anchor_j.z_m,objective_dexterity"),
        "{header}"
    );
    // Every row has the columns filled (500 ticks, one finger).
    let rows: Vec<&str> = trace.lines().skip(1).collect();
    assert_eq!(rows.len(), 500);
    assert!(
        rows.iter()
            .all(|r| r.split(',').count() == 20 && !r.ends_with(','))
    );
    assert!(out.join("design.svg").exists());
}

/// A bad `--free` or `--objective` is a usage error (status 2) that names
/// the flag and what is wrong, and runs nothing.
#[test]
fn bad_design_flags_are_usage_errors_naming_the_flag() {
    let cases: [(&[&str], &str); 6] = [
        (
            &["--free", "crank-pivot.lenght"],
            "--free:1:13: unknown design variable `lenght`",
        ),
        (
            &["--free", "crank-pivot.length"],
            "--free:1:13: joint `crank-pivot` (revolute) has no design variable `length`",
        ),
        (
            &["--free", "crank.position"],
            "--free:1:1: body `crank` is not fixed",
        ),
        (
            &["--free", "nodot"],
            "--free:1:1: expected <joint>.<variable>",
        ),
        (
            &["--objective", "dexterity:chain=[ground,crank,cuopler]"],
            "--objective:1:31: objective `dexterity`: names unknown body `cuopler`",
        ),
        (
            &[
                "--objective",
                "obstacle:points=[{body=crank}],distance=0.01",
            ],
            "--objective:1:1: an obstacle objective needs `obstacle",
        ),
    ];
    for (flags, expected) in cases {
        let r = haptloop()
            .args([
                "run",
                "four-bar",
                "--deterministic",
                "--seconds",
                "0.1",
                "--no-files",
            ])
            .args(flags)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&r.stderr);
        assert_eq!(r.status.code(), Some(2), "{flags:?}: {err}");
        assert!(err.starts_with(expected), "{flags:?}: {err}");
        assert!(
            !String::from_utf8_lossy(&r.stdout).contains("ticks:"),
            "{flags:?} ran"
        );
    }
}
