//! The assembly of A against a dense product, and kept inverse masses
//! against a fresh assembly.

use super::*;
use crate::mechanisms::four_bar;
use nalgebra::DMatrix;

/// The per-body assembly equals D C M̃⁻¹ Cᵀ D formed densely.
#[test]
fn assembly_matches_a_dense_product() {
    let model = four_bar();
    let mut ev = model.evaluation();
    let q: Vec<f64> = model
        .q0()
        .iter()
        .enumerate()
        .map(|(k, v)| v + 1e-3 * ((k % 5) as f64 - 2.0))
        .collect();
    ev.evaluate(&model, &q, &model.initial_targets()).unwrap();
    let jac = ev.jacobian();
    let masses = BodyMass::of_model(&model);
    let mut gram = Gram::new(&model, jac, &masses, &[]);
    let scale: Vec<f64> = (0..model.n_rows())
        .map(|i| 1.0 + 0.1 * (i % 3) as f64)
        .collect();
    let b = vec![0.0; model.n_coords()];
    let mut y = vec![0.0; model.n_coords()];
    gram.assemble(&q, jac, &scale, &masses, &b, &mut y);
    let n = model.n_coords();
    let mut minv = DMatrix::zeros(n, n);
    for m in &masses {
        let o = m.offset;
        let e = Vector4::new(q[o + 3], q[o + 4], q[o + 5], q[o + 6]);
        let f = BodyFrame::new(
            Vector3::new(q[o], q[o + 1], q[o + 2]),
            [e[0], e[1], e[2], e[3]],
        )
        .unwrap();
        minv.view_mut((o, o), (3, 3)).fill_diagonal(1.0 / m.mass);
        minv.view_mut((o + 3, o + 3), (4, 4))
            .copy_from(&m.inv_rotational_mass(&f, &e));
    }
    let d = DMatrix::from_diagonal(&nalgebra::DVector::from_vec(scale.clone()));
    let c = jac.to_dense();
    let a = &d * &c * minv * c.transpose() * &d;
    let nnz = gram.nnz();
    let (cp, ri) = (gram.pattern.col_ptr(), gram.pattern.row_idx());
    let mut worst = 0.0f64;
    for col in 0..gram.n_j {
        for (k, &r) in ri.iter().enumerate().take(cp[col + 1]).skip(cp[col]) {
            let (i, j) = (gram.j_rows[r], gram.j_rows[col]);
            worst = worst.max((gram.values[k] - a[(i, j)]).abs());
        }
    }
    for f in 0..gram.m_f {
        for j in 0..gram.n_j {
            let v = gram.values[nnz + f * gram.n_j + j];
            worst = worst.max((v - a[(gram.finger_rows[f], gram.j_rows[j])]).abs());
        }
        for h in 0..gram.m_f {
            let v = gram.values[nnz + gram.m_f * gram.n_j + f * gram.m_f + h];
            worst = worst.max((v - a[(gram.finger_rows[f], gram.finger_rows[h])]).abs());
        }
    }
    assert!(worst < 1e-9 * a.amax(), "worst {worst}, scale {}", a.amax());
}

/// A Gram that keeps the inverse rotational masses of bodies whose
/// Euler parameters did not change assembles the same bits as a fresh
/// one, after one body turned, after it turned back, and with a
/// degenerate rotation in between (which must not leave a stale key).
#[test]
fn kept_inverse_masses_give_the_bits_of_a_fresh_assembly() {
    let model = four_bar();
    let mut ev = model.evaluation();
    let q0 = model.q0().to_vec();
    let masses = BodyMass::of_model(&model);
    let o = masses[1].offset;
    let mut turned = q0.clone();
    turned[o + 4] += 0.01;
    let mut degenerate = q0.clone();
    degenerate[o + 3..o + 7].fill(0.0);
    ev.evaluate(&model, &q0, &model.initial_targets()).unwrap();
    let jac = ev.jacobian();
    let scale = vec![1.0; model.n_rows()];
    let b: Vec<f64> = (0..model.n_coords()).map(|k| 0.1 * k as f64).collect();
    let mut kept = Gram::new(&model, jac, &masses, &[]);
    let mut y = vec![0.0; model.n_coords()];
    let mut fresh_y = y.clone();
    for q in [&q0, &turned, &degenerate, &q0, &turned] {
        kept.assemble(q, jac, &scale, &masses, &b, &mut y);
        let mut fresh = Gram::new(&model, jac, &masses, &[]);
        fresh.assemble(q, jac, &scale, &masses, &b, &mut fresh_y);
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&kept.values), bits(&fresh.values));
        assert_eq!(bits(&y), bits(&fresh_y));
        let same = kept.minv_e.iter().zip(&fresh.minv_e);
        if q != &degenerate {
            assert!(same.clone().all(|(a, b)| a == b));
        }
    }
}
