//! The tree tick (`ForceSolver::Tree`): Eq. 7 and the projected steps by
//! conjugate gradients preconditioned by a spanning tree of the body graph
//! (`force::precond::tree`), against the Cholesky tick.

use std::sync::Arc;

use haptloop_rt::alloc::{count, is_installed};
use haptloop_solver::mechanisms::{bennett, chain_sized, four_bar, lattice_sized, sphere_toy};
use haptloop_solver::{
    FingerTarget, ForceSolver, Program, SolverSettings, TickOutcome, UpdateRule,
};

use crate::common::*;
use crate::lockstep::{Followed, follow, force_gap, moved, settings};

/// On mechanisms whose Gram matrix has no loop (a closed chain, a four-bar
/// and Bennett's 4R close their loop through the ground, which couples no
/// rows) the
/// spanning tree is the whole mechanism: P = A, so every force solve takes
/// at most one iteration and gives the Cholesky's force (to 1e-7: the
/// projected steps stop at a relative residual of 1e-6).
#[test]
fn without_loops_the_tree_is_exact() {
    for (name, model) in [
        ("chain 12", chain_sized(12).build().unwrap()),
        ("four-bar", four_bar()),
        ("bennett", bennett()),
    ] {
        let model = Arc::new(model);
        let mut tree = Program::new(model.clone(), settings(ForceSolver::TREE)).unwrap();
        let mut exact = Program::new(model.clone(), settings(ForceSolver::Cholesky)).unwrap();
        let st = tree.tree_stats().unwrap();
        assert_eq!(st.loop_rows, 0, "{st:?}");
        assert_eq!(st.p_nnz, st.a_nnz, "{st:?}");
        follow(
            name,
            &model,
            (&mut tree, &mut exact),
            20,
            |k, tree, exact| {
                let its = tree.force_cg_iterations();
                assert!(its <= 1, "{name} tick {k}: {its} iterations");
                let (gap, big) = force_gap(tree, exact);
                assert!(
                    gap <= 1e-7 * big.max(1e-3),
                    "{name} tick {k}: {gap:e} of {big:e} N"
                );
            },
        );
        assert_eq!(tree.matvec_unconverged(), 0);
    }
}

/// With loops among the moving bodies (a 2 × 4 lattice, the sphere toy)
/// the tree tick follows the Cholesky tick: the same violation order
/// and the same finger force to the solves' tolerance, over 60 ticks of
/// motion (12 in unoptimised builds), every solve converged.
#[test]
fn with_loops_the_tree_tick_follows_the_cholesky_tick() {
    for (name, model) in [
        ("lattice 2x4", lattice_sized(2, 4).build().unwrap()),
        ("sphere toy", sphere_toy()),
    ] {
        if cfg!(debug_assertions) && name == "sphere toy" {
            // Unoptimised builds: the lattice only (the sphere toy's CG
            // takes ~80 iterations a solve, seconds there).
            continue;
        }
        let model = Arc::new(model);
        let mut tree = Program::new(model.clone(), settings(ForceSolver::TREE)).unwrap();
        let mut exact = Program::new(model.clone(), settings(ForceSolver::Cholesky)).unwrap();
        let st = tree.tree_stats().unwrap();
        assert!(st.loop_rows > 0 && st.p_nnz < st.a_nnz, "{name}: {st:?}");
        // Unoptimised builds: 12 ticks (the CG solves cost 10× there).
        let ticks = if cfg!(debug_assertions) { 12 } else { 60 };
        let pair = (&mut tree, &mut exact);
        let Followed {
            worst,
            scale,
            viol,
            its: its_max,
        } = follow(name, &model, pair, ticks, |_, _, _| {});
        assert!(its_max > 1, "{name}: loops need iterations");
        assert_eq!(tree.matvec_unconverged(), 0, "{name}");
        assert!(viol < 1e-6, "{name}: violation {viol:e}");
        assert!(
            worst <= 1e-6 * scale.max(1e-2),
            "{name}: force off by {worst:e} N of {scale:e} N"
        );
    }
}

/// The tree tick allocates nothing, with the projected and the gradient
/// update.
#[test]
fn tree_ticks_allocate_nothing() {
    assert!(is_installed());
    let model = Arc::new(lattice_sized(2, 4).build().unwrap());
    for update in [UpdateRule::Projected, UpdateRule::Gradient] {
        let s = SolverSettings {
            update,
            ..settings(ForceSolver::TREE)
        };
        let mut p = Program::new(model.clone(), s).unwrap();
        let targets: Vec<Vec<FingerTarget>> =
            (0..20).map(|k| moved(&model, 1e-4 * k as f64)).collect();
        assert_eq!(p.tick(&targets[0], DT).status, TickOutcome::Ok);
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
fn what_the_tree_tick_accepts() {
    assert!(
        settings(ForceSolver::Tree { max_iterations: 0 })
            .validate()
            .is_err()
    );
    assert!(
        settings(ForceSolver::Tree {
            max_iterations: 1001
        })
        .validate()
        .is_err()
    );
    assert!(settings(ForceSolver::TREE).validate().is_ok());
    assert_eq!(ForceSolver::TREE.label(), "tree");
    assert_eq!(ForceSolver::Tree { max_iterations: 16 }.label(), "tree:16");
}
