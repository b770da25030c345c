//! `cargo test --release -p haptloop-solver --lib reduced::probe -- --ignored
//! --nocapture` (`HAPTLOOP_REDUCED_PROBE=four-bar,lattice` to choose scenes):
//! at the q a `Program` reaches after 300 ticks of the hand on a 2 mm
//! circle, interleaved, the thread's CPU time per call of
//!
//! - augmented: `Program::refresh` (evaluate C, C_q; the force stage: b,
//!   assembly of A, its sparse factor, the finger solve, the wrench), and one
//!   projected step (`Program::iterate`, 1 iteration);
//! - joint space: evaluate C, C_q (the same call), then [`JointSpace`]'s
//!   assemble (S's twists, H by composite inertias, J_r S), factor (H, W,
//!   the loop block, Σ_F) and finger solve; and a Gauss–Newton step's
//!   work (forward kinematics, evaluate, assemble, factor).
//!
//! Best and median of 9 rounds. Prints; asserts only that the calls succeed.

use super::{JointSpace, displace};
use crate::{Program, TickOutcome};

fn cpu_now() -> f64 {
    let mut ts = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `ts` is a valid, writable timespec.
    unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut ts) };
    ts.tv_sec as f64 + ts.tv_nsec as f64 * 1e-9
}

/// µs per call of `f` over `reps` calls.
fn time(reps: usize, mut f: impl FnMut()) -> f64 {
    let t = cpu_now();
    for _ in 0..reps {
        f();
    }
    (cpu_now() - t) / reps as f64 * 1e6
}

fn stats(mut v: Vec<f64>) -> (f64, f64) {
    v.sort_by(f64::total_cmp);
    (v[0], v[v.len() / 2])
}

fn program(name: &str) -> Program {
    super::tests::program_after(name, 300)
}

#[test]
#[ignore]
fn probe() {
    let list = std::env::var("HAPTLOOP_REDUCED_PROBE")
        .unwrap_or_else(|_| "four-bar,bennett,peaucellier,lattice".into());
    for name in list.split(',').filter(|s| !s.is_empty()) {
        let mut p = program(name);
        let model = p.model_arc().clone();
        let q = p.q().to_vec();
        let targets = super::tests::targets(&model, &q);
        let mut ev = model.evaluation();
        ev.evaluate(&model, &q, &targets).unwrap();
        let mut js = JointSpace::new(&model, &q, &ev).unwrap();
        let mut b: Vec<f64> = vec![0.0; model.n_coords()];
        let masses = crate::force::inertia::BodyMass::of_model(&model);
        let g = model.gravity_m_s2();
        let zero3 = nalgebra::Vector3::zeros();
        // b = Q_e + Q_v − M q̈ per body, as the force stage forms it (at rest:
        // the motion estimate is not timed on either side's account).
        let rhs = |b: &mut [f64]| {
            for m in &masses {
                let o = m.offset;
                let fr = crate::rotation::BodyFrame::new(
                    nalgebra::Vector3::new(q[o], q[o + 1], q[o + 2]),
                    [q[o + 3], q[o + 4], q[o + 5], q[o + 6]],
                )
                .unwrap();
                m.generalized_force(&fr, &g, &zero3, &zero3, &zero3, &mut b[o..o + 7]);
            }
        };
        rhs(&mut b);
        let mut q2 = q.clone();
        let zero = vec![0.0; js.tree.dofs()];
        let (n_j, m_f, nnz) = p.feedback().gram_size();
        println!(
            "{name}: augmented {} coords × {} rows (A: n_J {n_j}, m_f {m_f}, nnz lower {nnz}; {} masked); \
             joint space {} dofs ({} tree joints), {} loop rows ({} masked), {} finger rows",
            model.n_coords(),
            model.n_rows(),
            p.redundancy().rows.len(),
            js.tree.dofs(),
            js.tree.tree_joints(),
            js.tree.loop_rows().len(),
            js.masked(),
            js.tree.finger_rows().len()
        );
        // Calibrate: about 20 ms a measurement.
        let once = time(3, || assert_eq!(p.refresh(), TickOutcome::Ok));
        let reps = ((20_000.0 / once.max(0.1)) as usize).clamp(5, 20_000);
        let mut t: [Vec<f64>; 8] = Default::default();
        for _ in 0..9 {
            t[0].push(time(reps, || assert_eq!(p.refresh(), TickOutcome::Ok)));
            // At a converged q and the same targets: q barely moves.
            t[1].push(time(reps, || {
                let _ = p.iterate(&targets, 1);
            }));
            t[2].push(time(reps, || ev.evaluate(&model, &q, &targets).unwrap()));
            t[3].push(time(reps, || js.assemble(&model, &q, &ev).unwrap()));
            t[4].push(time(reps, || {
                js.assemble(&model, &q, &ev).unwrap();
                js.factor().unwrap();
            }));
            t[5].push(time(reps, || {
                let _ = js.finger_solve(&model, &b);
            }));
            t[6].push(time(reps, || {
                ev.evaluate(&model, &q, &targets).unwrap();
                rhs(&mut b);
                js.assemble(&model, &q, &ev).unwrap();
                js.factor().unwrap();
                let _ = js.finger_solve(&model, &b);
            }));
            t[7].push(time(reps, || {
                displace(&model, &js.tree, &js.kin, &q, &zero, &mut q2);
                ev.evaluate(&model, &q2, &targets).unwrap();
                js.assemble(&model, &q2, &ev).unwrap();
                js.factor().unwrap();
            }));
        }
        let s: Vec<(f64, f64)> = t.into_iter().map(stats).collect();
        let line = |label: &str, (best, med): (f64, f64)| {
            println!("  {label:<58} best {best:8.2} µs  median {med:8.2} µs");
        };
        line("augmented: evaluate + force stage (Program::refresh)", s[0]);
        line("augmented: one projected step (Program::iterate, 1)", s[1]);
        line("evaluate C, C_q (shared)", s[2]);
        line("joint: assemble (twists, H by CRBA, J_r S)", s[3]);
        line("joint: assemble + factor (H, W, W_LL, Σ_F)", s[4]);
        line("joint: finger solve (Sᵀb, two sweeps, Σ_F⁺)", s[5]);
        line(
            "joint: evaluate + b + assemble + factor + finger solve",
            s[6],
        );
        line(
            "joint: Gauss–Newton step work (FK + evaluate + assemble + factor)",
            s[7],
        );
        println!(
            "  ratio joint / augmented force stage (medians): {:.2}",
            s[6].1 / s[0].1
        );
    }
}
