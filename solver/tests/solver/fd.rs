//! Central finite differences of C(q), and the checker that compares them with
//! the analytic C_q.
//!
//! Step h = 1e-6 on coordinates of order 1: the central difference errs by
//! h²/6·|C'''| (≈ 1e-13 for the bounded third derivatives of these states,
//! quaternion norms ≥ 0.6) plus rounding ε·|C|/h (≈ 2e-10·|C|). The tolerance
//! 1e-7·(1 + |J|) leaves a margin of ~100× over that, while a wrong sign, factor
//! or missing term (errors of order |J|) fails it. Near singular geometry (a
//! hinge angle whose reference is almost along the axis) the third derivative
//! grows, so the tolerance adds 10× the FD's own error estimate
//! |FD(h) − FD(h/2)|, which is large only where curvature is.

use haptloop_solver::constraint::witness::Witness;
use haptloop_solver::{FingerTarget, Model};
use nalgebra::DMatrix;

/// C(q) by a fresh value-only evaluation.
pub fn values(model: &Model, q: &[f64], targets: &[FingerTarget]) -> Vec<f64> {
    values_with(model, q, targets, &[])
}

/// C(q) by a fresh value-only evaluation with the witness table `w` (the
/// contact and semantic rows' parameters; empty: the model's own).
pub fn values_with(model: &Model, q: &[f64], targets: &[FingerTarget], w: &[Witness]) -> Vec<f64> {
    let mut ev = model.evaluation();
    if !w.is_empty() {
        ev.witnesses_mut().copy_from_slice(w);
    }
    ev.evaluate_values(model, q, targets).expect("evaluate");
    ev.values().to_vec()
}

/// Central-difference Jacobian with step `h`.
pub fn fd_jacobian(model: &Model, q: &[f64], targets: &[FingerTarget], h: f64) -> DMatrix<f64> {
    fd_jacobian_with(model, q, targets, &[], h)
}

/// [`fd_jacobian`] with the witness table `w` loaded first.
pub fn fd_jacobian_with(
    model: &Model,
    q: &[f64],
    targets: &[FingerTarget],
    w: &[Witness],
    h: f64,
) -> DMatrix<f64> {
    let mut ev = model.evaluation();
    if !w.is_empty() {
        ev.witnesses_mut().copy_from_slice(w);
    }
    let mut j = DMatrix::zeros(model.n_rows(), model.n_coords());
    let mut x = q.to_vec();
    for col in 0..q.len() {
        x[col] = q[col] + h;
        ev.evaluate_values(model, &x, targets).expect("evaluate +h");
        let plus = ev.values().to_vec();
        x[col] = q[col] - h;
        ev.evaluate_values(model, &x, targets).expect("evaluate -h");
        for (r, p) in plus.iter().enumerate() {
            j[(r, col)] = (p - ev.values()[r]) / (2.0 * h);
        }
        x[col] = q[col];
    }
    j
}

/// The analytic Jacobian (dense copy) at `q`.
pub fn analytic(model: &Model, q: &[f64], targets: &[FingerTarget]) -> DMatrix<f64> {
    let mut ev = model.evaluation();
    ev.evaluate(model, q, targets).expect("evaluate");
    ev.jacobian().to_dense()
}

/// Compares a Jacobian with finite differences; `Err` names the worst entry.
pub fn check_against_fd(
    model: &Model,
    q: &[f64],
    targets: &[FingerTarget],
    a: &DMatrix<f64>,
) -> Result<(), String> {
    let h = 1e-6;
    let fd = fd_jacobian(model, q, targets, h);
    let fd2 = fd_jacobian(model, q, targets, h / 2.0);
    for r in 0..a.nrows() {
        for c in 0..a.ncols() {
            let est = (fd[(r, c)] - fd2[(r, c)]).abs();
            let tol = 1e-7 * (1.0 + a[(r, c)].abs()) + 10.0 * est;
            let err = (a[(r, c)] - fd2[(r, c)]).abs();
            if err > tol {
                let info = &model.constraints()[model.rows()[r].constraint.index()];
                return Err(format!(
                    "row {r} ({} `{}`), col {c}: analytic {:e} vs FD {:e} (err {err:e} > tol {tol:e})",
                    info.kind,
                    info.name,
                    a[(r, c)],
                    fd2[(r, c)]
                ));
            }
        }
    }
    Ok(())
}
