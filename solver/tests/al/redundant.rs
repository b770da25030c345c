//! Structurally redundant rows and the divergence guards: planar linkages of
//! spatial revolutes (`planar`), whose closed loops repeat out-of-plane rows.
//! `Program::new` masks the dependent rows; a tick refuses absurd results.

use std::sync::Arc;
use std::time::Duration;

use haptloop_rt::alloc::{count, is_installed};
use haptloop_solver::mechanisms::{four_bar, sphere_toy, stewart};
use haptloop_solver::{
    Divergence, FingerTarget, Model, PlaneOwner, PointPlaneSpec, Program, RedundancyCheck, RowUnit,
    SolverSettings, TickOutcome, UpdateRule, reference_finger_wrenches,
};
use nalgebra::{DMatrix, Vector3};

use crate::common::*;
use crate::planar::*;

fn settings(update: UpdateRule) -> SolverSettings {
    SolverSettings {
        update,
        ..SolverSettings::default()
    }
}

/// Numerical rank of `rows` of C_q at q0, rows scaled to metres (angle and
/// norm rows × L), singular values above 1e-9 × the largest.
fn rank(model: &Model, rows: &[usize]) -> usize {
    let mut ev = model.evaluation();
    ev.evaluate(model, model.q0(), &model.initial_targets())
        .unwrap();
    let c = ev.jacobian().to_dense();
    let ell = model.characteristic_length_m();
    let b = DMatrix::from_fn(rows.len(), model.n_coords(), |k, j| {
        let s = if model.rows()[rows[k]].unit == RowUnit::Length {
            1.0
        } else {
            ell
        };
        c[(rows[k], j)] * s
    });
    let sv = b.singular_values();
    sv.iter().filter(|&&v| v > 1e-9 * sv.max()).count()
}

/// The mechanism's equality rows (no fingers).
fn equality_rows(model: &Model) -> Vec<usize> {
    model
        .equality_rows()
        .filter(|&i| {
            model.constraints()[model.rows()[i].constraint.index()]
                .finger
                .is_none()
        })
        .collect()
}

/// `rows` less `masked`.
fn without(rows: &[usize], masked: &[usize]) -> Vec<usize> {
    rows.iter()
        .copied()
        .filter(|i| !masked.contains(i))
        .collect()
}

/// Rows 2..5 of a revolute (the out-of-plane pin, the two tilts).
fn out_of_plane_rows(model: &Model, joint: &str) -> Vec<usize> {
    let c = &model.constraints()[model.constraint_id(joint).unwrap().index()];
    assert_eq!(c.rows.len(), 5);
    (c.rows.start + 2..c.rows.end).collect()
}

#[test]
fn masked_rows_are_dependent_and_close_the_loops() {
    let g = [0.0, 0.0, -9.81];
    for (model, closing, rank_expected) in [
        (peaucellier(g), vec!["A-ap", "B-pb", "Q"], 48),
        (planar_four_bar(g), vec!["O2"], 20),
    ] {
        let p = program(model.clone(), SolverSettings::default());
        let red = p.redundancy().clone();
        // Model order keeps whole joints: the masked rows are the
        // out-of-plane rows of the joints that close the loops (a spanning
        // tree stays), the same set at every planar configuration.
        let expected: Vec<usize> = closing
            .iter()
            .flat_map(|j| out_of_plane_rows(&model, j))
            .collect();
        assert_eq!(red.rows, expected);
        assert!(red.dense, "{red:?}");
        assert!(red.conditioning.unwrap() < 1e-10, "{red:?}");
        // Dependent: the kept rows have the rank of all rows, and are
        // independent among themselves.
        let all = equality_rows(&model);
        let kept = without(&all, &red.rows);
        assert_eq!(rank(&model, &all), rank_expected);
        assert_eq!(rank(&model, &kept), rank_expected);
        assert_eq!(kept.len(), rank_expected);
        // The dense mode finds the same rows; the check switched off, none.
        let dense = Program::new(
            Arc::new(model.clone()),
            SolverSettings {
                redundancy: RedundancyCheck::Dense,
                ..SolverSettings::default()
            },
        )
        .unwrap();
        assert_eq!(dense.redundancy().rows, expected);
        let off = Program::new(
            Arc::new(model.clone()),
            SolverSettings {
                redundancy: RedundancyCheck::Off,
                ..SolverSettings::default()
            },
        )
        .unwrap();
        assert!(off.redundancy().rows.is_empty());
    }
}

/// The built-in mechanisms have full row rank: nothing is masked and the
/// cheap test spares them the dense QR.
#[test]
fn full_rank_mechanisms_skip_the_dense_test_and_mask_nothing() {
    for model in [four_bar(), stewart(), sphere_toy()] {
        let p = program(model, SolverSettings::default());
        let red = p.redundancy();
        assert!(red.rows.is_empty(), "{red:?}");
        assert!(!red.dense, "{red:?}");
        assert!(red.conditioning.unwrap() > 1e-6, "{red:?}");
    }
}

/// A contact the joints already enforce (a pin of the planar linkage on the
/// plane z ≥ −1 cm) is masked for good; one along the free motion is not.
#[test]
fn an_inequality_implied_by_the_joints_is_masked() {
    let model = planar_four_bar([0.0, 0.0, -9.81]);
    let crank = model.body_id("crank").unwrap();
    let plane = |name: &str, normal: [f64; 3], at: [f64; 3]| PointPlaneSpec {
        name: name.into(),
        body: crank,
        point_m: [0.0; 3],
        plane: PlaneOwner::World,
        plane_point_m: at,
        normal,
    };
    let model = model
        .with_inequalities(&[
            plane("floor", [0.0, 0.0, 1.0], [0.0, 0.0, -0.01]),
            plane("wall", [1.0, 0.0, 0.0], [-0.05, 0.0, 0.0]),
        ])
        .unwrap();
    let (floor, wall) = (model.n_rows() - 2, model.n_rows() - 1);
    let p = program(model, SolverSettings::default());
    let red = p.redundancy();
    assert_eq!(red.inequality_rows, 2);
    assert!(red.rows.contains(&floor), "{red:?}");
    assert!(!red.rows.contains(&wall), "{red:?}");
}

/// Eq. 7 on a redundant linkage held still under a gravity with an in-plane
/// part: the fast path (masked rows, sparse Cholesky) equals the dense
/// null-space reference (SVD null space, minimum-norm finger load), which
/// needs no masking.
#[test]
fn redundant_linkage_static_force_matches_the_reference() {
    let g = [0.0, -4.0, -9.0];
    for model in [peaucellier(g), planar_four_bar(g)] {
        let targets = model.initial_targets();
        for update in [UpdateRule::Projected, UpdateRule::Gradient] {
            let mut p = program(model.clone(), settings(update));
            hold(&mut p, &targets, 5);
            let zeros = vec![0.0; model.n_coords()];
            let reference = reference_finger_wrenches(&model, p.q(), &zeros, &zeros).unwrap();
            let (f, f_ref) = (
                p.finger_outputs()[0].constraint_force_n,
                reference[0].force_n,
            );
            assert!(f_ref.norm() > 0.01, "a real load: {f_ref}");
            assert!(rel(&f, &f_ref) < 1e-6, "{update:?}: {f} vs {f_ref}");
        }
    }
}

/// Finger target offset at time `t`: up to 1.5 cm in −x (off the
/// Peaucellier line, across the four-bar's coupler curve), a 2 cm sweep in
/// +y (along them, away from the Peaucellier dead point), ±3 mm out of the
/// plane (loading the redundant rows).
fn off_path(t: f64) -> Vector3<f64> {
    let w = 2.0 * std::f64::consts::PI * 0.25;
    Vector3::new(
        -0.0075 * (1.0 - (w * t).cos()),
        0.01 * (1.0 - (0.7 * w * t).cos()),
        0.003 * (1.3 * w * t).sin(),
    )
}

struct Run {
    max_violation_m: f64,
    max_force_n: f64,
    max_tracking_m: f64,
}

/// 10 s at 1 kHz along `off_path`; panics on any status but `Ok`.
fn follow(model: &Model, settings: SolverSettings) -> Run {
    let p0 = model.initial_targets()[0].position_m;
    let mut p = program(model.clone(), settings);
    let mut run = Run {
        max_violation_m: 0.0,
        max_force_n: 0.0,
        max_tracking_m: 0.0,
    };
    for k in 0..10_000 {
        let t = k as f64 * DT.as_secs_f64();
        let r = p.tick(&[FingerTarget::at(p0 + off_path(t))], DT);
        assert_eq!(r.status, TickOutcome::Ok, "tick {k}: {r:?}");
        run.max_violation_m = run.max_violation_m.max(r.max_violation_m);
        run.max_force_n = run.max_force_n.max(p.finger_outputs()[0].force_n.norm());
        run.max_tracking_m = run.max_tracking_m.max(r.max_tracking_error_m);
    }
    run
}

/// The planar four-bar's coupler point dragged up to 2 cm off its curve for
/// 10 s. Projected: exact to 1e-6 m (measured 9e-11). Gradient (Eq. 3, 4
/// steps): its violation is the lag of a first-order method, 5.6e-6 m on the
/// spatial four-bar's 1 cm trade-off circle (BENCHMARKS.md) and 7.7e-6 m here
/// (2 cm off); 2e-5 m leaves room and would catch an unmasked solve that
/// keeps pulling on repeated rows. The force is the coupling's 400 N/m times
/// the tracking error, plus the light links' Eq. 7 load.
#[test]
fn planar_four_bar_follows_an_off_curve_target_with_both_rules() {
    let model = planar_four_bar([0.0, 0.0, -9.81]);
    for (update, bound) in [(UpdateRule::Projected, 1e-6), (UpdateRule::Gradient, 2e-5)] {
        let run = follow(&model, settings(update));
        assert!(
            run.max_violation_m < bound,
            "{update:?}: {}",
            run.max_violation_m
        );
        assert!(
            run.max_tracking_m > 0.01,
            "{update:?}: the target must leave the curve"
        );
        assert!(run.max_force_n < 10.0, "{update:?}: {} N", run.max_force_n);
    }
}

/// The Peaucellier linkage's Q dragged up to 1.5 cm off its straight line
/// (and ±3 mm out of plane) for 10 s with the projected rule.
#[test]
fn peaucellier_follows_an_off_line_target() {
    let model = peaucellier([0.0, 0.0, -9.81]);
    let run = follow(&model, SolverSettings::default());
    assert!(run.max_violation_m < 1e-6, "{}", run.max_violation_m);
    assert!(run.max_tracking_m > 0.014, "{}", run.max_tracking_m);
    assert!(run.max_force_n < 10.0, "{} N", run.max_force_n);
}

/// Eq. 3 on the Peaucellier linkage, which works 1 cm from its dead point:
/// the slowest joint mode has (σ_min / σ_max)² ≈ 1e-5, so the gradient
/// rule keeps millimetres of violation and lags by centimetres (measured
/// 7.6 mm, 3.3 cm): not a rule for this scene. What masking guarantees is
/// that Eq. 7 stays physical on those violated configurations: 57 N of
/// unfiltered inertia at worst, where the unmasked solve asked 5e5 N.
#[test]
fn gradient_rule_on_peaucellier_keeps_eq7_physical() {
    let model = peaucellier([0.0, 0.0, -9.81]);
    let p0 = model.initial_targets()[0].position_m;
    let mut p = program(model, settings(UpdateRule::Gradient));
    let (mut max_eq7, mut max_violation) = (0.0f64, 0.0f64);
    for k in 0..10_000 {
        let t = k as f64 * DT.as_secs_f64();
        let r = p.tick(&[FingerTarget::at(p0 + off_path(t))], DT);
        assert_eq!(r.status, TickOutcome::Ok, "tick {k}");
        max_eq7 = max_eq7.max(p.finger_outputs()[0].constraint_force_n.norm());
        max_violation = max_violation.max(r.max_violation_m);
    }
    assert!(max_violation < 0.02, "{max_violation}");
    assert!(max_eq7 < 100.0, "{max_eq7} N");
}

/// A configuration off the manifold (a placement to a loose tolerance, a
/// corrupted state) puts C's nonlinearity into the redundant rows'
/// combination. Unmasked, the projected rule failed every tick from 1e-5 m
/// and the gradient rule's Eq. 7 asked 1.5e3 N; masked, both snap back, the
/// snap's inertia (0.1 mm in a tick on 20 g links) a few newtons.
#[test]
fn a_perturbed_redundant_linkage_recovers() {
    let model = peaucellier([0.0, 0.0, -9.81]);
    let targets = model.initial_targets();
    for update in [UpdateRule::Projected, UpdateRule::Gradient] {
        let mut p = program(model.clone(), settings(update));
        p.set_q(&perturbed(&model, 1e-4, 5)).unwrap();
        let mut max_eq7 = 0.0f64;
        let mut last = f64::INFINITY;
        for k in 0..1000 {
            let r = p.tick(&targets, DT);
            assert_eq!(r.status, TickOutcome::Ok, "{update:?} tick {k}: {r:?}");
            max_eq7 = max_eq7.max(p.finger_outputs()[0].constraint_force_n.norm());
            last = r.max_violation_m;
        }
        assert!(last < 1e-9, "{update:?}: {last}");
        assert!(max_eq7 < 10.0, "{update:?}: {max_eq7} N");
    }
}

/// The scene's hand circle (1.5 cm at 0.25 Hz, from the finger) drags Q down
/// its line into the dead point y = 0.0367 m at t ≈ 2.58 s, where P = Q, the
/// rhombus is flat and the kept rows lose rank. There the chord iteration
/// diverged (7e12 m) before the projected step learnt to stop; now the
/// linkage passes: it folds into its other assembly branch (Q on the crank
/// circle, toward the target), with a transient of at most 1 mm for a few
/// ticks and an inertial kick the session's 10 ms velocity filter smooths.
#[test]
fn the_dead_point_is_crossed_without_divergence() {
    let model = peaucellier([0.0, 0.0, -9.81]);
    let p0 = model.initial_targets()[0].position_m;
    let settings = SolverSettings {
        velocity_filter: Duration::from_millis(10),
        ..SolverSettings::default()
    };
    let mut p = program(model, settings);
    let w = 2.0 * std::f64::consts::PI * 0.25;
    let (mut before, mut lowest_y) = (0.0f64, f64::INFINITY);
    let (mut worst, mut max_force, mut violated) = (0.0f64, 0.0f64, 0);
    let mut after = 0.0f64;
    for k in 0..4000 {
        let t = k as f64 * DT.as_secs_f64();
        let target = p0 + Vector3::new((w * t).cos() - 1.0, (w * t).sin(), 0.0) * 0.015;
        let r = p.tick(&[FingerTarget::at(target)], DT);
        assert_eq!(r.status, TickOutcome::Ok, "tick {k}: {r:?}");
        let o = p.finger_outputs()[0];
        lowest_y = lowest_y.min(o.attachment_m.y);
        if k < 2500 {
            before = before.max(r.max_violation_m);
        } else if k >= 3000 {
            after = after.max(r.max_violation_m);
        }
        worst = worst.max(r.max_violation_m);
        max_force = max_force.max(o.force_n.norm());
        violated += usize::from(r.max_violation_m > 1e-6);
    }
    assert!(
        lowest_y < dead_point_y() + 1e-4,
        "reached the dead point: {lowest_y}"
    );
    assert!(before < 1e-8, "{before}");
    assert!(after < 1e-8, "{after}");
    assert!(worst < 1e-3, "{worst}");
    assert!(violated <= 20, "{violated} ticks above 1 µm");
    assert!(max_force < 300.0, "{max_force} N");
}

/// A crafted absurd step: a free body whose finger has no pull limit, its
/// target a kilometre away. The tick refuses it: status `Diverged(Step)`,
/// zero outputs, q and multipliers unchanged; an ordinary target works again.
#[test]
fn an_absurd_step_is_refused() {
    let model = free_body([0.0; 3], false);
    let targets = model.initial_targets();
    let mut p = program(
        model,
        SolverSettings {
            finger_pull_limit_m: f64::INFINITY,
            ..SolverSettings::default()
        },
    );
    hold(&mut p, &targets, 10);
    let (q, lambda) = (p.q().to_vec(), p.lambda().to_vec());
    let far = [FingerTarget::at(
        targets[0].position_m + Vector3::new(1e3, 0.0, 0.0),
    )];
    let r = p.tick(&far, DT);
    assert_eq!(r.status, TickOutcome::Diverged(Divergence::Step));
    assert_eq!(p.q(), &q[..]);
    assert_eq!(p.lambda(), &lambda[..]);
    assert!(p.finger_outputs().iter().all(|o| *o == Default::default()));
    assert_eq!(p.iterate(&far, 1), TickOutcome::Diverged(Divergence::Step));
    assert_eq!(p.q(), &q[..]);
    hold(&mut p, &targets, 5);
}

/// A crafted absurd violation: the planar four-bar's coupler 20 cm off its
/// pins (twice L), and a gradient rule at 1 % of its stable step that cannot
/// close that in a tick. The tick is refused as `Diverged(Violation)` with q
/// kept as it was given.
#[test]
fn an_absurd_violation_is_refused() {
    let model = planar_four_bar([0.0, 0.0, -9.81]);
    let targets = model.initial_targets();
    let slow = SolverSettings {
        step: 0.01,
        ..settings(UpdateRule::Gradient)
    };
    let mut p = program(model.clone(), slow);
    let mut q = model.q0().to_vec();
    let coupler = model
        .layout()
        .body_offset(model.body_id("coupler").unwrap())
        .unwrap();
    q[coupler + 2] += 0.2;
    p.set_q(&q).unwrap();
    let limit = p.divergence_limits().violation_m;
    assert!(limit < 0.2 && limit > 0.01, "{limit}");
    let r = p.tick(&targets, DT);
    assert_eq!(r.status, TickOutcome::Diverged(Divergence::Violation));
    assert_eq!(p.q(), &q[..]);
    assert!(p.finger_outputs().iter().all(|o| *o == Default::default()));
    p.set_q(model.q0()).unwrap();
    hold(&mut p, &targets, 5);
}

/// The masked linkage's ticks allocate nothing: through the dead point (the
/// projected step stopping early), the gradient rule, a refused tick.
#[test]
fn masked_ticks_allocate_nothing() {
    assert!(is_installed());
    let model = Arc::new(peaucellier([0.0, 0.0, -9.81]));
    let p0 = model.initial_targets()[0].position_m;
    let w = 2.0 * std::f64::consts::PI * 0.25;
    let circle: Vec<[FingerTarget; 1]> = (2500..2700)
        .map(|k| {
            let t = k as f64 * DT.as_secs_f64();
            [FingerTarget::at(
                p0 + Vector3::new((w * t).cos() - 1.0, (w * t).sin(), 0.0) * 0.015,
            )]
        })
        .collect();
    let mut p = Program::new(model.clone(), SolverSettings::default()).unwrap();
    let mut g = Program::new(model.clone(), settings(UpdateRule::Gradient)).unwrap();
    assert_eq!(p.redundancy().rows.len(), 9);
    // Drive to just before the dead point outside the counted section.
    for k in 0..2500 {
        let t = k as f64 * DT.as_secs_f64();
        let target = p0 + Vector3::new((w * t).cos() - 1.0, (w * t).sin(), 0.0) * 0.015;
        p.tick(&[FingerTarget::at(target)], DT);
    }
    let mut broken = model.q0().to_vec();
    broken[2] += 1.0;
    let (statuses, stats) = count(|| {
        let mut ok = 0;
        for t in &circle {
            ok += usize::from(p.tick(t, DT).status == TickOutcome::Ok);
            ok += usize::from(g.tick(t, DT).status == TickOutcome::Ok);
        }
        g.set_q(&broken).unwrap();
        (ok, g.tick(&circle[0], DT).status)
    });
    assert_eq!(stats.total(), 0, "allocations: {stats:?}");
    assert_eq!(statuses.0, 2 * circle.len());
    assert!(
        matches!(statuses.1, TickOutcome::Diverged(_)),
        "{statuses:?}"
    );
}

/// Not a test: prints what the redundancy check adds to `Program::new` per
/// built-in mechanism (median wall time of `Program::new` with the check
/// `Off`, `Auto` and `Dense`), for BENCHMARKS.md. Run with
/// `cargo test -p haptloop-solver --release --test al redundancy_cost -- --ignored --nocapture`.
#[test]
#[ignore = "a measurement; prints timings"]
fn redundancy_cost() {
    let median = |model: &Arc<Model>, mode: RedundancyCheck, runs: usize| {
        let s = SolverSettings {
            redundancy: mode,
            ..SolverSettings::default()
        };
        let mut t: Vec<f64> = (0..runs)
            .map(|_| {
                let start = std::time::Instant::now();
                let p = Program::new(model.clone(), s).unwrap();
                let dt = start.elapsed().as_secs_f64();
                std::hint::black_box(p);
                dt
            })
            .collect();
        t.sort_by(f64::total_cmp);
        t[runs / 2]
    };
    let g = [0.0, 0.0, -9.81];
    println!("| mechanism | rows × coords | masked | `new`, check off | `Auto` | `Dense` |");
    println!("|---|---|---|---|---|---|");
    for (name, model, runs) in [
        ("four-bar", four_bar(), 51),
        ("stewart", stewart(), 51),
        ("sphere-toy", sphere_toy(), 11),
        ("peaucellier", peaucellier(g), 51),
        ("planar four-bar", planar_four_bar(g), 51),
    ] {
        let model = Arc::new(model);
        let masked = program((*model).clone(), SolverSettings::default())
            .redundancy()
            .rows
            .len();
        let ms = |mode| 1e3 * median(&model, mode, runs);
        println!(
            "| {name} | {} × {} | {masked} | {:.3} ms | {:.3} ms | {:.3} ms |",
            model.n_rows(),
            model.n_coords(),
            ms(RedundancyCheck::Off),
            ms(RedundancyCheck::Auto),
            ms(RedundancyCheck::Dense),
        );
    }
}

/// n identical revolutes between the ground and one link: the per-body-pair
/// pass masks every row after the first joint's before A is built, so A's
/// factor keeps the size of a single joint whatever n is (it was a dense
/// 5n × 5n matrix), and the program behaves like the one-joint program.
#[test]
fn rows_dependent_within_a_body_pair_never_reach_the_force_factor() {
    let build = |n: usize| {
        Program::new(Arc::new(many_revolutes(n)), settings(UpdateRule::Projected)).unwrap()
    };
    let one = build(1);
    assert_eq!(one.redundancy().local, 0);
    for n in [2, 50, 400] {
        let p = build(n);
        let r = p.redundancy();
        assert_eq!(r.local, 5 * (n - 1), "n = {n}");
        assert_eq!(r.rows.len(), 5 * (n - 1), "n = {n}");
        assert_eq!(p.force_factor_nnz(), one.force_factor_nnz(), "n = {n}");
    }
    // And it still holds the link: one tick toward a displaced finger keeps
    // the joint rows satisfied as the single-joint program does.
    let (mut a, mut b) = (build(1), build(400));
    let mut targets = a.model().initial_targets();
    targets[0].position_m.x += 0.01;
    for _ in 0..50 {
        a.tick(&targets, Duration::from_millis(1));
        b.tick(&targets, Duration::from_millis(1));
    }
    let (ra, rb) = (a.last_report(), b.last_report());
    assert!(rb.max_violation_m < 1e-9, "{rb:?}");
    assert!((ra.max_violation_m - rb.max_violation_m).abs() < 1e-9);
    let (fa, fb) = (a.finger_outputs()[0].force_n, b.finger_outputs()[0].force_n);
    assert!(
        (fa - fb).norm() < 1e-6 * fa.norm().max(1e-3),
        "{fa} vs {fb}"
    );
}

/// A 12-cell ladder of pinned rods (12 closed loops): the ordered check, run
/// as a sparse factorisation in model order, masks 3 out-of-plane rows per
/// loop, and what it keeps is independent and has the rank of all the rows
/// (an SVD of the dense C_q, computed separately, is the judge).
#[test]
fn a_ladder_of_loops_masks_three_rows_per_loop_and_keeps_the_rank() {
    let model = ladder(12);
    let p = program(model.clone(), SolverSettings::default());
    let red = p.redundancy().clone();
    assert!(red.dense, "{red:?}");
    assert_eq!(red.rows.len(), 3 * 12, "{red:?}");
    let all = equality_rows(&model);
    let kept = without(&all, &red.rows);
    let r = rank(&model, &all);
    assert_eq!(rank(&model, &kept), r);
    assert_eq!(kept.len(), r);
}
