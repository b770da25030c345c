//! `cargo test --release -p haptloop-solver --lib force::solve::timing -- --ignored --nocapture`:
//! the supernodal factor against faer's on the built-in mechanisms'
//! Eq. 7 matrices, interleaved. Prints; asserts only agreement.
use super::super::gram::Gram;
use super::super::inertia::BodyMass;
use crate::cholesky::Cholesky;
use crate::mechanisms::{four_bar, sphere_toy, stewart};
use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::sparse::SparseColMatRef;
use faer::sparse::linalg::cholesky::{
    CholeskySymbolicParams, SymmetricOrdering, factorize_symbolic_cholesky,
};
use faer::{Conj, MatMut, Par, Side};
use std::time::Instant;

#[test]
#[ignore]
fn supernodal_against_faer() {
    for (name, model) in [
        ("four-bar", four_bar()),
        ("stewart", stewart()),
        ("sphere-toy", sphere_toy()),
    ] {
        let mut ev = model.evaluation();
        ev.evaluate(&model, model.q0(), &model.initial_targets())
            .unwrap();
        let masses = BodyMass::of_model(&model);
        let mut gram = Gram::new(&model, ev.jacobian(), &masses, &[]);
        let scale = vec![1.0; model.n_rows()];
        let b = vec![0.1; model.n_coords()];
        let mut y = vec![0.0; model.n_coords()];
        gram.assemble(model.q0(), ev.jacobian(), &scale, &masses, &b, &mut y);
        let (n, k) = (gram.n_j, 1 + gram.m_f);
        let a = &gram.values[..gram.nnz()];
        let reg = gram.regularization();
        let mut ours =
            Cholesky::analyze(n, gram.pattern.col_ptr(), gram.pattern.row_idx(), k).unwrap();
        let sym = factorize_symbolic_cholesky(
            gram.pattern.as_ref(),
            Side::Lower,
            SymmetricOrdering::Amd,
            CholeskySymbolicParams::default(),
        )
        .unwrap();
        let mut l = vec![0.0; sym.len_val()];
        let mut mem = MemBuffer::new(StackReq::any_of(&[
            sym.factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default()),
            sym.solve_in_place_scratch::<f64>(k, Par::Seq),
        ]));
        let rhs: Vec<f64> = (0..n * k).map(|i| (i % 7) as f64 - 3.0).collect();
        let (mut x1, mut x2) = (rhs.clone(), rhs.clone());
        let reps = (20_000 / n).max(20);
        let mut t = [[0f64; 2]; 4];
        for _round in 0..6 {
            let s = Instant::now();
            for _ in 0..reps {
                ours.factor(a, reg).unwrap();
            }
            t[0][0] += s.elapsed().as_secs_f64();
            let s = Instant::now();
            for _ in 0..reps {
                x1.copy_from_slice(&rhs);
                ours.solve(&mut x1, k);
            }
            t[1][0] += s.elapsed().as_secs_f64();
            let s = Instant::now();
            for _ in 0..reps {
                sym.factorize_numeric_llt::<f64>(
                    &mut l,
                    SparseColMatRef::new(gram.pattern.as_ref(), a),
                    Side::Lower,
                    LltRegularization {
                        dynamic_regularization_delta: reg.delta,
                        dynamic_regularization_epsilon: reg.epsilon,
                    },
                    Par::Seq,
                    MemStack::new(&mut mem),
                    Default::default(),
                )
                .unwrap();
            }
            t[0][1] += s.elapsed().as_secs_f64();
            let s = Instant::now();
            for _ in 0..reps {
                x2.copy_from_slice(&rhs);
                faer::sparse::linalg::cholesky::LltRef::new(&sym, &l).solve_in_place_with_conj(
                    Conj::No,
                    MatMut::from_column_major_slice_mut(&mut x2, n, k),
                    Par::Seq,
                    MemStack::new(&mut mem),
                );
            }
            t[1][1] += s.elapsed().as_secs_f64();
            let s = Instant::now();
            for _ in 0..reps {
                x1[..n].copy_from_slice(&rhs[..n]);
                ours.solve(&mut x1[..n], 1);
            }
            t[2][0] += s.elapsed().as_secs_f64();
            let s = Instant::now();
            for _ in 0..reps {
                x2[..n].copy_from_slice(&rhs[..n]);
                faer::sparse::linalg::cholesky::LltRef::new(&sym, &l).solve_in_place_with_conj(
                    Conj::No,
                    MatMut::from_column_major_slice_mut(&mut x2[..n], n, 1),
                    Par::Seq,
                    MemStack::new(&mut mem),
                );
            }
            t[2][1] += s.elapsed().as_secs_f64();
        }
        let per = |x: f64| x / (6 * reps) as f64 * 1e6;
        x1.copy_from_slice(&rhs);
        ours.solve(&mut x1, k);
        x2.copy_from_slice(&rhs);
        faer::sparse::linalg::cholesky::LltRef::new(&sym, &l).solve_in_place_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(&mut x2, n, k),
            Par::Seq,
            MemStack::new(&mut mem),
        );
        let diff = x1
            .iter()
            .zip(&x2)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        let big = x2.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        assert!(diff <= 1e-9 * big, "{name}: {diff:e} vs {big:e}");
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
}
