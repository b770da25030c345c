//! Criterion benches of the solver core, one run for every figure in the
//! `solver` section of BENCHMARKS.md:
//!
//! - `jacobian/evaluate/{four-bar,stewart,sphere-toy}`: C and C_q in place;
//! - `jacobian/mul_t/{block,csr,csc,faer}/…`: C_qᵀ·v with the API's
//!   `mul_t_vec` (hand-owned, per-constraint dense blocks), a plain CSR scatter
//!   over the same storage, a gather over the transposed index, and faer's
//!   `sparse_dense_matmul` on the zero-copy view of the same values;
//! - `jacobian/mul/{block,csr,faer}/…`: C_q·v likewise.
//!
//! Run: `CARGO_TARGET_DIR=target/solver cargo bench -p haptloop-solver --bench jacobian`

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use faer::sparse::linalg::matmul::sparse_dense_matmul;
use faer::{Accum, ColMut, ColRef, Par};
use haptloop_solver::mechanisms::{four_bar, sphere_toy, stewart};
use haptloop_solver::{Evaluation, Jacobian, Model};

fn mechanisms() -> Vec<(&'static str, Model)> {
    vec![
        ("four-bar", four_bar()),
        ("stewart", stewart()),
        ("sphere-toy", sphere_toy()),
    ]
}

/// q0 nudged off assembly so every row is non-trivial.
fn state(model: &Model) -> Vec<f64> {
    model
        .q0()
        .iter()
        .enumerate()
        .map(|(k, v)| v + 1e-3 * ((k * 7919 % 13) as f64 - 6.0))
        .collect()
}

fn evaluated(model: &Model) -> Evaluation {
    let mut ev = model.evaluation();
    ev.evaluate(model, &state(model), &model.initial_targets())
        .expect("evaluate");
    ev
}

/// y = Jx, plain CSR: one indexed load of x per entry.
fn mul_csr(j: &Jacobian, x: &[f64], y: &mut [f64]) {
    let (ptr, idx, val) = (j.row_ptr(), j.col_idx(), j.values());
    for (r, out) in y.iter_mut().enumerate() {
        *out = (ptr[r]..ptr[r + 1]).map(|k| val[k] * x[idx[k]]).sum();
    }
}

/// y = Jᵀx, plain CSR scatter: one indexed store into y per entry.
fn mul_t_csr(j: &Jacobian, x: &[f64], y: &mut [f64]) {
    let (ptr, idx, val) = (j.row_ptr(), j.col_idx(), j.values());
    y.fill(0.0);
    for (r, &xr) in x.iter().enumerate() {
        for k in ptr[r]..ptr[r + 1] {
            y[idx[k]] += val[k] * xr;
        }
    }
}

/// y = Jᵀx by gathering each column through the transposed index.
fn mul_t_csc(j: &Jacobian, x: &[f64], y: &mut [f64]) {
    let (ptr, rows, pos, val) = (j.col_ptr(), j.col_rows(), j.col_value_index(), j.values());
    for (c, out) in y.iter_mut().enumerate() {
        *out = (ptr[c]..ptr[c + 1]).map(|k| val[pos[k]] * x[rows[k]]).sum();
    }
}

fn evaluate(c: &mut Criterion) {
    let mut g = c.benchmark_group("jacobian/evaluate");
    for (name, model) in mechanisms() {
        let (q, targets) = (state(&model), model.initial_targets());
        let mut ev = model.evaluation();
        g.bench_function(name, |b| {
            b.iter(|| ev.evaluate(&model, black_box(&q), &targets).unwrap())
        });
    }
    g.finish();
}

fn products(c: &mut Criterion) {
    for (name, model) in mechanisms() {
        let ev = evaluated(&model);
        let j = ev.jacobian();
        let v: Vec<f64> = (0..j.nrows()).map(|k| (k % 5) as f64 - 2.0).collect();
        let x: Vec<f64> = (0..j.ncols()).map(|k| (k % 7) as f64 - 3.0).collect();
        let (mut y, mut z) = (vec![0.0; j.nrows()], vec![0.0; j.ncols()]);

        let mut g = c.benchmark_group("jacobian/mul_t");
        g.bench_function(format!("block/{name}"), |b| {
            b.iter(|| j.mul_t_vec(black_box(&v), &mut z).unwrap())
        });
        g.bench_function(format!("csr/{name}"), |b| {
            b.iter(|| mul_t_csr(j, black_box(&v), &mut z))
        });
        g.bench_function(format!("csc/{name}"), |b| {
            b.iter(|| mul_t_csc(j, black_box(&v), &mut z))
        });
        g.bench_function(format!("faer/{name}"), |b| {
            b.iter(|| {
                let dst = ColMut::from_slice_mut(&mut z).as_mat_mut();
                let rhs = ColRef::from_slice(black_box(&v)).as_mat();
                sparse_dense_matmul(
                    dst,
                    Accum::Replace,
                    j.as_faer().transpose(),
                    rhs,
                    1.0,
                    Par::Seq,
                );
            })
        });
        g.finish();

        let mut g = c.benchmark_group("jacobian/mul");
        g.bench_function(format!("block/{name}"), |b| {
            b.iter(|| j.mul_vec(black_box(&x), &mut y).unwrap())
        });
        g.bench_function(format!("csr/{name}"), |b| {
            b.iter(|| mul_csr(j, black_box(&x), &mut y))
        });
        g.bench_function(format!("faer/{name}"), |b| {
            b.iter(|| {
                let dst = ColMut::from_slice_mut(&mut y).as_mat_mut();
                let rhs = ColRef::from_slice(black_box(&x)).as_mat();
                sparse_dense_matmul(dst, Accum::Replace, j.as_faer(), rhs, 1.0, Par::Seq);
            })
        });
        g.finish();
    }
}

/// 1 s warm-up and 2 s of samples per figure keep the whole run near two
/// minutes on the shared 2-core machine.
fn config() -> Criterion {
    Criterion::default()
        .warm_up_time(std::time::Duration::from_secs(1))
        .measurement_time(std::time::Duration::from_secs(2))
}

criterion_group! {
    name = benches;
    config = config();
    targets = evaluate, products
}
criterion_main!(benches);
