//! The matvec-only tick (`ForceSolver::Matvec`): Eq. 7 by conjugate
//! gradients preconditioned by a factor the slow thread refreshes, the
//! projected update stepping with that factor, no factorisation in a tick.

use std::sync::Arc;

use haptloop_rt::alloc::{count, is_installed};
use haptloop_solver::mechanisms::{lattice_sized, sphere_toy, stewart};
use haptloop_solver::{
    FingerTarget, ForceSolver, Model, Program, SolverSettings, TickOutcome, UpdateRule,
};
use nalgebra::Vector3;

use crate::common::*;

fn matvec(max_iterations: u32) -> SolverSettings {
    SolverSettings {
        step: 1.0,
        iterations: 3,
        force_solver: ForceSolver::Matvec { max_iterations },
        ..SolverSettings::default()
    }
}

fn cholesky() -> SolverSettings {
    SolverSettings {
        force_solver: ForceSolver::Cholesky,
        ..matvec(1)
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

/// At the same configuration the matvec force solve, preconditioned by a
/// factor refreshed at another configuration (q0, the slow thread's, the
/// targets 3 mm back), converges to the Cholesky force solve's finger force
/// (a direct solve of the same Eq. 7); with a factor refreshed at the
/// configuration itself it needs at most one iteration.
#[test]
fn a_stale_factor_preconditions_the_cholesky_force() {
    for model in [
        stewart(),
        sphere_toy(),
        lattice_sized(2, 8).build().unwrap(),
    ] {
        let model = Arc::new(model);
        let mut fast = Program::new(model.clone(), matvec(100)).unwrap();
        let mut exact = Program::new(model.clone(), cholesky()).unwrap();
        let mut refresher = fast.factor_refresher().expect("matvec program");
        let mut f = refresher.buffer();
        assert!(refresher.refresh(model.q0(), &mut f));
        assert!(fast.adopt_factor(&mut f));
        assert!(!fast.adopt_factor(&mut f), "adopted twice");
        let t = moved(&model, 3e-3);
        for _ in 0..60 {
            assert_eq!(exact.tick(&t, DT).status, TickOutcome::Ok);
        }
        // Both from the same (converged, at rest) state, one tick at the
        // same targets: the update has nothing left to do, so the forces
        // are those of the same Eq. 7.
        let q = exact.q().to_vec();
        for fresh in [false, true] {
            if fresh {
                assert!(refresher.refresh(&q, &mut f));
                assert!(fast.adopt_factor(&mut f));
            }
            fast.set_q(&q).unwrap();
            exact.set_q(&q).unwrap();
            assert_eq!(fast.tick(&t, DT).status, TickOutcome::Ok);
            assert_eq!(exact.tick(&t, DT).status, TickOutcome::Ok);
            let its = fast.force_cg_iterations();
            if fresh {
                // 0 when the warm start (the same solve) already converged.
                assert!(its <= 1, "n {}: {its}", model.n_rows());
            } else {
                assert!((1..100).contains(&its), "{its} iterations");
            }
            for (a, b) in fast.finger_outputs().iter().zip(exact.finger_outputs()) {
                let (fa, fb) = (a.constraint_force_n, b.constraint_force_n);
                // The lattice's joints carry its weight (the finger feels
                // ~0 at rest); Stewart's and the sphere toy's fingers do.
                assert!(
                    (fa - fb).norm() <= 1e-8 * fb.norm().max(1e-2),
                    "{fa} vs {fb}"
                );
            }
        }
    }
}

/// A factor refreshed for another program is not adopted, and one made
/// for this program survives a round trip: the adopted values come back in
/// the box, not fresh.
#[test]
fn only_the_programs_own_refresh_is_adopted() {
    let model = Arc::new(stewart());
    let mut a = Program::new(model.clone(), matvec(4)).unwrap();
    let b = Program::new(model.clone(), matvec(4)).unwrap();
    let mut rb = b.factor_refresher().unwrap();
    let mut f = rb.buffer();
    assert!(rb.refresh(model.q0(), &mut f));
    assert!(f.is_fresh());
    assert!(!a.adopt_factor(&mut f));
    assert!(f.is_fresh(), "refused, still fresh");
    assert_eq!(a.factor_adoptions(), 0);
    let mut ra = a.factor_refresher().unwrap();
    assert!(ra.refresh(model.q0(), &mut f));
    assert!(a.adopt_factor(&mut f));
    assert!(!f.is_fresh());
    assert_eq!(a.factor_adoptions(), 1);
    assert!(
        Program::new(model, cholesky())
            .unwrap()
            .factor_refresher()
            .is_none()
    );
}

/// Following a moving target with refreshes every 5 ticks, the matvec
/// tick keeps the sphere toy within the scene's 1 µm (the Cholesky tick:
/// 1e-10 m; the matvec tick 4e-8 m four ticks after a refresh) and renders
/// the Cholesky tick's force within a small fraction of it.
#[test]
fn the_matvec_tick_follows_the_cholesky_tick() {
    let model = Arc::new(sphere_toy());
    let mut fast = Program::new(model.clone(), matvec(4)).unwrap();
    let mut exact = Program::new(model.clone(), cholesky()).unwrap();
    let mut refresher = fast.factor_refresher().unwrap();
    let mut f = refresher.buffer();
    let (mut worst, mut scale, mut viol) = (0.0f64, 0.0f64, 0.0f64);
    for k in 0..200 {
        let a = 0.004 * (k as f64 * 0.02).sin();
        let t = moved(&model, a);
        if k % 5 == 0 {
            assert!(refresher.refresh(fast.q(), &mut f));
            fast.adopt_factor(&mut f);
        }
        assert_eq!(fast.tick(&t, DT).status, TickOutcome::Ok, "tick {k}");
        assert_eq!(exact.tick(&t, DT).status, TickOutcome::Ok, "tick {k}");
        viol = viol.max(fast.last_report().max_violation_m);
        let (fa, fb) = (
            fast.finger_outputs()[0].force_n,
            exact.finger_outputs()[0].force_n,
        );
        worst = worst.max((fa - fb).norm());
        scale = scale.max(fb.norm());
    }
    assert!(viol < 1e-6, "violation {viol:e}");
    assert!(
        worst < 1e-3 * scale,
        "force off by {worst:e} N of {scale:e} N"
    );
    assert_eq!(fast.factor_adoptions(), 40);
}

/// The matvec tick and the adoption of a refreshed factor allocate nothing.
#[test]
fn matvec_ticks_and_adoptions_allocate_nothing() {
    assert!(is_installed());
    let model = Arc::new(sphere_toy());
    let mut p = Program::new(model.clone(), matvec(4)).unwrap();
    let mut refresher = p.factor_refresher().unwrap();
    let mut boxes = [refresher.buffer(), refresher.buffer()];
    for b in &mut boxes {
        assert!(refresher.refresh(model.q0(), b));
    }
    let targets: Vec<Vec<FingerTarget>> = (0..50).map(|k| moved(&model, 1e-4 * k as f64)).collect();
    let (ok, stats) = count(|| {
        let mut ok = 0;
        for (k, t) in targets.iter().enumerate() {
            if k % 20 == 0 {
                p.adopt_factor(&mut boxes[k / 20 % 2]);
            }
            ok += usize::from(p.tick(t, DT).status == TickOutcome::Ok);
        }
        ok
    });
    assert_eq!(stats.total(), 0, "allocations: {stats:?}");
    assert_eq!(ok, targets.len());
    assert_eq!(p.factor_adoptions(), 2);
}

/// The settings refuse a cap of 0; the gradient rule runs the matvec tick
/// (no factor in its update, CG in its force solve).
#[test]
fn what_the_matvec_tick_covers() {
    assert!(matvec(0).validate().is_err());
    assert!(matvec(4).validate().is_ok());
    let gradient = SolverSettings {
        update: UpdateRule::Gradient,
        ..matvec(4)
    };
    let mut p = Program::new(Arc::new(stewart()), gradient).unwrap();
    let t = moved(p.model(), 1e-3);
    assert_eq!(p.tick(&t, DT).status, TickOutcome::Ok);
    assert!(p.factor_refresher().is_some());
}
