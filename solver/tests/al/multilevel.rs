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

use crate::common::*;
use crate::lockstep::{Followed, follow, moved, settings};

/// Ticks the multilevel tick in lockstep with the Cholesky tick over
/// `ticks` ticks of motion; returns the comparison and the multilevel
/// program.
fn follow_cholesky(model: &Arc<Model>, ticks: usize, name: &str) -> (Followed, Program) {
    let mut ml = Program::new(model.clone(), settings(ForceSolver::MULTILEVEL)).unwrap();
    let mut exact = Program::new(model.clone(), settings(ForceSolver::Cholesky)).unwrap();
    let f = follow(name, model, (&mut ml, &mut exact), ticks, |_, _, _| {});
    (f, ml)
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
        let (
            Followed {
                worst,
                scale,
                viol,
                its,
            },
            ml,
        ) = follow_cholesky(&model, ticks, name);
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
        let (
            Followed {
                worst,
                scale,
                viol,
                its,
            },
            ml,
        ) = follow_cholesky(&model, 10, name);
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
