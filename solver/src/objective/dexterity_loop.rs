//! A closed dexterity chain's loop (Park & Kim, Nelson & Cohen's ref. 41):
//! the projector P onto the joint rates the loop allows, its degrees of
//! freedom, and the per-column buffers of `dexterity`. Split from
//! `dexterity`.

use nalgebra::{Matrix6, Vector6};

use super::dexterity::{Dexterity, LOOP_RANK_TOLERANCE, LOOP_ROW_TOLERANCE};
use super::grad::BodyGrad;
use super::sym6::pseudo_inverse;

/// Per-column buffers, allocated once by `ObjectiveEval`.
#[derive(Debug, Clone)]
pub(crate) struct DexScratch {
    /// s_c, then J̃'s column, W_J's and W_H's.
    pub(super) s: Vec<Vector6<f64>>,
    pub(super) j: Vec<Vector6<f64>>,
    pub(super) wj: Vec<Vector6<f64>>,
    pub(super) wh: Vec<Vector6<f64>>,
    /// H⁺ (n × 6, one row per column) and P (n × n, row-major).
    pub(super) hp: Vec<Vector6<f64>>,
    pub(super) p: Vec<f64>,
    /// An orthonormal basis of H's row space (up to 6 rows of n).
    pub(super) basis: Vec<f64>,
}

impl DexScratch {
    /// For chains of up to `columns` columns.
    pub fn new(columns: usize) -> Self {
        let v = vec![Vector6::zeros(); columns];
        Self {
            s: v.clone(),
            j: v.clone(),
            wj: v.clone(),
            wh: v.clone(),
            hp: v,
            p: vec![0.0; columns * columns],
            basis: vec![0.0; 6 * columns],
        }
    }
}

impl Dexterity {
    /// P = I − Σ_k u_k u_kᵀ over an orthonormal basis u_k of H's row space,
    /// by modified Gram–Schmidt run twice ("twice is enough"): accurate to
    /// round-off times H's condition, where I − H⁺H through (H Hᵀ)⁺ would
    /// square it (F's value then carries that error, 1e-11 measured, and
    /// finite differences of it go astray). A row whose part outside the
    /// others is below [`LOOP_ROW_TOLERANCE`] of its length is dependent.
    pub(super) fn projector(&self, x: &mut DexScratch) {
        let n = self.columns.len();
        let mut basis = 0;
        for row in 0..6 {
            let u = &mut x.basis[basis * n..(basis + 1) * n];
            for (c, v) in u.iter_mut().enumerate() {
                *v = x.s[c][row];
            }
            let norm0 = u.iter().map(|v| v * v).sum::<f64>().sqrt();
            if norm0 == 0.0 {
                continue;
            }
            for _ in 0..2 {
                for k in 0..basis {
                    let (done, rest) = x.basis.split_at_mut(basis * n);
                    let b = &done[k * n..(k + 1) * n];
                    let u = &mut rest[..n];
                    let d: f64 = b.iter().zip(u.iter()).map(|(p, q)| p * q).sum();
                    u.iter_mut().zip(b).for_each(|(q, p)| *q -= d * p);
                }
            }
            let u = &mut x.basis[basis * n..(basis + 1) * n];
            let norm = u.iter().map(|v| v * v).sum::<f64>().sqrt();
            if norm > LOOP_ROW_TOLERANCE * norm0 {
                u.iter_mut().for_each(|v| *v /= norm);
                basis += 1;
            }
        }
        for a in 0..n {
            for b in 0..n {
                let q: f64 = (0..basis)
                    .map(|k| x.basis[k * n + a] * x.basis[k * n + b])
                    .sum();
                x.p[a * n + b] = if a == b { 1.0 } else { 0.0 } - q;
            }
        }
    }

    /// The loop's degrees of freedom at q: columns minus the rank of H.
    /// Allocates (build time).
    pub fn loop_dof(&self, g: &BodyGrad, q: &[f64]) -> usize {
        let mut x = DexScratch::new(self.columns.len());
        if self.columns(g, q, &mut x).is_none() {
            return 0;
        }
        let n = self.columns.len();
        let hht: Matrix6<f64> = x.s[..n].iter().map(|s| s * s.transpose()).sum();
        pseudo_inverse(&hht, LOOP_RANK_TOLERANCE).map_or(0, |(_, rank)| n - rank)
    }
}
