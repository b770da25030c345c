//! The dense test: Householder QR in model order.

use std::cmp::Ordering;

use nalgebra::{Matrix4, Vector3, Vector4};

use super::{REDUNDANCY_TOLERANCE, dot, norm};
use crate::force::inertia::BodyMass;
use crate::rotation::BodyFrame;
use crate::{Evaluation, Model};

/// The rows of `rows` (model order) that are dependent on the rows before
/// them: Householder QR of B's columns b_i = ℓ_i M̃^{-1/2} C_iᵀ without
/// pivoting, skipping (and reporting) a column whose part outside the kept
/// span is at most [`REDUNDANCY_TOLERANCE`] × its length. Dense: O(n m r).
pub(super) fn dependent_in_order(
    model: &Model,
    ev: &Evaluation,
    masses: &[BodyMass],
    ell: &[f64],
    rows: &[usize],
) -> Vec<usize> {
    let q = model.q0();
    let jac = ev.jacobian();
    let nb0 = model.layout().body_coords();
    // Auxiliary blocks (flexible deformations, surface parameters) take
    // part with their metric: Lᵀ with L Lᵀ = H⁻¹, after the bodies'.
    let aux: Vec<(usize, usize, nalgebra::DMatrix<f64>)> = model
        .layout()
        .aux_blocks()
        .iter()
        .filter_map(|b| {
            let inv = nalgebra::DMatrix::from_row_slice(b.width, b.width, &b.inv_metric);
            Some((b.offset, b.width, inv.cholesky()?.l().transpose()))
        })
        .collect();
    let nb = nb0 + aux.iter().map(|a| a.1).sum::<usize>();
    // M̃^{-1/2} per body: 1/√m on r, Lᵀ with L Lᵀ = M̃_e⁻¹ on e.
    let halves: Vec<(usize, f64, Matrix4<f64>)> = masses
        .iter()
        .filter_map(|m| {
            let o = m.offset;
            let e = Vector4::new(q[o + 3], q[o + 4], q[o + 5], q[o + 6]);
            let frame = BodyFrame::new(Vector3::new(q[o], q[o + 1], q[o + 2]), e.into())?;
            let l = m.inv_rotational_mass(&frame, &e).cholesky()?.l();
            Some((o, 1.0 / m.mass.sqrt(), l.transpose()))
        })
        .collect();
    let mut col = vec![0.0; nb];
    let mut raw = vec![0.0; model.n_coords()];
    // Reflectors: v_j lives in reflectors[j * nb + j..(j + 1) * nb].
    let mut reflectors: Vec<f64> = Vec::new();
    let mut betas: Vec<f64> = Vec::new();
    let mut dependent = Vec::new();
    for &i in rows {
        raw.fill(0.0);
        let span = jac.row_ptr()[i]..jac.row_ptr()[i + 1];
        for p in span {
            raw[jac.col_idx()[p]] = ell[i] * jac.values()[p];
        }
        col.fill(0.0);
        for (o, inv_sqrt_m, lt) in &halves {
            for c in 0..3 {
                col[o + c] = raw[o + c] * inv_sqrt_m;
            }
            let ce = lt * Vector4::new(raw[o + 3], raw[o + 4], raw[o + 5], raw[o + 6]);
            col[o + 3..o + 7].copy_from_slice(ce.as_slice());
        }
        let mut at = nb0;
        for (o, w, lt) in &aux {
            let c = lt * nalgebra::DVector::from_column_slice(&raw[*o..o + w]);
            col[at..at + w].copy_from_slice(c.as_slice());
            at += w;
        }
        let own = norm(&col);
        let kept = betas.len();
        for (j, &beta) in betas.iter().enumerate() {
            let v = &reflectors[j * nb + j..(j + 1) * nb];
            let t = beta * dot(v, &col[j..]);
            for (c, vk) in col[j..].iter_mut().zip(v) {
                *c -= t * vk;
            }
        }
        let tail = norm(&col[kept..]);
        let independent =
            tail.partial_cmp(&(REDUNDANCY_TOLERANCE * own)) == Some(Ordering::Greater);
        if !independent || kept == nb {
            dependent.push(i);
            continue;
        }
        let alpha = if col[kept] >= 0.0 { -tail } else { tail };
        let mut v = vec![0.0; nb];
        v[kept..].copy_from_slice(&col[kept..]);
        v[kept] -= alpha;
        let vv = dot(&v[kept..], &v[kept..]);
        reflectors.extend_from_slice(&v);
        betas.push(2.0 / vv);
    }
    dependent
}
