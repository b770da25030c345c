//! Criterion benches of the Newton-KKT placement, one run for every figure in
//! the `placement` section of BENCHMARKS.md:
//!
//! - `placement/symbolic_212`: `Placement::analyze` of the 212-variable chain
//!   (Choi & Cremer's size; built in `tests/placement/common.rs`);
//! - `placement/numeric_212`: one iteration's numeric phase (fill J Jᵀ + μI,
//!   LLᵀ, solve, δq) at a 1 cm / 5° perturbed start;
//! - `placement/full_212`: a full placement from that start (q_ref = the
//!   assembled q0), reusing the analysis;
//! - `placement/full_212_reanalyse`: the same iterations with a fresh
//!   symbolic analysis before each one (no reuse);
//! - `placement/full_sphere_toy`: full placement of the 132-body toy;
//! - `placement/star50/{split,unsplit}`, `placement/chain50`: one numeric
//!   step of the 50-spoke star with and without the dense-column split, and
//!   of the same bodies joined in a chain;
//! - `placement/crossover/{faer,nalgebra}/{25,50,100,500,2000}`: faer's
//!   sparse numeric step vs nalgebra's dense Cholesky + solve of the same
//!   J Jᵀ + μI (chains with 23, 47, 99, 499 and 1999 rows).
//!
//! Run: `CARGO_TARGET_DIR=target/placement cargo bench -p haptloop-solver --bench placement`

use std::hint::black_box;
use std::time::Duration;

use criterion::{BatchSize, Criterion, criterion_group, criterion_main};
use haptloop_solver::mechanisms::sphere_toy;
use haptloop_solver::{
    BodySpec, JointKind, JointSpec, Model, ModelBuilder, Placement, PlacementOptions, SolveStatus,
};
use nalgebra::{DMatrix, DVector};

#[allow(dead_code)]
#[path = "../tests/placement/common.rs"]
mod common;

use common::{chain212, hub, perturbed};

fn start(model: &Model) -> Vec<f64> {
    perturbed(model, model.q0(), 0.01, 5f64.to_radians(), 7)
}

fn symbolic_numeric_full(c: &mut Criterion) {
    let model = chain212();
    let opts = PlacementOptions::default();
    let (q, targets) = (start(&model), model.initial_targets());
    let mut g = c.benchmark_group("placement");
    g.bench_function("symbolic_212", |b| {
        b.iter(|| Placement::analyze(black_box(&model), &opts).unwrap())
    });
    let mut p = Placement::analyze(&model, &opts).unwrap();
    p.prepare(&model, &q, &targets).unwrap();
    g.bench_function("numeric_212", |b| {
        b.iter(|| p.numeric_step(black_box(&q), model.q0()).unwrap()[0])
    });
    let mut out = q.clone();
    let info = p.solve(&model, &mut out, model.q0(), &targets).unwrap();
    assert_eq!(info.status, SolveStatus::Converged);
    let iterations = info.iterations;
    println!(
        "full_212: {iterations} iterations, residual {:e}",
        info.residual
    );
    g.bench_function("full_212", |b| {
        b.iter(|| {
            out.copy_from_slice(&q);
            p.solve(&model, &mut out, model.q0(), &targets).unwrap()
        })
    });
    let one = PlacementOptions {
        max_iterations: 1,
        ..opts.clone()
    };
    g.bench_function("full_212_reanalyse", |b| {
        b.iter(|| {
            out.copy_from_slice(&q);
            for _ in 0..iterations {
                let mut fresh = Placement::analyze(&model, &one).unwrap();
                fresh.solve(&model, &mut out, model.q0(), &targets).unwrap();
            }
        })
    });
    let toy = sphere_toy();
    let (tq, tt) = (start(&toy), toy.initial_targets());
    let mut tp = Placement::analyze(&toy, &opts).unwrap();
    let mut tout = tq.clone();
    let info = tp.solve(&toy, &mut tout, toy.q0(), &tt).unwrap();
    println!("full_sphere_toy: {info:?}");
    g.bench_function("full_sphere_toy", |b| {
        b.iter(|| {
            tout.copy_from_slice(&tq);
            tp.solve(&toy, &mut tout, toy.q0(), &tt).unwrap()
        })
    });
    g.finish();
}

fn numeric_bench(
    g: &mut criterion::BenchmarkGroup<'_, criterion::measurement::WallTime>,
    id: &str,
    model: &Model,
    opts: &PlacementOptions,
) {
    let (q, targets) = (start(model), model.initial_targets());
    let mut p = Placement::analyze(model, opts).unwrap();
    println!("{id}: {:?}", p.stats());
    p.prepare(model, &q, &targets).unwrap();
    g.bench_function(id, |b| {
        b.iter(|| p.numeric_step(black_box(&q), model.q0()).unwrap()[0])
    });
}

fn dense_columns(c: &mut Criterion) {
    let mut g = c.benchmark_group("placement");
    let unsplit = PlacementOptions {
        dense_column_threshold: usize::MAX,
        ..Default::default()
    };
    numeric_bench(
        &mut g,
        "star50/split",
        &hub(50, false),
        &PlacementOptions::default(),
    );
    numeric_bench(&mut g, "star50/unsplit", &hub(50, false), &unsplit);
    numeric_bench(
        &mut g,
        "chain50",
        &hub(50, true),
        &PlacementOptions::default(),
    );
    g.finish();
}

/// A zig-zag chain of `n` bodies pinned to the ground at both ends by
/// spherical joints: 3(n + 1) + n rows.
fn chain(n: usize) -> Model {
    let p = |i: usize| {
        [
            0.1 * i as f64,
            if i.is_multiple_of(2) { 0.02 } else { -0.02 },
            0.0,
        ]
    };
    let sub = |a: [f64; 3], o: [f64; 3]| -> [f64; 3] { std::array::from_fn(|k| a[k] - o[k]) };
    let mut b = ModelBuilder::new();
    b.body(BodySpec::fixed("ground"));
    for i in 0..n {
        b.body(BodySpec::new(format!("b{i}")).at(p(i)));
    }
    let first = sub(p(0), [0.05, 0.0, 0.0]);
    b.joint(JointSpec::new(JointKind::Spherical, "ground", "b0").anchors(first, sub(first, p(0))));
    for i in 0..n - 1 {
        let m: [f64; 3] = std::array::from_fn(|k| 0.5 * (p(i)[k] + p(i + 1)[k]));
        b.joint(
            JointSpec::new(JointKind::Spherical, format!("b{i}"), format!("b{}", i + 1))
                .anchors(sub(m, p(i)), sub(m, p(i + 1))),
        );
    }
    let last = [p(n - 1)[0] + 0.05, p(n - 1)[1], 0.0];
    let end = format!("b{}", n - 1);
    b.joint(
        JointSpec::new(JointKind::Spherical, "ground", &end).anchors(last, sub(last, p(n - 1))),
    );
    b.build().unwrap()
}

fn crossover(c: &mut Criterion) {
    let mut g = c.benchmark_group("placement/crossover");
    g.sample_size(10)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(3));
    for (size, bodies) in [(25, 5), (50, 11), (100, 24), (500, 124), (2000, 499)] {
        let model = chain(bodies);
        let opts = PlacementOptions::default();
        let q = start(&model);
        let mut p = Placement::analyze(&model, &opts).unwrap();
        println!("crossover {size}: {:?}", p.stats());
        p.prepare(&model, &q, &[]).unwrap();
        g.bench_function(format!("faer/{size}"), |b| {
            b.iter(|| p.numeric_step(black_box(&q), model.q0()).unwrap()[0])
        });
        let mut ev = model.evaluation();
        ev.evaluate(&model, &q, &[]).unwrap();
        let j = ev.jacobian().to_dense();
        let mut n = &j * j.transpose();
        for i in 0..n.nrows() {
            n[(i, i)] += opts.damping;
        }
        let rhs = DVector::from_element(n.nrows(), 1.0);
        g.bench_function(format!("nalgebra/{size}"), |b| {
            b.iter_batched(
                || n.clone(),
                |m: DMatrix<f64>| m.cholesky().unwrap().solve(&rhs)[0],
                BatchSize::LargeInput,
            )
        });
    }
    g.finish();
}

criterion_group!(benches, symbolic_numeric_full, dense_columns, crossover);
criterion_main!(benches);
