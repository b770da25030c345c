//! Eq. 8: from a generalized force on one body's seven columns to a world-frame
//! force and torque, and from finger multipliers to the wrench on the finger.
//!
//! A world force F at the body origin and a world torque τ do virtual work
//! F·δr + τ·δθ = F·δr + (Ωᵀτ)·δe, so their generalized force is
//! W_c = [F; Ωᵀ τ]. Back: F = W_c[r], and because Ω Ωᵀ = (4/|e|²) I and Ω e = 0,
//! τ = (|e|²/4) Ω W_c[e] — Nelson & Cohen's W = ¼ G W_c with G = Ω for unit e
//! (the e-component along e, which only the norm row produces, drops out).
//! Verified by virtual work in the tests, for non-unit e too.
//!
//! Sign: Eq. 6 reads M q̈ + C_qᵀλ = Q, so a constraint pushes the bodies with
//! −C_qᵀλ. The finger row C = p(q) − p_target with p the attachment point has
//! ∂C/∂q = ∂p/∂q, so the finger pushes the body with the world force −λ at p,
//! and the body pushes the finger with +λ: **λ of a point finger's rows is the
//! force on the finger**, e.g. m g (downwards) for a body hanging from it.

use nalgebra::{Vector3, Vector4};

use crate::rotation::BodyFrame;

/// World force (N) and torque about the body origin (N·m) of a generalized
/// force `w_c` on one moving body's columns [r (3), e (4)] at Euler parameters
/// `e` (any norm): Eq. 8. `None` for a degenerate quaternion.
pub fn body_wrench(e: [f64; 4], w_c: &[f64; 7]) -> Option<(Vector3<f64>, Vector3<f64>)> {
    let f = BodyFrame::new(Vector3::zeros(), e)?;
    Some(wrench(&f, w_c))
}

#[inline]
pub(crate) fn wrench(f: &BodyFrame, w_c: &[f64; 7]) -> (Vector3<f64>, Vector3<f64>) {
    let [w, x, y, z] = [w_c[3], w_c[4], w_c[5], w_c[6]];
    // s/4 with s = |e|², recovered from Ω: Ω Ωᵀ = (4/s) I.
    let s_over_4 = 1.0 / f.omega.row(0).norm_squared();
    let tau = f.omega * Vector4::new(w, x, y, z) * s_over_4;
    (Vector3::new(w_c[0], w_c[1], w_c[2]), tau)
}

/// The wrench on the finger (world force, N; world torque about the
/// attachment point `p`, N·m) from the generalized force `w_c` that the
/// finger constraint's multipliers produce on the held body, C_fᵀλ_f
/// restricted to the body's columns. The finger pushes the body with −w_c;
/// the body pushes the finger with the opposite wrench.
#[inline]
pub(crate) fn on_finger(
    f: &BodyFrame,
    p: &Vector3<f64>,
    w_c: &[f64; 7],
) -> (Vector3<f64>, Vector3<f64>) {
    // The body receives −(f_c, τ_c) (about its origin) from the finger, so the
    // finger receives (f_c, τ_c); moved from the origin r to p: τ − (p − r) × f.
    let (f_c, tau_c) = wrench(f, w_c);
    (f_c, tau_c - (p - f.r).cross(&f_c))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn eq8_factor_recovers_a_torque_for_non_unit_e() {
        let e = [1.2, -0.4, 0.6, 0.3];
        let f = BodyFrame::new(Vector3::zeros(), e).unwrap();
        let (force, tau) = (Vector3::new(1.0, -2.0, 0.5), Vector3::new(0.3, 0.1, -0.7));
        let ge = f.omega.transpose() * tau;
        let w_c = [force.x, force.y, force.z, ge[0], ge[1], ge[2], ge[3]];
        let (f2, t2) = body_wrench(e, &w_c).unwrap();
        assert!((f2 - force).norm() < 1e-15 && (t2 - tau).norm() < 1e-14);
    }
}
