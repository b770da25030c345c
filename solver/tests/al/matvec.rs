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

/// The matvec tick at the default cap on the two mechanisms where the
/// old cap of 4 failed ticks (Bennett's overconstrained loop, the 4 × 16
/// lattice with its 192 masked rows): a factor refreshed every 5 ticks (the
/// slow loop's 5 ms at 1 kHz), the targets moving 1 cm back and forth. No
/// tick fails, fewer solves than ticks stop at the cap (each is redone with
/// a factorisation in the tick), the violation
/// stays at the Cholesky tick's, and the finger force is the Cholesky
/// tick's (a direct factorisation of the same Eq. 7) to 1e-6 of the
/// largest force.
#[test]
fn the_default_matvec_tick_fails_no_tick_on_bennett_and_the_lattice() {
    use haptloop_solver::mechanisms::{bennett, lattice};
    for (name, model) in [("bennett", bennett()), ("lattice", lattice())] {
        // The lattice's matvec tick costs ~8 ms optimised: release only
        // (the debug run keeps Bennett).
        if cfg!(debug_assertions) && name == "lattice" {
            continue;
        }
        let model = Arc::new(model);
        let s = SolverSettings {
            iterations: 4,
            force_solver: ForceSolver::MATVEC,
            ..SolverSettings::default()
        };
        let e = SolverSettings {
            force_solver: ForceSolver::Cholesky,
            ..s
        };
        let mut fast = Program::new(model.clone(), s).unwrap();
        let mut exact = Program::new(model.clone(), e).unwrap();
        let mut refresher = fast.factor_refresher().unwrap();
        let mut f = refresher.buffer();
        let (mut worst, mut scale, mut viol, mut viol_exact) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
        let ticks = if cfg!(debug_assertions) { 40 } else { 120 };
        for k in 0..ticks {
            let t = moved(&model, 0.01 * (k as f64 * 0.05).sin());
            if k % 5 == 0 {
                assert!(refresher.refresh(fast.q(), &mut f), "{name} tick {k}");
                assert!(fast.adopt_factor(&mut f), "{name} tick {k}");
            }
            assert_eq!(fast.tick(&t, DT).status, TickOutcome::Ok, "{name} tick {k}");
            assert_eq!(
                exact.tick(&t, DT).status,
                TickOutcome::Ok,
                "{name} tick {k}"
            );
            viol = viol.max(fast.last_report().max_violation_m);
            viol_exact = viol_exact.max(exact.last_report().max_violation_m);
            for (a, b) in fast.finger_outputs().iter().zip(exact.finger_outputs()) {
                worst = worst.max((a.force_n - b.force_n).norm());
                scale = scale.max(b.force_n.norm());
            }
        }
        // A solve that hits the cap is redone with a factorisation in the
        // tick; most of the 5 solves a tick must stay matvec-only.
        let capped = fast.matvec_unconverged();
        assert!(
            capped < ticks as u64,
            "{name}: {capped} solves at the cap in {ticks} ticks"
        );
        assert!(
            scale > 1e-3,
            "{name}: the fingers felt nothing ({scale:e} N)"
        );
        assert!(
            viol <= 10.0 * viol_exact.max(1e-10),
            "{name}: violation {viol:e} m against the Cholesky tick's {viol_exact:e} m"
        );
        assert!(
            worst <= 1e-6 * scale,
            "{name}: force off by {worst:e} N of {scale:e} N"
        );
    }
}

/// `cargo test --release -p haptloop-solver --test al probe_matvec -- --ignored --nocapture`:
/// failed ticks of the matvec tick on Bennett and the lattice against the
/// refresh interval and the cap (prints; BENCHMARKS.md, issue 23).
#[test]
#[ignore]
fn probe_matvec_failures() {
    use haptloop_solver::mechanisms::{bennett, lattice};
    for (name, model) in [("bennett", bennett()), ("lattice", lattice())] {
        let model = Arc::new(model);
        for (every, cap) in [(1, 4), (5, 4), (5, 8), (5, 16), (1, 64), (5, 64), (20, 64)] {
            let s = SolverSettings {
                iterations: 4,
                force_solver: ForceSolver::Matvec {
                    max_iterations: cap,
                },
                ..SolverSettings::default()
            };
            let mut fast = Program::new(model.clone(), s).unwrap();
            let mut refresher = fast.factor_refresher().unwrap();
            let mut f = refresher.buffer();
            let (mut fails, mut viol, mut cg) = (0, 0.0f64, 0u32);
            let mut first = None;
            for k in 0..200 {
                let t = moved(&model, 0.01 * (k as f64 * 0.02).sin());
                if k % every == 0 {
                    assert!(refresher.refresh(fast.q(), &mut f));
                    fast.adopt_factor(&mut f);
                }
                let r = fast.tick(&t, DT);
                if r.status != TickOutcome::Ok {
                    fails += 1;
                    first.get_or_insert((k, r.status));
                } else {
                    viol = viol.max(r.max_violation_m);
                    cg = cg.max(fast.force_cg_iterations());
                }
            }
            println!(
                "{name} refresh every {every} ticks, cap {cap}: {fails} failed of 200 (first {first:?}), \
                 max violation {viol:e} m, force CG max {cg} it., solves at the cap {}",
                fast.matvec_unconverged()
            );
        }
    }
}

/// `cargo test --release -p haptloop-solver --test al probe_matvec_scaling -- --ignored --nocapture`:
/// cost against size, the Cholesky tick and the matvec tick (a factor
/// refreshed every 5 ticks, the refresh not timed: the slow thread's), on
/// the lattice at 32 / 128 / 512 bars and the sphere toy at 33 / 132 / 400
/// bodies; median tick (wall clock) of 3 interleaved rounds, and the fitted
/// exponent of each family (prints).
#[test]
#[ignore]
fn probe_matvec_scaling() {
    use haptloop_solver::mechanisms::{
        lattice_shape, lattice_sized, sphere_toy_shape, sphere_toy_sized,
    };
    use std::time::Instant;
    let families: [(&str, Vec<(usize, Model)>); 2] = [
        (
            "lattice",
            [32, 128, 512]
                .iter()
                .map(|&b| {
                    let (r, c) = lattice_shape(b).unwrap();
                    let m = lattice_sized(r, c).build().unwrap();
                    (m.bodies().len(), m)
                })
                .collect(),
        ),
        (
            "sphere toy",
            [33, 132, 400]
                .iter()
                .map(|&b| {
                    let (r, c) = sphere_toy_shape(b).unwrap();
                    let m = sphere_toy_sized(r, c).build().unwrap();
                    (m.bodies().len(), m)
                })
                .collect(),
        ),
    ];
    // The tree tick (0.3–0.8 s a tick at the largest sizes) only when asked.
    let with_tree = std::env::var_os("HAPTLOOP_PROBE_TREE").is_some();
    for (family, sizes) in families {
        let mut pts = Vec::new();
        for (bodies, model) in sizes {
            let model = Arc::new(model);
            let s = SolverSettings {
                iterations: 4,
                force_solver: ForceSolver::MATVEC,
                ..SolverSettings::default()
            };
            let with = |force_solver| SolverSettings { force_solver, ..s };
            let mut fast = Program::new(model.clone(), s).unwrap();
            let mut exact = Program::new(model.clone(), with(ForceSolver::Cholesky)).unwrap();
            let mut tree = Program::new(model.clone(), with(ForceSolver::TREE)).unwrap();
            let mut ml = Program::new(model.clone(), with(ForceSolver::MULTILEVEL)).unwrap();
            let (mut t_tr, mut cg_tr) = (Vec::new(), 0u64);
            let (mut t_ml, mut cg_ml) = (Vec::new(), 0u64);
            let mut refresher = fast.factor_refresher().unwrap();
            let mut f = refresher.buffer();
            let ticks = 40;
            let (mut t_mv, mut t_ch) = (Vec::new(), Vec::new());
            let (mut cg, mut k_all) = (0u64, 0usize);
            for round in 0..3 {
                for k in 0..ticks {
                    let kk = round * ticks + k;
                    let t = moved(&model, 0.005 * (kk as f64 * 0.05).sin());
                    if kk % 5 == 0 {
                        assert!(refresher.refresh(fast.q(), &mut f));
                        fast.adopt_factor(&mut f);
                    }
                    let s0 = Instant::now();
                    assert_eq!(fast.tick(&t, DT).status, TickOutcome::Ok);
                    t_mv.push(s0.elapsed().as_secs_f64());
                    cg += u64::from(fast.force_cg_iterations());
                    let s0 = Instant::now();
                    assert_eq!(exact.tick(&t, DT).status, TickOutcome::Ok);
                    t_ch.push(s0.elapsed().as_secs_f64());
                    let s0 = Instant::now();
                    assert_eq!(ml.tick(&t, DT).status, TickOutcome::Ok);
                    t_ml.push(s0.elapsed().as_secs_f64());
                    cg_ml += u64::from(ml.force_cg_iterations());
                    if with_tree {
                        let s0 = Instant::now();
                        assert_eq!(tree.tick(&t, DT).status, TickOutcome::Ok);
                        t_tr.push(s0.elapsed().as_secs_f64());
                        cg_tr += u64::from(tree.force_cg_iterations());
                    }
                    k_all += 1;
                }
            }
            let med = |v: &mut Vec<f64>| {
                if v.is_empty() {
                    return f64::NAN;
                }
                v.sort_by(|a, b| a.partial_cmp(b).unwrap());
                v[v.len() / 2] * 1e6
            };
            let (mv, ch, tt) = (med(&mut t_mv), med(&mut t_ch), med(&mut t_tr));
            let mlt = med(&mut t_ml);
            if with_tree {
                let st = tree.tree_stats().unwrap();
                println!(
                    "{family} {bodies} bodies: tree {tt:.1} µs ({:.2}× cholesky), force CG {:.1} it./tick, step CG {:.1} it./tick, unconverged {}, A nnz {}, P nnz {}, P factor {} values, loop rows {}",
                    tt / ch,
                    cg_tr as f64 / k_all as f64,
                    st.step_iterations as f64 / k_all as f64,
                    tree.matvec_unconverged(),
                    st.a_nnz,
                    st.p_nnz,
                    st.factor_values,
                    st.loop_rows
                );
            }
            let st = ml.multilevel_stats().unwrap();
            println!(
                "{family} {bodies} bodies: multilevel {mlt:.1} µs ({:.2}× cholesky), force CG {:.1} it./tick, step CG {:.1} it./tick, unconverged {}, level rows {:?}, level values {}",
                mlt / ch,
                cg_ml as f64 / k_all as f64,
                st.step_iterations as f64 / k_all as f64,
                ml.matvec_unconverged(),
                st.rows,
                st.values
            );
            println!(
                "{family} {bodies} bodies ({} rows, factor {} values): cholesky {ch:.1} µs, matvec {mv:.1} µs ({:.2}×), force CG {:.1} it./tick, solves at the cap {:.2}/tick",
                model.n_rows(),
                exact.force_factor_nnz(),
                mv / ch,
                cg as f64 / k_all as f64,
                fast.matvec_unconverged() as f64 / k_all as f64
            );
            pts.push((bodies as f64, ch, mv, tt, mlt));
        }
        // (bodies, cholesky µs, matvec µs, tree µs, multilevel µs)
        type Point = (f64, f64, f64, f64, f64);
        let fit = |y: &dyn Fn(&Point) -> f64| {
            let n = pts.len() as f64;
            let (mx, my) = (
                pts.iter().map(|p| p.0.ln()).sum::<f64>() / n,
                pts.iter().map(|p| y(p).ln()).sum::<f64>() / n,
            );
            let sxy: f64 = pts.iter().map(|p| (p.0.ln() - mx) * (y(p).ln() - my)).sum();
            let sxx: f64 = pts.iter().map(|p| (p.0.ln() - mx).powi(2)).sum();
            sxy / sxx
        };
        println!(
            "{family}: exponent cholesky {:.2}, matvec {:.2}, tree {:.2}, multilevel {:.2}",
            fit(&|p| p.1),
            fit(&|p| p.2),
            fit(&|p| p.3),
            fit(&|p| p.4)
        );
    }
}
