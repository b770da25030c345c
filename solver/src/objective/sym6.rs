//! Symmetric positive semi-definite matrices up to 6 × 6 (padded with ones
//! on the unused diagonal): the determinant and adjugate of a Gram matrix
//! and a pseudo-inverse, through one eigendecomposition each, finite at
//! singular matrices (the dexterity objective's G and its loop's H Hᵀ).
//!
//! # Real-time
//! No allocation (static 6 × 6 storage); nalgebra's symmetric QR
//! eigensolver, capped at [`MAX_SWEEPS`] iterations (6 × 6 converges in a
//! few dozen).

use nalgebra::{Matrix3, Matrix6, SymmetricEigen};

/// The eigensolver's iteration cap.
pub(crate) const MAX_SWEEPS: usize = 500;

/// det(A) and adj(A) of a symmetric A that is the identity outside its
/// leading `size` × `size` block. Up to 3 × 3: cofactors (exact zeros where
/// they cancel: a singular pose's gradient is zero, not round-off); larger:
/// with A = V Λ Vᵀ, det = Π λ and adj = V diag(Π_{j≠i} λ_j) Vᵀ (= det · A⁻¹
/// where A is invertible, finite where it is not). `None` if the
/// eigensolver does not converge.
pub(crate) fn det_adjugate(a: &Matrix6<f64>, size: usize) -> Option<(f64, Matrix6<f64>)> {
    if size <= 3 {
        let b: Matrix3<f64> = a.fixed_view::<3, 3>(0, 0).into_owned();
        let det = b.determinant();
        let mut adj = Matrix6::identity() * det;
        adj.fixed_view_mut::<3, 3>(0, 0).copy_from(&adjugate3(&b));
        return Some((det, adj));
    }
    let e = SymmetricEigen::try_new(*a, 1e-15, MAX_SWEEPS)?;
    let l = e.eigenvalues;
    let det: f64 = l.iter().product();
    let mut d = [0.0; 6];
    for (i, di) in d.iter_mut().enumerate() {
        *di = (0..6).filter(|&j| j != i).map(|j| l[j]).product();
    }
    let v = e.eigenvectors;
    let mut adj = Matrix6::zeros();
    for (i, &di) in d.iter().enumerate() {
        let c = v.column(i);
        adj += c * c.transpose() * di;
    }
    Some((det, adj))
}

/// adj(A) = cofactor matrixᵀ of a 3 × 3 A, finite for a singular A
/// (A adj(A) = det(A) I).
fn adjugate3(a: &Matrix3<f64>) -> Matrix3<f64> {
    let c = |r0: usize, r1: usize, c0: usize, c1: usize| {
        a[(r0, c0)] * a[(r1, c1)] - a[(r0, c1)] * a[(r1, c0)]
    };
    #[rustfmt::skip]
    let adj = Matrix3::new(
        c(1, 2, 1, 2), -c(0, 2, 1, 2), c(0, 1, 1, 2),
        -c(1, 2, 0, 2), c(0, 2, 0, 2), -c(0, 1, 0, 2),
        c(1, 2, 0, 1), -c(0, 2, 0, 1), c(0, 1, 0, 1),
    );
    adj
}

/// The pseudo-inverse of a symmetric positive semi-definite A: eigenvalues
/// at most `rel_tol` × the largest count as zero. Also returns the rank.
pub(crate) fn pseudo_inverse(a: &Matrix6<f64>, rel_tol: f64) -> Option<(Matrix6<f64>, usize)> {
    let e = SymmetricEigen::try_new(*a, 1e-15, MAX_SWEEPS)?;
    let top = e.eigenvalues.iter().fold(0.0f64, |m, &x| m.max(x));
    let mut out = Matrix6::zeros();
    let mut rank = 0;
    for i in 0..6 {
        let l = e.eigenvalues[i];
        if top > 0.0 && l > rel_tol * top {
            let c = e.eigenvectors.column(i);
            out += c * c.transpose() / l;
            rank += 1;
        }
    }
    Some((out, rank))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spd() -> Matrix6<f64> {
        let b = Matrix6::from_fn(|i, j| {
            ((i * 7 + j * 3) % 5) as f64 - 1.5 + if i == j { 3.0 } else { 0.0 }
        });
        b * b.transpose()
    }

    #[test]
    fn adjugate_is_det_times_inverse_and_finite_when_singular() {
        let a = spd();
        let (det, adj) = det_adjugate(&a, 6).unwrap();
        assert!((det - a.determinant()).abs() < 1e-9 * det.abs());
        assert!((a * adj - Matrix6::identity() * det).norm() < 1e-9 * det.abs());
        let mut s = a;
        s.set_row(5, &s.row(4).clone_owned());
        s.set_column(5, &s.column(4).clone_owned());
        let (det, adj) = det_adjugate(&s, 6).unwrap();
        assert!(det.abs() < 1e-6 * a.determinant().abs());
        assert!(adj.iter().all(|v| v.is_finite()));
        assert!((s * adj).norm() < 1e-6 * adj.norm());
    }

    #[test]
    fn small_blocks_take_cofactors() {
        let mut a = Matrix6::identity();
        let b = Matrix3::new(2.0, 0.3, -1.0, 0.3, 1.5, 0.2, -1.0, 0.2, 0.9);
        a.fixed_view_mut::<3, 3>(0, 0).copy_from(&b);
        let (det, adj) = det_adjugate(&a, 3).unwrap();
        assert!((det - b.determinant()).abs() < 1e-14);
        assert!((a * adj - Matrix6::identity() * det).norm() < 1e-12);
        let (d6, a6) = det_adjugate(&a, 6).unwrap();
        assert!((d6 - det).abs() < 1e-12 && (a6 - adj).norm() < 1e-10);
    }

    #[test]
    fn pseudo_inverse_inverts_on_the_range() {
        let a = spd();
        let (p, rank) = pseudo_inverse(&a, 1e-12).unwrap();
        assert_eq!(rank, 6);
        assert!((a * p - Matrix6::identity()).norm() < 1e-9);
        let mut low = Matrix6::zeros();
        low.fixed_view_mut::<3, 3>(0, 0)
            .copy_from(&a.fixed_view::<3, 3>(0, 0));
        let (p, rank) = pseudo_inverse(&low, 1e-12).unwrap();
        assert_eq!(rank, 3);
        assert!((low * p * low - low).norm() < 1e-9 * low.norm());
    }
}
