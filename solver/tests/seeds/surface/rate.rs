//! Eq. 16, u̇ = D q̇: the closed form (`Model::contact_rate`) against
//! finite differences of the nearest-point parameters, and against what the
//! fast update does to the (u, v) coordinates when a finger moves the ball.

use haptloop_solver::parametric::{Surface, SurfaceKind};
use haptloop_solver::{BodyId, ConstraintId, FingerTarget};
use nalgebra::{Matrix3, Vector3};

use super::common::{DT, LEVEL, R, ball, bowl, program};

#[test]
fn the_contact_rate_is_the_derivative_of_the_contact_parameters() {
    for kind in [
        bowl(),
        SurfaceKind::Sphere {
            radius_m: 0.15,
            concave: false,
        },
        SurfaceKind::Cylinder {
            radius_m: 0.1,
            concave: true,
        },
    ] {
        let model = ball(kind, LEVEL, [0.04, -0.02], true, false);
        let q = model.q0().to_vec();
        let d = model.contact_rate(&q, ConstraintId(0)).unwrap();
        let s = Surface::new(kind, Vector3::zeros(), Matrix3::identity());
        let c = model.body_position(&q, BodyId(1)).unwrap();
        let uv = &q[model.contact_parameters(ConstraintId(0)).unwrap()];
        let h = 1e-6;
        for dir in [Vector3::x(), Vector3::y(), Vector3::new(0.3, -0.5, 0.8)] {
            let (plus, _) = s.project(&(c + dir * h), R);
            let (minus, _) = s.project(&(c - dir * h), R);
            let fd = [
                (plus[0] - minus[0]) / (2.0 * h),
                (plus[1] - minus[1]) / (2.0 * h),
            ];
            let want = d * dir;
            assert!(
                (fd[0] - want[0]).abs() < 1e-7 && (fd[1] - want[1]).abs() < 1e-7,
                "{kind:?} {dir}: FD {fd:?} vs D {want}"
            );
            // At the point itself the projection is exact.
            let ([u0, v0], dist) = s.project(&c, R);
            assert!(dist < 1e-12 && (u0 - uv[0]).abs() < 1e-12 && (v0 - uv[1]).abs() < 1e-12);
        }
    }
}

/// One tick of a small finger motion moves (u, v) by D Δp, to second order.
#[test]
fn the_update_moves_the_contact_parameters_by_eq_16() {
    let model = ball(bowl(), LEVEL, [0.03, 0.01], true, false);
    let mut p = program(model.clone());
    let uv = model.contact_parameters(ConstraintId(0)).unwrap();
    let q0 = p.q().to_vec();
    let d = model.contact_rate(&q0, ConstraintId(0)).unwrap();
    let c0 = model.body_position(&q0, BodyId(1)).unwrap();
    // A tangential step of 10 µm.
    let n = (Vector3::new(0.0, 0.0, 0.2) - c0).normalize();
    let step = (Vector3::new(1.0, 0.4, 0.0) - n * n.dot(&Vector3::new(1.0, 0.4, 0.0))) * 1e-5;
    p.tick(&[FingerTarget::at(c0 + step)], DT);
    let q1 = p.q();
    let moved = model.body_position(q1, BodyId(1)).unwrap() - c0;
    let want = d * moved;
    for k in 0..2 {
        let got = q1[uv.start + k] - q0[uv.start + k];
        assert!(
            (got - want[k]).abs() < 1e-8 * moved.norm() * 1e3,
            "{k}: {got:e} vs {:e}",
            want[k]
        );
    }
}
