//! `cargo test --release -p haptloop-solver --lib force::solve::timing -- --ignored --nocapture`:
//! the supernodal factor against faer's on the built-in mechanisms'
//! Eq. 7 matrices, interleaved. Prints; asserts only agreement.
use super::super::gram::Gram;
use super::super::inertia::BodyMass;
use crate::Model;
use crate::cholesky::{Cholesky, Regularization};
use crate::mechanisms::{four_bar, sphere_toy, stewart};
use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::sparse::SparseColMatRef;
use faer::sparse::linalg::cholesky::{
    CholeskySymbolicParams, SymbolicCholesky, SymmetricOrdering, factorize_symbolic_cholesky,
};
use faer::{Conj, MatMut, Par, Side};
use std::time::Instant;

/// faer's factor of one Gram pattern (AMD order, its own symbolic
/// analysis), its values and its workspace.
struct Faer {
    sym: SymbolicCholesky<usize>,
    l: Vec<f64>,
    mem: MemBuffer,
}

impl Faer {
    fn new(gram: &Gram, k: usize) -> Self {
        let sym = factorize_symbolic_cholesky(
            gram.pattern.as_ref(),
            Side::Lower,
            SymmetricOrdering::Amd,
            CholeskySymbolicParams::default(),
        )
        .unwrap();
        let l = vec![0.0; sym.len_val()];
        let mem = MemBuffer::new(StackReq::any_of(&[
            sym.factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default()),
            sym.solve_in_place_scratch::<f64>(k, Par::Seq),
        ]));
        Self { sym, l, mem }
    }

    fn factor(&mut self, gram: &Gram, a: &[f64], reg: Regularization) {
        self.sym
            .factorize_numeric_llt::<f64>(
                &mut self.l,
                SparseColMatRef::new(gram.pattern.as_ref(), a),
                Side::Lower,
                LltRegularization {
                    dynamic_regularization_delta: reg.delta,
                    dynamic_regularization_epsilon: reg.epsilon,
                },
                Par::Seq,
                MemStack::new(&mut self.mem),
                Default::default(),
            )
            .unwrap();
    }

    /// Solves in place for the `k` columns of `x` (`n` rows each).
    fn solve(&mut self, x: &mut [f64], n: usize, k: usize) {
        faer::sparse::linalg::cholesky::LltRef::new(&self.sym, &self.l).solve_in_place_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(x, n, k),
            Par::Seq,
            MemStack::new(&mut self.mem),
        );
    }
}

/// Seconds `reps` calls of `f` take.
fn timed(reps: usize, mut f: impl FnMut()) -> f64 {
    let s = Instant::now();
    for _ in 0..reps {
        f();
    }
    s.elapsed().as_secs_f64()
}

/// The model's Eq. 7 matrix at q0, all rows scaled 1.
fn assembled(model: &Model) -> Gram {
    let mut ev = model.evaluation();
    ev.evaluate(model, model.q0(), &model.initial_targets())
        .unwrap();
    let masses = BodyMass::of_model(model);
    let mut gram = Gram::new(model, ev.jacobian(), &masses, &[]);
    let scale = vec![1.0; model.n_rows()];
    let b = vec![0.1; model.n_coords()];
    let mut y = vec![0.0; model.n_coords()];
    gram.assemble(model.q0(), ev.jacobian(), &scale, &masses, &b, &mut y);
    gram
}

#[test]
#[ignore]
fn supernodal_against_faer() {
    for (name, model) in [
        ("four-bar", four_bar()),
        ("stewart", stewart()),
        ("sphere-toy", sphere_toy()),
    ] {
        let gram = assembled(&model);
        let (n, k) = (gram.n_j, 1 + gram.m_f);
        let a = &gram.values[..gram.nnz()];
        let reg = gram.regularization();
        let mut ours =
            Cholesky::analyze(n, gram.pattern.col_ptr(), gram.pattern.row_idx(), k).unwrap();
        let mut faer = Faer::new(&gram, k);
        let rhs: Vec<f64> = (0..n * k).map(|i| (i % 7) as f64 - 3.0).collect();
        let (mut x1, mut x2) = (rhs.clone(), rhs.clone());
        let reps = (20_000 / n).max(20);
        let mut t = [[0f64; 2]; 4];
        for _round in 0..6 {
            t[0][0] += timed(reps, || ours.factor(a, reg).unwrap());
            t[1][0] += timed(reps, || {
                x1.copy_from_slice(&rhs);
                ours.solve(&mut x1, k);
            });
            t[0][1] += timed(reps, || faer.factor(&gram, a, reg));
            t[1][1] += timed(reps, || {
                x2.copy_from_slice(&rhs);
                faer.solve(&mut x2, n, k);
            });
            t[2][0] += timed(reps, || {
                x1[..n].copy_from_slice(&rhs[..n]);
                ours.solve(&mut x1[..n], 1);
            });
            t[2][1] += timed(reps, || {
                x2[..n].copy_from_slice(&rhs[..n]);
                faer.solve(&mut x2[..n], n, 1);
            });
        }
        x1.copy_from_slice(&rhs);
        ours.solve(&mut x1, k);
        x2.copy_from_slice(&rhs);
        faer.solve(&mut x2, n, k);
        let diff = x1
            .iter()
            .zip(&x2)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        let big = x2.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        assert!(diff <= 1e-9 * big, "{name}: {diff:e} vs {big:e}");
        report(name, n, k, &t, reps);
    }
}

/// Prints one mechanism's per-call times (µs) and faer/ours ratios.
fn report(name: &str, n: usize, k: usize, t: &[[f64; 2]; 4], reps: usize) {
    let per = |x: f64| x / (6 * reps) as f64 * 1e6;
    println!(
        "{name}: n {n}, k {k}: factor ours {:.2} µs faer {:.2} µs ({:.2}×); solve×{k} ours {:.2} faer {:.2} ({:.2}×); solve×1 ours {:.2} faer {:.2} ({:.2}×)",
        per(t[0][0]),
        per(t[0][1]),
        t[0][1] / t[0][0],
        per(t[1][0]),
        per(t[1][1]),
        t[1][1] / t[1][0],
        per(t[2][0]),
        per(t[2][1]),
        t[2][1] / t[2][0],
    );
}
