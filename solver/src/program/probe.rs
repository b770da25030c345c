//! `HAPTLOOP_PROBE=a.toml,b.toml cargo test --release -p haptloop-solver
//! --lib program::probe -- --ignored --nocapture` (with
//! `HAPTLOOP_PROBE_NORM_ROWS_OUT=1`: `SolverSettings::norm_rows_out` on): the shape of each scene's
//! Eq. 7 factor and the time of its parts (assembly + factorisation + solve,
//! the factorisation alone, one projected step), interleaved. Times are the
//! thread's CPU time (`CLOCK_THREAD_CPUTIME_ID`), which a shared machine's
//! other processes do not add to. Prints; asserts nothing but that the
//! ticks succeed.

use std::sync::Arc;
use std::time::Duration;

/// This thread's CPU time.
struct Instant(f64);

impl Instant {
    fn now() -> Self {
        let mut ts = libc::timespec {
            tv_sec: 0,
            tv_nsec: 0,
        };
        // SAFETY: `ts` is a valid, writable timespec.
        unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut ts) };
        Instant(ts.tv_sec as f64 + ts.tv_nsec as f64 * 1e-9)
    }

    fn elapsed(&self) -> Elapsed {
        Elapsed(Self::now().0 - self.0)
    }
}

struct Elapsed(f64);

impl Elapsed {
    fn as_secs_f64(&self) -> f64 {
        self.0
    }
}

use crate::{FingerTarget, Program, SolverSettings};

fn scenes() -> Vec<(String, crate::Model, SolverSettings)> {
    let mut out = Vec::new();
    let list = std::env::var("HAPTLOOP_PROBE").unwrap_or_default();
    for path in list.split(',').filter(|p| !p.is_empty()) {
        let loaded = crate::scene::load(std::path::Path::new(path)).expect("scene loads");
        let compiled = loaded.compile().expect("scene compiles");
        // The scene's solver keys, but the solver's default (kinematic)
        // motion whatever the scene's `dynamics`, as the probe ran before
        // it took the scene's settings whole (it took step and iterations).
        let settings = SolverSettings {
            // `HAPTLOOP_PROBE_NORM_ROWS_OUT=1`: the quaternion-norm rows
            // out of the force factor (`SolverSettings::norm_rows_out`).
            norm_rows_out: std::env::var("HAPTLOOP_PROBE_NORM_ROWS_OUT").is_ok_and(|v| v == "1"),
            dynamics: SolverSettings::default().dynamics,
            ..compiled.settings.solver_settings()
        };
        out.push((compiled.name.clone(), compiled.model, settings));
    }
    out
}

#[test]
#[ignore]
fn probe() {
    for (name, model, settings) in scenes() {
        let model = Arc::new(model);
        let t0 = Instant::now();
        let mut p = Program::new(model.clone(), settings).expect("program builds");
        let build = t0.elapsed();
        let build = Elapsed(build.as_secs_f64());
        let targets0: Vec<FingerTarget> = model.initial_targets();
        let a = p.assemble(&targets0, 100, 1e-10);
        assert!(a.converged, "{a:?}");
        print_shapes(&name, &model, &p, &build);
        let shape = p.feedback.factor_shape();
        let reps = (2_000_000 / shape.factor_flops.max(1)).clamp(20, 2000);
        let (t, targets, motion_ticks, factorisations) = timed_rounds(&mut p, &targets0, reps);
        let per = |x: f64| x / (5 * reps) as f64 * 1e6;
        let (best, assembly) = simd_baseline(&mut p, reps);
        let path = supernodal_against_dense(&mut p, &model, &targets, reps);
        println!(
            "  best of 9, supernodal / dense: factor {:.2} / {:.2} µs, solve {:.2} / {:.2} µs, projected step {:.2} / {:.2} µs",
            path[0][0] * 1e6,
            path[1][0] * 1e6,
            path[0][1] * 1e6,
            path[1][1] * 1e6,
            path[0][2] * 1e6,
            path[1][2] * 1e6
        );
        p.refresh();
        println!(
            "  Eq. 7 factorisations a tick: {:.2} ({factorisations} in {motion_ticks} ticks of motion)",
            factorisations as f64 / motion_ticks as f64
        );
        println!("  best of 9: assembly {:.1} µs", assembly * 1e6);
        println!(
            "  best of 9: factor baseline {:.1} µs, AVX2+FMA {:.1} µs ({:.2}×); solve {:.1} / {:.1} µs ({:.2}×)",
            best[0][0] * 1e6,
            best[0][1] * 1e6,
            best[0][0] / best[0][1],
            best[1][0] * 1e6,
            best[1][1] * 1e6,
            best[1][0] / best[1][1]
        );
        println!(
            "  evaluate + assemble + factor + solve {:.1} µs; factor {:.1} µs; projected step {:.1} µs",
            per(t[0]),
            per(t[1]),
            per(t[2])
        );
    }
}

/// The scene's size and the shape of its Eq. 7 factor under each ordering.
fn print_shapes(name: &str, model: &crate::Model, p: &Program, build: &Elapsed) {
    let shape = p.feedback.factor_shape();
    let (n_j, m_f, nnz_a) = p.feedback.gram_size();
    let red = p.redundancy();
    println!(
        "{name}: {} coords × {} rows; A: n_J {n_j}, m_f {m_f}, nnz(A_JJ lower) {nnz_a}; masked {} ({} local); build {:.1} ms",
        model.n_coords(),
        model.n_rows(),
        red.rows.len(),
        red.local,
        build.0 * 1e3
    );
    let (coupled, coupled_cliques, norms) = p.feedback.coupled_entries();
    println!(
        "  L ({:?}{}; {norms} norm rows decoupled): {} supernodes, widest {}, {} values; factor {} k madd, solve {} k madd",
        shape.ordering,
        if shape.induced {
            ", the coupled pattern's"
        } else {
            ""
        },
        shape.supernodes,
        shape.widest,
        shape.values,
        shape.factor_flops / 1000,
        shape.solve_flops / 1000
    );
    let (n, tail, entries, cliques) = p.feedback.factor_entries();
    let (amd, nd) = crate::cholesky::Cholesky::both_shapes(n, tail, &entries, &cliques);
    let (camd, cnd) = crate::cholesky::Cholesky::both_shapes(n, tail, &coupled, &coupled_cliques);
    for (label, sh) in [
        ("AMD", amd),
        ("dissection", nd),
        ("coupled pattern, AMD", camd),
        ("coupled pattern, dissection", cnd),
    ] {
        println!(
            "  {label}: {} supernodes, widest {}, {} values; factor {} k madd, solve {} k madd, cost {} k",
            sh.supernodes,
            sh.widest,
            sh.values,
            sh.factor_flops / 1000,
            sh.solve_flops / 1000,
            sh.cost() / 1000
        );
    }
}

/// Five rounds of a few ticks of motion, then `reps` each of refresh,
/// refactor and one projected step: their summed times, the targets the
/// motion left, the ticks of motion and the factorisations they made.
fn timed_rounds(
    p: &mut Program,
    targets0: &[FingerTarget],
    reps: usize,
) -> ([f64; 3], Vec<FingerTarget>, u64, u64) {
    let dt = Duration::from_millis(1);
    let mut targets = targets0.to_vec();
    let mut t = [0.0f64; 3];
    let mut motion_ticks = 0u64;
    let mut factorisations = 0u64;
    for round in 0..5 {
        // A few ticks of motion between rounds.
        for k in 0..5 {
            let a = 0.002 * ((round * 5 + k) as f64 * 0.3).sin();
            for (t, t0) in targets.iter_mut().zip(targets0) {
                t.position_m = t0.position_m + nalgebra::Vector3::new(a, 0.5 * a, 0.0);
            }
            let g = p.feedback.generation;
            let r = p.tick(&targets, dt);
            factorisations += p.feedback.generation.wrapping_sub(g);
            motion_ticks += 1;
            assert_eq!(
                r.status,
                crate::program::TickOutcome::Ok,
                "round {round} tick {k}"
            );
        }
        let s = Instant::now();
        for _ in 0..reps {
            assert_eq!(p.refresh(), crate::program::TickOutcome::Ok);
        }
        t[0] += s.elapsed().as_secs_f64();
        let s = Instant::now();
        for _ in 0..reps {
            p.feedback.refactor().unwrap();
        }
        t[1] += s.elapsed().as_secs_f64();
        let saved = p.q.clone();
        let s = Instant::now();
        for _ in 0..reps {
            let _ = p.iterate(&targets, 1);
            p.q.copy_from_slice(&saved);
        }
        t[2] += s.elapsed().as_secs_f64();
    }
    (t, targets, motion_ticks, factorisations)
}

/// Baseline against AVX2 + FMA kernels, interleaved, best of 9 rounds
/// each: `[factor, solve][baseline, simd]` and the assembly, seconds.
fn simd_baseline(p: &mut Program, reps: usize) -> ([[f64; 2]; 2], f64) {
    let (n_j, _, _) = p.feedback.gram_size();
    let mut x = vec![0.0; n_j];
    let mut best = [[f64::INFINITY; 2]; 2];
    let mut assembly = f64::INFINITY;
    for _ in 0..9 {
        let s = Instant::now();
        for _ in 0..reps {
            p.feedback.reassemble(&p.ev);
        }
        assembly = assembly.min(s.elapsed().as_secs_f64() / reps as f64);
        for (k, on) in [false, true].into_iter().enumerate() {
            p.feedback.set_simd(on);
            let s = Instant::now();
            for _ in 0..reps {
                p.feedback.refactor().unwrap();
            }
            best[0][k] = best[0][k].min(s.elapsed().as_secs_f64() / reps as f64);
            let s = Instant::now();
            for r in 0..reps {
                x.fill(r as f64);
                p.feedback.solve_joint(&mut x);
            }
            best[1][k] = best[1][k].min(s.elapsed().as_secs_f64() / reps as f64);
        }
    }
    (best, assembly)
}

/// The supernodal kernels against the dense path (forced at any size),
/// interleaved, best of 9: `[supernodal, dense][factor, one solve, one
/// projected step]`, seconds. Leaves the default dense threshold set.
fn supernodal_against_dense(
    p: &mut Program,
    model: &crate::Model,
    targets: &[FingerTarget],
    reps: usize,
) -> [[f64; 3]; 2] {
    let (n_j, _, _) = p.feedback.gram_size();
    let mut x = vec![0.0; n_j];
    let mut path = [[f64::INFINITY; 3]; 2];
    let saved = p.q.clone();
    for _ in 0..9 {
        for (k, dense_max) in [0, usize::MAX].into_iter().enumerate() {
            p.feedback.set_dense(model, dense_max);
            p.feedback.refactor().unwrap();
            p.refresh();
            let s = Instant::now();
            for _ in 0..reps {
                p.feedback.refactor().unwrap();
            }
            path[k][0] = path[k][0].min(s.elapsed().as_secs_f64() / reps as f64);
            let s = Instant::now();
            for r in 0..reps {
                x.fill(r as f64);
                p.feedback.solve_joint(&mut x);
            }
            path[k][1] = path[k][1].min(s.elapsed().as_secs_f64() / reps as f64);
            let s = Instant::now();
            for _ in 0..reps {
                let _ = p.iterate(targets, 1);
                p.q.copy_from_slice(&saved);
            }
            path[k][2] = path[k][2].min(s.elapsed().as_secs_f64() / reps as f64);
        }
    }
    p.feedback.set_dense(model, crate::cholesky::DENSE_MAX);
    path
}
