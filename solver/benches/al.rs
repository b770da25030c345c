//! Criterion benches of the fast update and the fast tick (BENCHMARKS.md,
//! solver section):
//!
//! - `al_iteration/{four-bar,stewart,sphere-toy}`: one augmented-Lagrangian
//!   iteration, `Program::iterate(targets, 1)`: evaluate C and C_q in place,
//!   the multiplier and penalty terms, one C_qᵀ product, the q update;
//! - `tick/{…}`: one `Program::tick` with the default settings (4 iterations,
//!   the final evaluation, Eq. 7–8 forces and coupling).
//!
//! Run: `CARGO_TARGET_DIR=target/al cargo bench -p haptloop-solver --bench al`

use std::hint::black_box;
use std::sync::Arc;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use haptloop_solver::mechanisms::{four_bar, sphere_toy, stewart};
use haptloop_solver::{FingerTarget, Model, Program, SolverSettings, TickOutcome};
use nalgebra::Vector3;

fn mechanisms() -> Vec<(&'static str, Model)> {
    vec![
        ("four-bar", four_bar()),
        ("stewart", stewart()),
        ("sphere-toy", sphere_toy()),
    ]
}

/// Targets a millimetre from the initial ones, so every iteration has work.
fn targets(model: &Model) -> Vec<FingerTarget> {
    let mut t = model.initial_targets();
    for f in &mut t {
        f.position_m += Vector3::new(1e-3, -0.5e-3, 0.5e-3);
    }
    t
}

fn al_iteration(c: &mut Criterion) {
    let mut g = c.benchmark_group("al_iteration");
    for (name, model) in mechanisms() {
        let t = targets(&model);
        let mut p = Program::new(Arc::new(model), SolverSettings::default()).unwrap();
        g.bench_function(name, |b| {
            b.iter(|| assert_eq!(p.iterate(black_box(&t), 1), TickOutcome::Ok))
        });
    }
    g.finish();
}

fn tick(c: &mut Criterion) {
    let mut g = c.benchmark_group("tick");
    for (name, model) in mechanisms() {
        let t = targets(&model);
        let mut p = Program::new(Arc::new(model), SolverSettings::default()).unwrap();
        let dt = Duration::from_millis(1);
        g.bench_function(name, |b| {
            b.iter(|| assert_eq!(p.tick(black_box(&t), dt).status, TickOutcome::Ok))
        });
    }
    g.finish();
}

/// 1 s warm-up and 2 s of samples per figure, as the other solver benches.
fn config() -> Criterion {
    Criterion::default()
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(2))
}

criterion_group! {
    name = benches;
    config = config();
    targets = al_iteration, tick
}

criterion_main!(benches);
