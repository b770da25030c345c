//! `coordinates = Auto` on every shipped scene (`scenes/*.toml`): the
//! program either ticks in augmented coordinates and says why (what the
//! joint tick refuses, or the cost estimate that ruled it out), or ticks in
//! joint coordinates through the scene's hand with no failure, no fallback,
//! its violation within the scene's tolerance and its finger forces in
//! lockstep with the augmented program's. Also: what the cost model picks
//! on the lattice, the chain and the four-bar, and the chain in joint
//! coordinates (the universals' forward kinematics, issue 23).

use std::sync::Arc;
use std::time::Duration;

use haptloop_solver::scene::{CompiledScene, HandPath};
use haptloop_solver::{Coordinates, FingerTarget, Model, Program, SolverSettings, TickOutcome};
use nalgebra::Vector3;

use super::joint_coordinates::{body_gap, scene};

const DT: Duration = Duration::from_millis(1);

/// Ticks run per scene where `Auto` picks joint coordinates.
const TICKS: usize = 300;

fn compiled(path: &std::path::Path) -> CompiledScene {
    haptloop_solver::scene::load(path)
        .unwrap()
        .compile()
        .unwrap()
}

/// The scene's settings (step, iterations) with `coordinates`.
fn settings(c: &CompiledScene, coordinates: Coordinates) -> SolverSettings {
    super::common::step_and_iterations(&c.settings, coordinates)
}

/// Each finger's target at `t_s`: its start plus its device's hand path
/// (circle, line, waypoints; a CSV trace is held still), in the scene frame.
fn hand_targets(c: &CompiledScene, t0: &[FingerTarget], t_s: f64) -> Vec<FingerTarget> {
    let mut out = t0.to_vec();
    for f in &c.fingers {
        let offset = match &c.devices[f.device].hand.path {
            HandPath::Circle { radius_m, hz, u, v } => {
                let a = 2.0 * std::f64::consts::PI * hz * t_s;
                (Vector3::from(*u) * (a.cos() - 1.0) + Vector3::from(*v) * a.sin()) * *radius_m
            }
            HandPath::Line { to_m, seconds } => Vector3::from(*to_m) * (t_s / seconds).min(1.0),
            HandPath::Waypoints { points } => waypoint(points, t_s),
            _ => Vector3::zeros(),
        };
        let k = f.finger.0 as usize;
        out[k].position_m = t0[k].position_m + offset;
    }
    out
}

/// The waypoints' offset at `t_s`, linearly interpolated, held at the ends.
fn waypoint(points: &[[f64; 4]], t_s: f64) -> Vector3<f64> {
    let at = |p: &[f64; 4]| Vector3::new(p[1], p[2], p[3]);
    let Some(first) = points.first() else {
        return Vector3::zeros();
    };
    if t_s <= first[0] {
        return at(first);
    }
    for w in points.windows(2) {
        if t_s <= w[1][0] {
            let f = (t_s - w[0][0]) / (w[1][0] - w[0][0]);
            return at(&w[0]) * (1.0 - f) + at(&w[1]) * f;
        }
    }
    at(points.last().unwrap())
}

/// Worst figures of a joint program against the augmented one over the
/// scene's hand: finger force difference, largest force, joint violation.
fn lockstep(
    c: &CompiledScene,
    model: &Arc<Model>,
    joint: &mut Program,
    aug: &mut Program,
) -> [f64; 3] {
    let name = &c.name;
    let t0 = model.initial_targets();
    let (mut df, mut fmax, mut viol) = (0.0f64, 0.0f64, 0.0f64);
    for k in 0..TICKS {
        let t = hand_targets(c, &t0, k as f64 * DT.as_secs_f64());
        let (rj, ra) = (joint.tick(&t, DT), aug.tick(&t, DT));
        assert_eq!(ra.status, TickOutcome::Ok, "{name} tick {k} (augmented)");
        assert_eq!(rj.status, TickOutcome::Ok, "{name} tick {k} (joint)");
        viol = viol.max(rj.max_violation_m);
        for (a, b) in aug.finger_outputs().iter().zip(joint.finger_outputs()) {
            df = df.max((a.force_n - b.force_n).norm());
            fmax = fmax.max(a.force_n.norm());
        }
    }
    assert_eq!(joint.joint_fallbacks(), 0, "{name}: fallbacks");
    [df, fmax, viol]
}

/// Every shipped scene with `coordinates = auto`: augmented with a reason
/// (a refusal, or a cost estimate not below the augmented one), or
/// `TICKS` ticks of the scene's hand in joint coordinates with 0 failures
/// and 0 fallbacks, the violation within the scene's tolerance (1e-6 m if
/// it states none), finger forces within 1e-4 of the largest (+1 µN) of the
/// augmented program's on the same targets.
#[test]
fn auto_is_honest_on_every_shipped_scene() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes");
    let mut paths: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    paths.sort();
    let (mut joint_scenes, mut checked) = (Vec::new(), 0);
    for path in &paths {
        let c = compiled(path);
        let model = Arc::new(c.model.clone());
        let Ok(mut aug) = Program::new(model.clone(), settings(&c, Coordinates::Augmented)) else {
            continue;
        };
        let mut auto = Program::new(model.clone(), settings(&c, Coordinates::Auto))
            .unwrap_or_else(|e| panic!("{}: auto failed where augmented builds: {e}", c.name));
        checked += 1;
        let choice = auto.coordinates().clone();
        println!("{}: {choice}", c.name);
        if !choice.joint {
            assert!(!choice.why.is_empty(), "{}: no reason", c.name);
            if let Some(e) = choice.estimate {
                assert!(e.joint_us() >= e.augmented_us(), "{}: {choice}", c.name);
            }
            continue;
        }
        let e = choice.estimate.expect("a joint choice has its estimate");
        assert!(e.joint_us() < e.augmented_us(), "{}: {choice}", c.name);
        let [df, fmax, viol] = lockstep(&c, &model, &mut auto, &mut aug);
        let tol = c.settings.violation_tolerance.unwrap_or(1e-6);
        println!("  |ΔF| {df:.2e} N of {fmax:.2e} N, violation {viol:.2e} m (tolerance {tol:.0e})");
        assert!(viol <= tol, "{}: violation {viol:.2e} m", c.name);
        assert!(
            df <= 1e-4 * fmax + 1e-6,
            "{}: |ΔF| {df:.2e} N of {fmax:.2e}",
            c.name
        );
        joint_scenes.push(c.name.clone());
    }
    assert!(checked >= 20, "{checked} scenes built");
    joint_scenes.sort();
    assert_eq!(
        joint_scenes,
        [
            "bennett",
            "four-bar",
            "peaucellier",
            "stewart",
            "stewart-3rsu"
        ]
    );
}

/// The cost model's choice (`joint_cost`, constants fitted in BENCHMARKS.md
/// issue 23, "auto's cost model refitted"): on the lattice (132 joint
/// coordinates, 128 loop rows: a dense 128-row loop Gram) and the 64-link
/// chain (130 coordinates in two 65-deep branches) the joint estimate is
/// over the augmented one (measured 1.43× and 1.66×) and `auto` runs
/// augmented; on the four-bar (5 coordinates) it is about half (measured
/// 0.49×) and `auto` runs joint.
/// The estimates are checked against terms computed here from the stated
/// shapes: at least the loop block's n_L³/6 and the branch factor of the
/// stated depths (a path of L coordinates: Σ_k k(k − 1)/2 = C(L + 1, 3)),
/// at most the dense count this model replaced (n³/6 + m n²/2 + m² n/2 +
/// n_L³/6, + 2e3 for the per-step terms); and `joint` asked explicitly
/// still runs joint.
#[test]
fn auto_picks_by_the_cost_model() {
    let path_factor = |l: f64| (l + 1.0) * l * (l - 1.0) / 6.0;
    let lattice: (&str, f64, f64, f64, f64, bool) = ("lattice", 132.0, 131.0, 128.0, 0.0, false);
    for (name, n, m, nl, branch, joint) in [
        lattice,
        ("chain", 130.0, 7.0, 4.0, 2.0 * path_factor(65.0), false),
        ("four-bar", 5.0, 7.0, 4.0, 0.0, true),
    ] {
        let (model, s) = scene(name, Coordinates::Auto);
        let p = Program::new(model.clone(), s).unwrap();
        let c = p.coordinates();
        println!("{name}: {c}");
        assert_eq!(c.joint, joint, "{name}: {c}");
        let e = c.estimate.expect("an estimate");
        let low = (nl * nl * nl / 6.0).max(branch);
        let dense = n * n * n / 6.0 + m * n * n / 2.0 + m * m * n / 2.0 + nl * nl * nl / 6.0;
        assert!(
            e.joint_madds > low && e.joint_madds < dense + 2e3,
            "{name}: {:.3e} against {low:.3e}..{dense:.3e} + 2e3",
            e.joint_madds
        );
        let ratio = e.joint_us() / e.augmented_us();
        if joint {
            assert!(ratio < 0.6, "{name}: {c}");
        } else {
            assert!(ratio > 1.2, "{name}: {c}");
            assert!(c.why.contains("joint estimate"), "{c}");
        }
        let asked = SolverSettings {
            coordinates: Coordinates::Joint,
            ..s
        };
        assert!(
            Program::new(model, asked).unwrap().coordinates().joint,
            "{name}"
        );
    }
}

/// The 64-link chain asked in joint coordinates, 2000 ticks of its scene's
/// hand (a 1 cm circle at 0.5 Hz): no failure, no fallback, and every
/// mechanism row from an independent evaluation at the end — the tree
/// universals the joint tick never evaluates included — within the
/// scene's 1 µm; the bodies stay near the augmented program's (the chain is
/// underdetermined: the two ticks' metrics agree to second order only).
/// Before issue 23's fix the tree universals drifted (1.3e-5 m in 20 ticks)
/// and the chain collapsed at tick ~262.
#[test]
fn the_chain_ticks_in_joint_coordinates() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/chain.toml");
    let c = compiled(&path);
    let model = Arc::new(c.model.clone());
    let mut joint = Program::new(model.clone(), settings(&c, Coordinates::Joint)).unwrap();
    let mut aug = Program::new(model.clone(), settings(&c, Coordinates::Augmented)).unwrap();
    assert!(joint.coordinates().joint);
    let t0 = model.initial_targets();
    let mut t = t0.clone();
    for k in 0..2000 {
        t = hand_targets(&c, &t0, k as f64 * DT.as_secs_f64());
        let r = joint.tick(&t, DT);
        assert_eq!(r.status, TickOutcome::Ok, "tick {k}");
        assert!(
            r.max_violation_m <= 1e-6,
            "tick {k}: {:.2e} m",
            r.max_violation_m
        );
        assert_eq!(aug.tick(&t, DT).status, TickOutcome::Ok, "tick {k}");
    }
    assert_eq!(joint.joint_fallbacks(), 0);
    let mut ev = model.evaluation();
    ev.evaluate(&model, joint.q(), &t).unwrap();
    let fingers: Vec<usize> = model
        .fingers()
        .iter()
        .flat_map(|f| model.constraints()[f.constraint.index()].rows.clone())
        .collect();
    let worst = model
        .rows()
        .iter()
        .enumerate()
        .filter(|(i, r)| r.unit == haptloop_solver::RowUnit::Length && !fingers.contains(i))
        .map(|(i, _)| ev.values()[i].abs())
        .fold(0.0, f64::max);
    let gap = body_gap(&model, joint.q(), aug.q());
    println!("chain: worst length row {worst:.2e} m, bodies within {gap:.2e} m of augmented");
    assert!(worst <= 1e-6, "{worst:.2e} m");
    assert!(gap < 2e-3, "{gap:.2e} m");
    assert!(body_gap(&model, model.q0(), joint.q()) > 1e-3, "it moved");
}

/// The generated chains (`chain-N`, the chain scene's settings): `auto`
/// follows the measured order (BENCHMARKS.md issue 23, "auto's cost model
/// refitted": joint/augmented measured 0.55× at 8 links, 0.62× at 16,
/// 0.73× at 24, 0.84× at 32, 1.17× at 48, 1.66× at 64). Before the refit
/// `auto` ran chain-24 and chain-32 augmented. Each augmented estimate is
/// at least its per-row evaluation and Jacobian terms computed here from the
/// built model (190 N (iterations + 1) + 12 nnz(C_q)).
#[test]
fn auto_follows_the_measured_order_on_the_generated_chains() {
    let (_, s) = scene("chain", Coordinates::Auto);
    for (links, joint) in [
        (8, true),
        (16, true),
        (24, true),
        (32, true),
        (48, false),
        (64, false),
    ] {
        let model = Arc::new(
            haptloop_solver::mechanisms::chain_sized(links)
                .build()
                .unwrap(),
        );
        let c = Program::new(model.clone(), s)
            .unwrap()
            .coordinates()
            .clone();
        println!("chain-{links}: {c}");
        assert_eq!(c.joint, joint, "chain-{links}: {c}");
        let e = c.estimate.expect("an estimate");
        assert_eq!(e.joint_cheaper(), joint, "chain-{links}: {c}");
        let mut ev = model.evaluation();
        ev.evaluate(&model, model.q0(), &model.initial_targets())
            .unwrap();
        let steps = f64::from(s.iterations + 1);
        let low = 190.0 * model.n_rows() as f64 * steps + 12.0 * ev.jacobian().nnz() as f64;
        assert!(
            e.augmented_madds > low,
            "chain-{links}: {:.3e} against {low:.3e}",
            e.augmented_madds
        );
    }
}
