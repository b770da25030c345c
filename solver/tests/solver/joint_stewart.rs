//! The Stewart platform in joint coordinates: its rigid (six-row) grasp
//! and its stroke limits, each against the augmented program ticking the
//! same targets (the pattern of `joint_coordinates`), and zero allocation.

use std::sync::Arc;
use std::time::Duration;

use haptloop_rt::alloc::{count, is_installed};
use haptloop_solver::{Coordinates, FingerTarget, Model, Program, SolverSettings, TickOutcome};
use nalgebra::{UnitQuaternion, Vector3};

use super::common::step_and_iterations;
use super::joint_coordinates::body_gap;

const DT: Duration = Duration::from_millis(1);

/// The scene `name` (its `[solver]` step and iterations), with every
/// `limits = …` line dropped when `free`.
pub fn scene(name: &str, free: bool) -> (Arc<Model>, SolverSettings) {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../scenes")
        .join(format!("{name}.toml"));
    let text = std::fs::read_to_string(&path).unwrap();
    let text: String = text
        .lines()
        .filter(|l| !(free && l.trim_start().starts_with("limits")))
        .map(|l| format!("{l}\n"))
        .collect();
    let compiled = haptloop_solver::scene::parse(&format!("{name}.toml"), &text, None)
        .unwrap()
        .compile()
        .unwrap();
    let settings = step_and_iterations(&compiled.settings, SolverSettings::default().coordinates);
    (Arc::new(compiled.model), settings)
}

/// The augmented and the joint program of a scene from its q0, with
/// `iterations` steps a tick if given.
pub fn pair(name: &str, free: bool, iterations: Option<u32>) -> (Program, Program) {
    let (model, mut s) = scene(name, free);
    s.iterations = iterations.unwrap_or(s.iterations);
    let aug = Program::new(model.clone(), s).unwrap();
    let joint = Program::new(
        model,
        SolverSettings {
            coordinates: Coordinates::Joint,
            ..s
        },
    )
    .unwrap_or_else(|e| panic!("{name}: {e}"));
    assert!(!aug.coordinates().joint);
    assert!(joint.coordinates().joint, "{name}: {}", joint.coordinates());
    (aug, joint)
}

/// A 2 mm hand circle, 500 ticks a turn, the grasp turned up to 0.05 rad
/// about a wandering axis.
fn wobble(t0: &[FingerTarget], k: usize) -> Vec<FingerTarget> {
    let a = 2.0 * std::f64::consts::PI * k as f64 / 500.0;
    let mut t = t0.to_vec();
    for (t, t0) in t.iter_mut().zip(t0) {
        t.position_m = t0.position_m + Vector3::new(a.cos() - 1.0, a.sin(), 0.0) * 0.002;
        let axis = Vector3::new(a.sin(), (2.0 * a).cos(), 0.5);
        t.orientation =
            UnitQuaternion::from_scaled_axis(axis.normalize() * 0.05 * a.sin()) * t0.orientation;
    }
    t
}

/// Largest |force| and |torque| differences of the two programs' finger
/// outputs, and the largest |force|, |torque| of the augmented one's.
fn output_gaps(a: &Program, b: &Program) -> [f64; 4] {
    let mut g = [0.0f64; 4];
    for (x, y) in a.finger_outputs().iter().zip(b.finger_outputs()) {
        g[0] = g[0].max((x.force_n - y.force_n).norm());
        g[1] = g[1].max((x.torque_nm - y.torque_nm).norm());
        g[2] = g[2].max(x.force_n.norm());
        g[3] = g[3].max(x.torque_nm.norm());
    }
    g
}

/// The rigid grasp: 400 ticks of the wobbling grasp on Stewart without its
/// stroke limits and on the 3-RUS platform (its welded ground a tree joint
/// without coordinates, its crank limits not reached; gravity is off in
/// both scenes), both programs from q0, each finger output's force and
/// torque against the augmented program's: with the scene's steps (the two
/// chords differ at second order) bodies within 1 µm, force and torque
/// within 1e-3 of the largest; with four steps on Stewart (both converged:
/// the same rows, scale and output) within 1e-5 of the largest.
#[test]
fn the_rigid_grasp_follows_the_augmented_program() {
    let runs = [
        ("stewart", true, None, 1e-3),
        ("stewart", true, Some(4), 1e-5),
        ("stewart-3rsu", false, None, 1e-3),
    ];
    for (name, free, steps, bound) in runs {
        let (mut aug, mut joint) = pair(name, free, steps);
        let model = aug.model_arc().clone();
        let t0 = model.initial_targets();
        let (mut dr, mut worst) = (0.0f64, [0.0f64; 4]);
        for k in 0..400 {
            let t = wobble(&t0, k);
            let (ra, rj) = (aug.tick(&t, DT), joint.tick(&t, DT));
            assert_eq!(ra.status, TickOutcome::Ok, "{name} tick {k}");
            assert_eq!(rj.status, TickOutcome::Ok, "{name} tick {k}");
            dr = dr.max(body_gap(&model, aug.q(), joint.q()));
            for (w, g) in worst.iter_mut().zip(output_gaps(&aug, &joint)) {
                *w = w.max(g);
            }
        }
        let [df, dt, fmax, tmax] = worst;
        println!(
            "{name}, {steps:?} steps: |Δr| {dr:.2e} m, |ΔF| {df:.2e} of {fmax:.2e} N, \
             |Δτ| {dt:.2e} of {tmax:.2e} N m"
        );
        assert_eq!(
            joint.joint_fallbacks(),
            0,
            "{name}: every tick a joint tick"
        );
        assert!(
            fmax > 1e-3 && tmax > 1e-5,
            "{name}: the load is not trivially zero"
        );
        assert!(dr < 1e-6, "{name}: |Δr| {dr:.2e} m");
        assert!(df < bound * fmax, "{name}: |ΔF| {df:.2e} N");
        assert!(dt < bound * tmax, "{name}: |Δτ| {dt:.2e} N m");
        assert!(
            body_gap(&model, model.q0(), joint.q()) > 1e-4,
            "{name}: it moved"
        );
        let drift = tree_rows_at(&model, joint.q(), &wobble(&t0, 399));
        println!("{name}: the tree joints' rows at the joint program's q {drift:.2e}");
        assert!(
            drift < 1e-12,
            "{name}: forward kinematics broke a tree joint"
        );
    }
}

/// The largest |C| of the tree joints' rows at q (a fresh evaluation):
/// forward kinematics keeps them (the universal joints' rotation about their
/// own point, not the foot of the first axis).
fn tree_rows_at(model: &Model, q: &[f64], t: &[FingerTarget]) -> f64 {
    let tree = haptloop_solver::reduced::JointTree::new(model).unwrap();
    let mut ev = model.evaluation();
    ev.evaluate(model, q, t).unwrap();
    tree.tree_rows()
        .iter()
        .map(|&r| ev.values()[r].abs())
        .fold(0.0, f64::max)
}

/// 300 ticks of the rigid grasp in joint coordinates: no allocator call.
#[test]
fn the_rigid_grasp_allocates_nothing() {
    assert!(is_installed());
    let (_, mut joint) = pair("stewart", true, None);
    let t0 = joint.model().initial_targets();
    let targets: Vec<Vec<FingerTarget>> = (0..300).map(|k| wobble(&t0, k)).collect();
    let (ok, stats) = count(|| {
        targets
            .iter()
            .all(|t| joint.tick(t, DT).status == TickOutcome::Ok)
    });
    assert!(ok, "a tick failed");
    assert_eq!(stats.total(), 0, "allocations {stats:?}");
    assert_eq!(joint.joint_fallbacks(), 0);
}

/// The scene's lift (5 cm up) at 25 µm a tick, held 200 ticks, then 1 cm
/// back down.
fn lift(t0: &[FingerTarget], k: usize) -> Vec<FingerTarget> {
    let up = 2000.0;
    let z = if k < 2200 {
        (k as f64 / up).min(1.0)
    } else {
        1.0 - (k - 2200) as f64 / up
    } * 0.05;
    let mut t = t0.to_vec();
    for (t, t0) in t.iter_mut().zip(t0) {
        t.position_m = t0.position_m + Vector3::new(0.0, 0.0, z);
    }
    t
}

/// The smallest limit-row value at q (a fresh evaluation): < 0 past a stop.
fn limit_gap(model: &Model, q: &[f64], t: &[FingerTarget]) -> f64 {
    let mut ev = model.evaluation();
    ev.evaluate(model, q, t).unwrap();
    model
        .inequality_rows()
        .map(|r| ev.values()[r])
        .fold(f64::INFINITY, f64::min)
}

/// Height of the platform (the finger's body).
fn height(model: &Model, q: &[f64]) -> f64 {
    let o = model.layout().body_offset(model.fingers()[0].body).unwrap();
    q[o + 2]
}

/// Through the stops: the scene's lift until the stroke limits stop the
/// platform, held there, then back down, both programs from q0. The stop
/// engages on the same tick (a limit row within 1 µm of its bound, and the
/// first in-tick activation), the platform's height stays within 1 µm and
/// the felt force within 1e-3 of the largest; the stop never pulls: on the
/// way down the platform leaves it on the same tick as the augmented
/// program's and then follows the hand (tracking error below 0.1 mm).
#[test]
fn the_stroke_limits_stop_the_platform_as_the_augmented_program() {
    let name = "stewart";
    let (mut aug, mut joint) = pair(name, false, None);
    let model = aug.model_arc().clone();
    let t0 = model.initial_targets();
    let (mut engage, mut activate, mut leave) = ([None; 2], [None; 2], [None; 2]);
    let (mut dz, mut df, mut fmax, mut track, mut low) = (0.0f64, 0.0f64, 0.0f64, 0.0f64, 0.0f64);
    for k in 0..2800 {
        let t = lift(&t0, k);
        let (ra, rj) = (aug.tick(&t, DT), joint.tick(&t, DT));
        assert_eq!(ra.status, TickOutcome::Ok, "{name} tick {k}");
        assert_eq!(rj.status, TickOutcome::Ok, "{name} tick {k}");
        for (s, (p, r)) in [(&aug, ra), (&joint, rj)].into_iter().enumerate() {
            let gap = limit_gap(&model, p.q(), &t);
            if gap < 1e-6 && engage[s].is_none() {
                engage[s] = Some(k);
            }
            if r.activations > 0 && activate[s].is_none() {
                activate[s] = Some(k);
            }
            if k > 2200 && gap > 1e-6 && leave[s].is_none() {
                leave[s] = Some(k);
            }
            low = low.min(gap);
        }
        dz = dz.max((height(&model, aug.q()) - height(&model, joint.q())).abs());
        let [d, _, f, _] = output_gaps(&aug, &joint);
        (df, fmax) = (df.max(d), fmax.max(f));
        if leave[1].is_some_and(|l| k > l + 2) {
            track = track.max(rj.max_tracking_error_m);
        }
    }
    println!(
        "{name}: stop engaged at {engage:?}, first activation {activate:?}, left at {leave:?}; \
         |Δz| {dz:.2e} m, |ΔF| {df:.2e} of {fmax:.2e} N, lowest limit value {low:.2e}, \
         tracking once off the stop {track:.2e} m, releases {} / {}",
        aug.force_releases(),
        joint.force_releases()
    );
    assert!(
        engage[0].is_some() && activate[0].is_some(),
        "the stop was reached"
    );
    assert_eq!(engage[0], engage[1], "the stop engages on the same tick");
    assert_eq!(activate[0], activate[1], "the same first activation");
    assert!(
        leave[0].is_some() && leave[0] == leave[1],
        "the stop releases on the same tick"
    );
    assert_eq!(joint.joint_fallbacks(), 0, "every tick a joint tick");
    assert_eq!(aug.force_releases(), joint.force_releases(), "releases");
    assert!(dz < 1e-6, "|Δz| {dz:.2e} m");
    assert!(df < 1e-3 * fmax, "|ΔF| {df:.2e} N of {fmax:.2e}");
    assert!(
        track < 1e-4,
        "the platform follows the hand down: {track:.2e} m"
    );
}

/// Through the stops and back: no allocator call.
#[test]
fn the_stroke_limits_allocate_nothing() {
    assert!(is_installed());
    let (_, mut joint) = pair("stewart", false, None);
    let t0 = joint.model().initial_targets();
    let targets: Vec<Vec<FingerTarget>> = (0..2800).map(|k| lift(&t0, k)).collect();
    let (ok, stats) = count(|| {
        targets
            .iter()
            .all(|t| joint.tick(t, DT).status == TickOutcome::Ok)
    });
    assert!(ok, "a tick failed");
    assert_eq!(stats.total(), 0, "allocations {stats:?}");
    assert_eq!(joint.joint_fallbacks(), 0);
}

/// A revolute limit (an angle row, scaled by L like every angle row): the
/// limited pendulum of `joint_choice` dragged by its tip around its hinge
/// past 1 rad, back past −0.5 rad and back to 0, both programs from q0:
/// the stop engages and leaves on the same ticks, the arm's angle within
/// 1e-5 rad (2.1 mrad a tick: the two chords differ at second order, 1.8e-6
/// measured) and the felt force within 1e-3 of the largest. (The releases
/// are not compared: resting on a stop with no load along the hinge, the
/// limit's multiplier is round-off of either sign.)
#[test]
fn a_hinge_limit_stops_the_arm_as_the_augmented_program() {
    let model = Arc::new(super::joint_choice::limited_pendulum());
    let s = SolverSettings::default();
    let mut aug = Program::new(model.clone(), s).unwrap();
    let mut joint = Program::new(
        model.clone(),
        SolverSettings {
            coordinates: Coordinates::Joint,
            ..s
        },
    )
    .unwrap();
    assert!(joint.coordinates().joint, "{}", joint.coordinates());
    let t0 = model.initial_targets();
    let o = model.layout().body_offset(model.fingers()[0].body).unwrap();
    let angle = |q: &[f64]| q[o + 1].atan2(q[o]);
    let (mut engaged, mut left) = (Vec::new(), Vec::new());
    let (mut da, mut df, mut fmax, mut low) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    for k in 0..3000 {
        // 0 → 1.3 rad → −0.8 rad → 0 at 2.13 mrad a tick (the tip's
        // 0.2 m), a rate whose ticks never land on a bound exactly (there
        // round-off decides whether a resting stop leaves a tick early).
        let x = k as f64 * 0.00213;
        let a = if x < 1.3 {
            x
        } else if x < 3.4 {
            2.6 - x
        } else {
            (x - 4.2).min(0.0)
        };
        let mut t = t0.clone();
        t[0].position_m = Vector3::new(a.cos(), a.sin(), 0.0) * 0.2;
        let (ra, rj) = (aug.tick(&t, DT), joint.tick(&t, DT));
        assert_eq!(ra.status, TickOutcome::Ok, "tick {k}");
        assert_eq!(rj.status, TickOutcome::Ok, "tick {k}");
        let at = [
            limit_gap(&model, aug.q(), &t),
            limit_gap(&model, joint.q(), &t),
        ];
        let on = at.map(|g| g < 1e-6);
        engaged.push(on);
        left.push(at);
        low = low.min(at[1]);
        da = da.max((angle(aug.q()) - angle(joint.q())).abs());
        let [d, _, f, _] = output_gaps(&aug, &joint);
        (df, fmax) = (df.max(d), fmax.max(f));
    }
    let switches = |s: usize| {
        let mut v = Vec::new();
        for (k, w) in engaged.windows(2).enumerate() {
            if w[0][s] != w[1][s] {
                v.push(k + 1);
            }
        }
        v
    };
    let (sa, sj) = (switches(0), switches(1));
    println!(
        "hinge: the stop on/off at ticks {sa:?} / {sj:?}; |Δangle| {da:.2e} rad, \
         |ΔF| {df:.2e} of {fmax:.2e} N, lowest limit value {low:.2e}, releases {} / {}",
        aug.force_releases(),
        joint.force_releases()
    );
    assert_eq!(sa.len(), 4, "both stops engaged and left: {sa:?}");
    assert_eq!(sa, sj, "the same ticks");
    assert_eq!(joint.joint_fallbacks(), 0);
    assert!(da < 1e-5, "|Δangle| {da:.2e} rad");
    assert!(df < 1e-3 * fmax, "|ΔF| {df:.2e} N of {fmax:.2e}");
}
