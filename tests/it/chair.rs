//! Choi & Cremer Fig. 1 as the built-in scene `sit-on-chair`: a jointed
//! figure (pelvis, torso, thighs, shins, arms; hinges with limits) dragged
//! by a scripted hand onto a chair without interpenetration, and the same
//! figure placed onto the seat by `haptloop place`. The seat's top face
//! and the pelvis's half-height are read from the compiled scene; where the
//! pelvis comes to rest is their closed form; the joint rows are evaluated
//! on the joints-only model at the final poses, apart from the session's
//! own violation figures.

use std::process::Command;

use haptloop::report::summary::Summary;
use haptloop::scenes::{Scene, resolve};
use haptloop::session::{self, Plan, SessionOptions};
use haptloop_rt::schedule::StopFlag;
use haptloop_solver::geometry::Shape;
use haptloop_solver::{Evaluation, Model};
use nalgebra::{Quaternion, UnitQuaternion, Vector3};

/// Half extents of `body`'s box in `model`.
fn half(model: &Model, body: &str) -> [f64; 3] {
    let b = &model.bodies()[model.body_id(body).unwrap().index()];
    match b.shape {
        Some(Shape::Box { half_extents_m }) => half_extents_m,
        ref s => panic!("{body}: {s:?}"),
    }
}

/// (seat top z, pelvis half-height) of the compiled scene.
fn seat_and_pelvis(scene: &Scene) -> (f64, f64) {
    let m = &scene.compiled.model;
    let seat = m.body_position(m.q0(), m.body_id("seat").unwrap());
    let seat_top = seat.map_or(-0.025, |p| p.z) + half(m, "seat")[2];
    (seat_top, half(m, "pelvis")[2])
}

/// q of `model` with each moving body at the pose `at(name)` gives.
fn q_from(model: &Model, at: impl Fn(&str) -> (Vector3<f64>, UnitQuaternion<f64>)) -> Vec<f64> {
    let mut q = model.q0().to_vec();
    let layout = model.layout();
    for (id, _) in layout.moving_bodies() {
        let (p, r) = at(&model.bodies()[id.index()].name);
        let pos = layout.position_range(id).unwrap();
        q[pos].copy_from_slice(p.as_slice());
        let rot = layout.rotation_range(id).unwrap();
        q[rot].copy_from_slice(&[r.w, r.i, r.j, r.k]);
    }
    q
}

/// Largest |C| of the joint rows and largest limit violation at `q`.
fn joint_residual(model: &Model, q: &[f64]) -> f64 {
    let mut e = Evaluation::new(model);
    e.evaluate_values(model, q, &[]).unwrap();
    let v = e.values();
    let eq = v[model.equality_rows()]
        .iter()
        .fold(0.0_f64, |m, v| m.max(v.abs()));
    let ineq = v[model.inequality_rows()]
        .iter()
        .fold(0.0_f64, |m, v| m.max(-v));
    eq.max(ineq)
}

#[test]
fn fig_1_the_figure_is_dragged_onto_the_chair_without_interpenetration() {
    let scene = resolve("sit-on-chair").unwrap();
    let (seat_top, pelvis_half) = seat_and_pelvis(&scene);
    let dir = tempfile::tempdir().unwrap();
    let options = SessionOptions {
        seconds: 4.6,
        rate_hz: Some(1000),
        deterministic: true,
        out_dir: Some(dir.path().to_path_buf()),
        ..SessionOptions::default()
    };
    let plan = Plan::new(&scene, &options).unwrap();
    let o = session::run(&scene, plan, &StopFlag::new(), &mut |_| {}).unwrap();
    let s = Summary::of(&o);
    let c = s.contact.as_ref().expect("a scene with shapes");
    println!(
        "sit-on-chair: penetration {:.2e} m (tolerance {:.0e}), violation {:.2e} m, {} backups, {} pairs at most",
        c.max_penetration_m, c.tolerance_m, s.violation.max, c.backups, c.max_tracked_pairs
    );
    assert_eq!(s.safety.solver_failures, 0);
    assert_eq!(s.violation.ticks_failed, 0);
    assert_eq!(c.backups, 0);
    assert!(c.max_penetration_m <= c.tolerance_m && c.tolerance_m <= 1e-4);
    assert!(s.violation.max <= 1e-6, "joints {} m", s.violation.max);
    assert!(c.max_active > 0, "the figure touched the chair");

    // The last sampled poses.
    let t = &o.track;
    let (_, last) = t.samples.iter().last().expect("samples");
    let at = |name: &str| {
        let k = t.bodies.iter().position(|b| b.name == name).unwrap();
        let (r, q) = last.poses[k];
        let q = UnitQuaternion::from_quaternion(Quaternion::new(q[0], q[1], q[2], q[3]));
        (Vector3::from(r), q)
    };
    let (pelvis, tilt) = at("pelvis");
    // The hand ends 2 cm behind and 6.5 cm below where the pelvis started:
    // 5 mm under the seat top.
    let start = scene
        .compiled
        .model
        .body_position(
            scene.compiled.model.q0(),
            scene.compiled.model.body_id("pelvis").unwrap(),
        )
        .unwrap();
    let hand = start + Vector3::new(0.02, 0.0, -0.065);
    assert!(
        hand.z < seat_top + pelvis_half - 0.004,
        "the hand pushes into the seat"
    );
    println!(
        "pelvis ends at {pelvis:?}, tilted {:.2e} rad; the hand at {hand:?}",
        tilt.angle()
    );
    assert!(
        (pelvis.z - (seat_top + pelvis_half)).abs() < 1e-4,
        "the pelvis rests on the seat: centre {} m, seat top + half-height {} m",
        pelvis.z,
        seat_top + pelvis_half
    );
    assert!((pelvis.x - hand.x).abs() < 5e-4 && (pelvis.y - hand.y).abs() < 5e-4);
    assert!(tilt.angle() < 1e-3, "level: {} rad", tilt.angle());
    // The seated pose held: thighs flat on the seat beside the pelvis, the
    // torso upright.
    for name in ["thigh-left", "thigh-right", "torso"] {
        let (p, r) = at(name);
        assert!(
            (r * tilt.inverse()).angle() < 1e-3,
            "{name} turned against the pelvis"
        );
        if name != "torso" {
            let bottom = p.z - half(&scene.compiled.model, name)[2];
            assert!(
                (bottom - seat_top).abs() < 1e-4,
                "{name} bottom at {bottom} m"
            );
        }
    }
    let q = q_from(&scene.compiled.joints_only, at);
    let residual = joint_residual(&scene.compiled.joints_only, &q);
    assert!(residual < 1e-6, "joint rows at the final poses: {residual}");
}

#[test]
fn fig_1_place_stops_the_pelvis_on_the_seat_top() {
    let scene = resolve("sit-on-chair").unwrap();
    let (seat_top, pelvis_half) = seat_and_pelvis(&scene);
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("seated.toml");
    // The goal: 5 mm inside the seat, under where the hand left it above.
    let o = Command::new(env!("CARGO_BIN_EXE_haptloop"))
        .args(["place", "sit-on-chair", "--body", "pelvis", "--goal"])
        .arg(format!("0.04,0,{}", seat_top + pelvis_half - 0.005))
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    let text =
        String::from_utf8_lossy(&o.stdout).into_owned() + &String::from_utf8_lossy(&o.stderr);
    println!("{text}");
    assert_eq!(o.status.code(), Some(3), "blocked: not at the goal\n{text}");
    assert!(text.contains("BLOCKED by contact"), "{text}");
    let placed = haptloop_solver::scene::load(&out)
        .unwrap()
        .compile()
        .unwrap();
    let m = &placed.joints_only;
    let p = m
        .body_position(m.q0(), m.body_id("pelvis").unwrap())
        .unwrap();
    // On the seat: no corner of the pelvis below its top face (to 2 µm, a
    // blocked final goal's intermediate tolerance), its centre within
    // 0.1 mm of the closed form (the figure rests on pelvis and thighs,
    // which the path leaves tilted by a few 1e-4 rad), under the goal.
    let r = m
        .body_rotation(m.q0(), m.body_id("pelvis").unwrap())
        .unwrap();
    let h = half(m, "pelvis");
    let low = (0..8)
        .map(|k| {
            let s = |b: usize| if k & (1 << b) == 0 { -1.0 } else { 1.0 };
            (p + r * Vector3::new(s(0) * h[0], s(1) * h[1], s(2) * h[2])).z
        })
        .fold(f64::MAX, f64::min);
    println!(
        "placed pelvis at {p:?}, lowest corner {:.2e} m above the seat",
        low - seat_top
    );
    assert!(
        low > seat_top - 2e-6,
        "a corner {} m into the seat",
        seat_top - low
    );
    assert!(
        (p.z - (seat_top + pelvis_half)).abs() < 1e-4,
        "pelvis at {p:?}"
    );
    assert!((p.x - 0.04).abs() < 1e-4 && p.y.abs() < 1e-4, "{p:?}");
    assert!(joint_residual(m, m.q0()) < 1e-6);
    // Without contact the same goal is met, inside the seat.
    let o = Command::new(env!("CARGO_BIN_EXE_haptloop"))
        .args([
            "place",
            "sit-on-chair",
            "--body",
            "pelvis",
            "--no-contact",
            "--goal",
        ])
        .arg(format!("0.04,0,{}", seat_top + pelvis_half - 0.005))
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stdout)
    );
}
