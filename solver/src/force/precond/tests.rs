//! The tree preconditioner against a dense reference of the same operator.

use super::super::gram::Gram;
use super::super::inertia::BodyMass;
use super::super::small::cholesky_solve;
use super::tree::{TreePrecond, split};
use crate::Model;
use crate::mechanisms::{chain_sized, lattice_sized, sphere_toy_shape, sphere_toy_sized};

/// `model`'s Gram matrix assembled at q0 (unit scaling) and each J row's
/// constraint.
pub(super) fn assembled(model: &Model) -> (Gram, Vec<usize>) {
    assembled_with(model, true)
}

/// [`assembled`] with the quaternion-norm rows decoupled or not.
pub(super) fn assembled_with(model: &Model, decouple_norms: bool) -> (Gram, Vec<usize>) {
    let mut ev = model.evaluation();
    ev.evaluate(model, model.q0(), &model.initial_targets())
        .unwrap();
    let masses = BodyMass::of_model(model);
    let mut gram = Gram::with_norms(model, ev.jacobian(), &masses, &[], decouple_norms);
    let scale = vec![1.0; model.n_rows()];
    let b = vec![0.1; model.n_coords()];
    let mut y = vec![0.0; model.n_coords()];
    gram.assemble(model.q0(), ev.jacobian(), &scale, &masses, &b, &mut y);
    let group = (gram.j_rows.iter())
        .map(|&r| model.rows()[r].constraint.index())
        .collect();
    (gram, group)
}

/// A_JJ as a full dense n × n matrix (row-major).
pub(super) fn dense(gram: &Gram) -> Vec<f64> {
    let n = gram.n_j;
    let (cp, ri) = (gram.pattern.col_ptr(), gram.pattern.row_idx());
    let mut a = vec![0.0; n * n];
    for c in 0..n {
        for p in cp[c]..cp[c + 1] {
            a[ri[p] * n + c] = gram.values[p];
            a[c * n + ri[p]] = gram.values[p];
        }
    }
    a
}

/// P⁻¹ b by the sparse tree factor equals the dense Cholesky solve of P
/// formed from the dense A by the split's rule (tree × tree entries and each
/// loop constraint's own block), on the sphere toy (loops); and on a chain
/// (no loop in A's graph) P is A itself. (The lattice's and Bennett's A are
/// singular until the program masks their redundant rows: no dense
/// Cholesky of them here; `tests/al/tree.rs` runs them through programs.)
#[test]
fn the_tree_factor_solves_the_dense_p() {
    let (r, c) = sphere_toy_shape(33).unwrap();
    for (name, model, loops) in [
        (
            "sphere toy 33",
            sphere_toy_sized(r, c).build().unwrap(),
            true,
        ),
        ("chain 10", chain_sized(10).build().unwrap(), false),
    ] {
        let (gram, group) = assembled(&model);
        let n = gram.n_j;
        let sp = split(&gram, &group);
        assert_eq!(sp.loop_constraints > 0, loops, "{name}");
        let a = dense(&gram);
        let mut p = a.clone();
        for i in 0..n {
            for j in 0..n {
                let (ti, tj) = (sp.tree_row[i], sp.tree_row[j]);
                if !((ti && tj) || (!ti && !tj && group[i] == group[j])) {
                    p[i * n + j] = 0.0;
                }
            }
        }
        if !loops {
            assert_eq!(p, a, "{name}: no loop, P = A");
        }
        let mut tree = TreePrecond::new(&gram, &group, 1).unwrap();
        tree.factor(&gram).unwrap();
        let b: Vec<f64> = (0..n).map(|i| ((i * 7) % 11) as f64 - 5.0).collect();
        let mut x = b.clone();
        tree.apply(&mut x, 1);
        let (mut pd, mut y) = (p.clone(), b.clone());
        assert!(cholesky_solve(&mut pd, &mut y), "{name}: P is SPD");
        let big = y.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let gap = x
            .iter()
            .zip(&y)
            .fold(0.0f64, |m, (u, v)| m.max((u - v).abs()));
        assert!(gap <= 1e-8 * big, "{name}: {gap:e} of {big:e}");
        // And the sparse product with P's values is the dense one.
        let mut px = vec![0.0; n];
        tree.mul(&x, &mut px);
        for i in 0..n {
            let d: f64 = (0..n).map(|j| p[i * n + j] * x[j]).sum();
            assert!((px[i] - d).abs() <= 1e-9 * big.max(1.0), "{name} row {i}");
        }
    }
}

/// The tree factor has no fill beyond P's own pattern's supernodal blocks:
/// on the lattice and the sphere toy it stores fewer values than the full
/// A's factor.
#[test]
fn the_tree_factor_is_smaller_than_the_full_one() {
    let (r, c) = sphere_toy_shape(132).unwrap();
    for model in [
        lattice_sized(4, 16).build().unwrap(),
        sphere_toy_sized(r, c).build().unwrap(),
    ] {
        let (gram, group) = assembled(&model);
        let tree = TreePrecond::new(&gram, &group, 1).unwrap();
        let full = super::super::solve::MultiplierSolve::new(&gram, None, None, &[]).unwrap();
        let st = tree.stats(gram.nnz(), 0);
        assert!(st.p_nnz < gram.nnz());
        assert!(
            st.factor_values < full.factor_nnz(),
            "{st:?} against {}",
            full.factor_nnz()
        );
    }
}
