//! Criterion benches of the fast update and the fast tick (BENCHMARKS.md,
//! solver section), one run for every figure:
//!
//! - `al_iteration/{four-bar,stewart,sphere-toy}`: one augmented-Lagrangian
//!   iteration of Eq. 1–3 as shipped (`UpdateRule::Gradient`,
//!   `Program::iterate(targets, 1)`): C and the weighted gradient C_qᵀ w in
//!   one fused pass, multipliers, the q update;
//! - `al_iteration_stored/{…}`: the same iteration written with the stored
//!   Jacobian through the public API (`Evaluation::evaluate`, then
//!   `Jacobian::mul_t_vec_add`, then the update), the unfused baseline;
//! - `al_iteration_projected/{…}`: one iteration of `UpdateRule::Projected`
//!   (value-only evaluation, C_q·v, sparse triangular solves with the force
//!   solve's factor, C_qᵀ·v, M⁻¹), timed from a fresh factor at q0;
//! - `tick/{gradient,projected}/{…}`: one `Program::tick` with 4 iterations of
//!   that rule, the final evaluation, Eq. 7–8 forces and coupling.
//!
//! Run: `CARGO_TARGET_DIR=target/al cargo bench -p haptloop-solver --bench al`

use std::hint::black_box;
use std::sync::Arc;
use std::time::{Duration, Instant};

use criterion::{Criterion, criterion_group, criterion_main};
use haptloop_solver::mechanisms::{four_bar, sphere_toy, stewart};
use haptloop_solver::{
    FingerTarget, Model, Program, RowUnit, SolverSettings, TickOutcome, UpdateRule,
};
use nalgebra::Vector3;

fn mechanisms() -> Vec<(&'static str, Arc<Model>)> {
    vec![
        ("four-bar", Arc::new(four_bar())),
        ("stewart", Arc::new(stewart())),
        ("sphere-toy", Arc::new(sphere_toy())),
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

fn settings(update: UpdateRule) -> SolverSettings {
    SolverSettings {
        update,
        ..SolverSettings::default()
    }
}

fn al_iteration(c: &mut Criterion) {
    let mut g = c.benchmark_group("al_iteration");
    for (name, model) in mechanisms() {
        let t = targets(&model);
        let mut p = Program::new(model, settings(UpdateRule::Gradient)).unwrap();
        g.bench_function(name, |b| {
            b.iter(|| assert_eq!(p.iterate(black_box(&t), 1), TickOutcome::Ok))
        });
    }
    g.finish();
    // The projected rule steps with the factor of the last tick: restart from
    // q0 (refactoring, untimed) before each timed iteration, as in a tick.
    let mut g = c.benchmark_group("al_iteration_projected");
    for (name, model) in mechanisms() {
        let t = targets(&model);
        let q0 = model.q0().to_vec();
        let mut p = Program::new(model, settings(UpdateRule::Projected)).unwrap();
        g.bench_function(name, |b| {
            b.iter_custom(|n| {
                let mut total = Duration::ZERO;
                for _ in 0..n {
                    p.set_q(&q0).unwrap();
                    let start = Instant::now();
                    let r = p.iterate(black_box(&t), 1);
                    total += start.elapsed();
                    assert_eq!(r, TickOutcome::Ok);
                }
                total
            })
        });
    }
    g.finish();
}

/// Eq. 3 with the stored Jacobian, public API only, with the shipped gains
/// (K ℓ² per row, W⁻¹ per column, fingers without multiplier; no pull
/// limit). With a multiplier on the finger rows this loop diverges: the
/// 1-DOF four-bar cannot reach the offset target, and that λ grew linearly
/// (46 → 1080 over 3000 iterations) until the linkage came apart.
fn al_iteration_stored(c: &mut Criterion) {
    let mut g = c.benchmark_group("al_iteration_stored");
    for (name, model) in mechanisms() {
        let t = targets(&model);
        let p = Program::new(model.clone(), settings(UpdateRule::Gradient)).unwrap();
        let (h, k, l) = (p.step_h(), p.settings().gain, p.length_scale_m());
        let kk: Vec<f64> = model
            .rows()
            .iter()
            .map(|r| {
                if r.unit == RowUnit::Length {
                    k
                } else {
                    k * l * l
                }
            })
            .collect();
        let k2: Vec<f64> = model
            .rows()
            .iter()
            .zip(&kk)
            .map(|(r, k)| {
                let finger = model.constraints()[r.constraint.index()].finger.is_some();
                if finger { 0.0 } else { *k }
            })
            .collect();
        let mut winv = vec![1.0; model.n_coords()];
        for (_, o) in model.layout().moving_bodies() {
            winv[o + 3..o + 7].fill(1.0 / (l * l));
        }
        let mut ev = model.evaluation();
        let mut q = model.q0().to_vec();
        let q_ref = q.clone();
        let mut lambda = vec![0.0; model.n_rows()];
        let mut w = vec![0.0; model.n_rows()];
        let mut grad = vec![0.0; model.n_coords()];
        g.bench_function(name, |b| {
            b.iter(|| {
                ev.evaluate(&model, black_box(&q), &t).unwrap();
                let rows = w.iter_mut().zip(&mut lambda).zip(ev.values());
                for ((((wi, li), ci), ki), k2i) in rows.zip(&kk).zip(&k2) {
                    *li += k2i * ci;
                    *wi = *li + ki * ci;
                }
                grad.fill(0.0);
                ev.jacobian().mul_t_vec_add(1.0, &w, &mut grad).unwrap();
                for (((qc, rc), gc), wc) in q.iter_mut().zip(&q_ref).zip(&grad).zip(&winv) {
                    *qc -= h * ((*qc - *rc) + wc * gc);
                }
            })
        });
    }
    g.finish();
}

fn tick(c: &mut Criterion) {
    for (rule_name, rule) in [
        ("gradient", UpdateRule::Gradient),
        ("projected", UpdateRule::Projected),
    ] {
        let mut g = c.benchmark_group(format!("tick/{rule_name}"));
        for (name, model) in mechanisms() {
            let t = targets(&model);
            let mut p = Program::new(model, settings(rule)).unwrap();
            let dt = Duration::from_millis(1);
            g.bench_function(name, |b| {
                b.iter(|| assert_eq!(p.tick(black_box(&t), dt).status, TickOutcome::Ok))
            });
        }
        g.finish();
    }
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
    targets = al_iteration, al_iteration_stored, tick
}
criterion_main!(benches);
