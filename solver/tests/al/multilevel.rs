//! The multilevel tick (`ForceSolver::Multilevel`): Eq. 7 and the projected
//! steps by conjugate gradients preconditioned by an aggregation V-cycle
//! (`force::precond::multilevel`), against the Cholesky tick.

use std::sync::Arc;

use haptloop_rt::alloc::{count, is_installed};
use haptloop_solver::mechanisms::{
    bennett, chain_sized, lattice_shape, lattice_sized, sphere_toy, sphere_toy_shape,
    sphere_toy_sized,
};
use haptloop_solver::{
    FingerTarget, ForceSolver, Model, Program, SolverSettings, TickOutcome, UpdateRule,
};
use nalgebra::Vector3;

use crate::common::*;

fn settings(force_solver: ForceSolver) -> SolverSettings {
    SolverSettings {
        step: 1.0,
        iterations: 3,
        force_solver,
        ..SolverSettings::default()
    }
}

/// Targets moved `a` metres along a fixed direction.
fn moved(model: &Model, a: f64) -> Vec<FingerTarget> {
    model
        .initial_targets()
        .into_iter()
        .map(|t| FingerTarget::at(t.position_m + Vector3::new(0.6, -0.3, 0.2) * a))
        .collect()
}

/// Largest finger-force difference between two programs, and the largest
/// force (N).
fn force_gap(a: &Program, b: &Program) -> (f64, f64) {
    a.finger_outputs()
        .iter()
        .zip(b.finger_outputs())
        .fold((0.0, 0.0), |(gap, big), (x, y)| {
            let (fx, fy) = (x.constraint_force_n, y.constraint_force_n);
            (gap.max((fx - fy).norm()), big.max(fy.norm()))
        })
}

/// Runs `ticks` ticks of motion on both; returns the largest force gap,
/// the largest force, the largest violation of the multilevel tick, and
/// the largest force-solve iteration count.
fn follow(model: &Arc<Model>, ticks: usize, name: &str) -> (f64, f64, f64, u32, Program) {
    let mut ml = Program::new(model.clone(), settings(ForceSolver::MULTILEVEL)).unwrap();
    let mut exact = Program::new(model.clone(), settings(ForceSolver::Cholesky)).unwrap();
    let (mut worst, mut scale, mut viol, mut its) = (0.0f64, 0.0f64, 0.0f64, 0);
    for k in 0..ticks {
        let t = moved(model, 0.003 * (k as f64 * 0.05).sin());
        assert_eq!(ml.tick(&t, DT).status, TickOutcome::Ok, "{name} {k}");
        assert_eq!(exact.tick(&t, DT).status, TickOutcome::Ok, "{name} {k}");
        viol = viol.max(ml.last_report().max_violation_m);
        its = its.max(ml.force_cg_iterations());
        let (gap, big) = force_gap(&ml, &exact);
        worst = worst.max(gap);
        scale = scale.max(big);
    }
    (worst, scale, viol, its, ml)
}

/// On mechanisms with and without loops among the moving bodies (a chain,
/// Bennett's 4R, a 2 × 4 lattice, the sphere toy) the multilevel tick
/// follows the Cholesky tick: the same finger force to the solves'
/// tolerance and violations under the scenes' 1e-6 m, over 60 ticks of
/// motion (12 in unoptimised builds, without the sphere toy), every solve
/// converged.
#[test]
fn the_multilevel_tick_follows_the_cholesky_tick() {
    for (name, model) in [
        ("chain 12", chain_sized(12).build().unwrap()),
        ("bennett", bennett()),
        ("lattice 2x4", lattice_sized(2, 4).build().unwrap()),
        ("sphere toy", sphere_toy()),
    ] {
        if cfg!(debug_assertions) && name == "sphere toy" {
            // Unoptimised builds: the small meshes only (the sphere toy's
            // CG takes ~50 iterations a force solve, seconds there).
            continue;
        }
        let model = Arc::new(model);
        let ticks = if cfg!(debug_assertions) { 12 } else { 60 };
        let (worst, scale, viol, its, ml) = follow(&model, ticks, name);
        assert!(its >= 1, "{name}: no iteration");
        assert_eq!(ml.matvec_unconverged(), 0, "{name}");
        assert!(viol < 1e-6, "{name}: violation {viol:e}");
        assert!(
            worst <= 1e-6 * scale.max(1e-2),
            "{name}: force off by {worst:e} N of {scale:e} N"
        );
    }
}

/// Larger meshes (a 128-bar lattice, a 132-body sphere toy) coarsen to
/// more than one level and the tick still gives the Cholesky's force
/// (their iteration counts, which grow with size, are measured in
/// BENCHMARKS.md, not asserted). Release builds only (seconds
/// unoptimised).
#[test]
fn larger_meshes_coarsen_and_follow_the_cholesky_tick() {
    if cfg!(debug_assertions) {
        return;
    }
    let (lr, lc) = lattice_shape(128).unwrap();
    let (sr, sc) = sphere_toy_shape(132).unwrap();
    for (name, model) in [
        ("lattice 128", lattice_sized(lr, lc).build().unwrap()),
        ("sphere toy 132", sphere_toy_sized(sr, sc).build().unwrap()),
    ] {
        let model = Arc::new(model);
        let (worst, scale, viol, its, ml) = follow(&model, 10, name);
        let st = ml.multilevel_stats().unwrap();
        assert!(st.rows.len() >= 2, "{name}: {st:?}");
        assert_eq!(ml.matvec_unconverged(), 0, "{name}");
        assert!(viol < 1e-6, "{name}: violation {viol:e}");
        assert!(
            worst <= 1e-6 * scale.max(1e-2),
            "{name}: force off by {worst:e} N of {scale:e} N"
        );
        assert!(its >= 1, "{name}: no iteration");
    }
}

/// The multilevel tick allocates nothing, with the projected and the
/// gradient update (its first factorisation, which builds the
/// prolongation, included).
#[test]
fn multilevel_ticks_allocate_nothing() {
    assert!(is_installed());
    let model = Arc::new(lattice_sized(2, 4).build().unwrap());
    for update in [UpdateRule::Projected, UpdateRule::Gradient] {
        let s = SolverSettings {
            update,
            ..settings(ForceSolver::MULTILEVEL)
        };
        let mut p = Program::new(model.clone(), s).unwrap();
        let targets: Vec<Vec<FingerTarget>> =
            (0..20).map(|k| moved(&model, 1e-4 * k as f64)).collect();
        let (ok, stats) = count(|| {
            targets
                .iter()
                .filter(|t| p.tick(t, DT).status == TickOutcome::Ok)
                .count()
        });
        assert_eq!(stats.total(), 0, "{update:?}: allocations {stats:?}");
        assert_eq!(ok, targets.len());
        assert!(p.force_cg_iterations() > 0);
    }
}

/// The settings refuse a cap of 0 or above 1000; the label round-trips the
/// command line's spelling.
#[test]
fn what_the_multilevel_tick_accepts() {
    for bad in [0, 1001] {
        let s = settings(ForceSolver::Multilevel {
            max_iterations: bad,
        });
        assert!(s.validate().is_err(), "{bad}");
    }
    assert!(settings(ForceSolver::MULTILEVEL).validate().is_ok());
    assert_eq!(ForceSolver::MULTILEVEL.label(), "multilevel");
    assert_eq!(
        ForceSolver::Multilevel { max_iterations: 16 }.label(),
        "multilevel:16"
    );
}
