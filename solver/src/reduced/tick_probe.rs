//! `cargo test --release -p haptloop-solver --lib reduced::tick_probe --
//! --ignored --nocapture` (`HAPTLOOP_TICK_PROBE=four-bar` to choose
//! scenes): the augmented `Program::tick` and the joint tick over the same
//! hand path (2 mm circle, 500 ticks a turn; 4 mm on Peaucellier), each from
//! the scene's assembled q, interleaved in rounds of ≈ 20 ms (the order
//! alternating), the thread's CPU time per tick; and, at a fixed state, the
//! joint tick's update alone and its loop/finger evaluation alone. Best and
//! median of 9 rounds, and the median of the per-round ratios.
//! `HAPTLOOP_TICK_PROBE_EXTRA=k` gives the joint tick k more update steps
//! than the scene's (the augmented tick keeps the scene's). Prints;
//! asserts only that the ticks succeed.

use std::time::Duration;

use super::JointTick;
use super::tick_tests::hand;
use crate::TickOutcome;

fn cpu_now() -> f64 {
    let mut ts = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `ts` is a valid, writable timespec.
    unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut ts) };
    ts.tv_sec as f64 + ts.tv_nsec as f64 * 1e-9
}

fn stats(mut v: Vec<f64>) -> (f64, f64) {
    v.sort_by(f64::total_cmp);
    (v[0], v[v.len() / 2])
}

#[test]
#[ignore]
fn tick_probe() {
    let list = std::env::var("HAPTLOOP_TICK_PROBE")
        .unwrap_or_else(|_| "four-bar,bennett,peaucellier".into());
    let extra: u32 = std::env::var("HAPTLOOP_TICK_PROBE_EXTRA")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(0);
    for name in list.split(',').filter(|s| !s.is_empty()) {
        let radius = if name == "peaucellier" { 0.004 } else { 0.002 };
        let mut p = super::tests::program_after(name, 0);
        let model = p.model_arc().clone();
        let t0 = model.initial_targets();
        let mut s = *p.settings();
        s.iterations += extra;
        let mut jt = JointTick::new(model.clone(), s, p.q(), &t0).unwrap();
        let mut t = t0.clone();
        let reps = 4000;
        let (mut ka, mut kj) = (0usize, 0usize);
        let mut aug = |t: &mut Vec<crate::FingerTarget>| {
            let s = cpu_now();
            for _ in 0..reps {
                hand(&t0, ka, radius, t);
                ka += 1;
                let r = p.tick(t, Duration::from_millis(1));
                assert_eq!(r.status, TickOutcome::Ok);
            }
            (cpu_now() - s) / reps as f64 * 1e6
        };
        let (mut ta, mut tj, mut ratio) = (Vec::new(), Vec::new(), Vec::new());
        let mut t2 = t0.clone();
        for round in 0..9 {
            let mut joint = || {
                let s = cpu_now();
                for _ in 0..reps {
                    hand(&t0, kj, radius, &mut t2);
                    kj += 1;
                    jt.tick(&t2, 1e-3).unwrap();
                }
                (cpu_now() - s) / reps as f64 * 1e6
            };
            let (a, j) = if round % 2 == 0 {
                let a = aug(&mut t);
                (a, joint())
            } else {
                let j = joint();
                (aug(&mut t), j)
            };
            ta.push(a);
            tj.push(j);
            ratio.push(j / a);
        }
        // At a fixed state: the update alone and one evaluation of the
        // loop and finger rows (both repeatable: neither moves q_s).
        let (mut tu, mut te) = (Vec::new(), Vec::new());
        for _ in 0..9 {
            let s = cpu_now();
            for _ in 0..reps {
                jt.update_for_probe(&t2);
            }
            tu.push((cpu_now() - s) / reps as f64 * 1e6);
            let s = cpu_now();
            for _ in 0..reps {
                jt.values_for_probe(&t2);
            }
            te.push((cpu_now() - s) / reps as f64 * 1e6);
        }
        let (a, j, r) = (stats(ta), stats(tj), stats(ratio));
        let (u, e) = (stats(tu), stats(te));
        println!(
            "{name}: {} dofs, {} kept rows ({} loop), update steps: joint {}, augmented {}",
            jt.dofs(),
            jt.rows.len(),
            jt.n_loop,
            s.iterations,
            p.settings().iterations
        );
        let line = |label: &str, (best, med): (f64, f64)| {
            println!("  {label:<44} best {best:7.2} µs  median {med:7.2} µs");
        };
        line("augmented Program::tick", a);
        line("joint tick", j);
        line("joint: the update's steps (fixed state)", u);
        line("joint: loop + finger values (fixed state)", e);
        println!(
            "  joint / augmented per round: median {:.3}, lowest {:.3}",
            r.1, r.0
        );
    }
}
