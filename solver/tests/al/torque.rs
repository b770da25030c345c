//! §5.2's joint torques: the torque a motor on a named joint's axis would
//! need to make the mechanism's motion, against closed forms.

use haptloop_solver::{
    BodySpec, FingerSpec, FingerTarget, JointKind, JointSpec, ModelBuilder, SolverSettings,
    TickOutcome,
};
use nalgebra::Vector3;

use crate::common::*;

/// The pendulum of `common::pendulum` with a motor reported on its hinge.
fn pendulum_with_motor(theta: f64) -> haptloop_solver::Model {
    let d = arm_dir(theta);
    let rot = nalgebra::UnitQuaternion::from_axis_angle(&Vector3::y_axis(), -theta);
    let q = rot.quaternion();
    let mut b = ModelBuilder::new();
    b.gravity(G);
    b.body(BodySpec::fixed("ground"));
    b.body(
        BodySpec::new("arm")
            .at((d * L_C).into())
            .oriented([q.w, q.i, q.j, q.k])
            .mass(ARM_KG)
            .inertia([ARM_KG * 0.04 / 12.0, ARM_KG * 0.04 / 12.0, 1e-6]),
    );
    b.joint(
        JointSpec::new(JointKind::Revolute, "ground", "arm")
            .named("hinge")
            .anchors([0.0; 3], [0.0, 0.0, L_C])
            .axes([0.0, 1.0, 0.0], [0.0, 1.0, 0.0])
            .report_torque(),
    );
    b.finger(FingerSpec::point("tip", "arm", [0.0, 0.0, -(L_F - L_C)]));
    b.build().expect("pendulum builds")
}

/// Held still at θ from hanging, gravity turns the arm about +y with
/// m g l sin θ; the hinge's motor must apply the opposite (the brief's
/// m g l cos θ with θ from horizontal), and that is also the finger's
/// torque about the hinge from Eq. 7.
#[test]
fn a_pendulum_held_still_needs_m_g_l_sin_theta_at_its_hinge() {
    for theta in [0.3, 1.0, 2.0, -0.7] {
        let model = pendulum_with_motor(theta);
        assert_eq!(model.torque_joints().len(), 1);
        let targets = model.initial_targets();
        let mut p = program(model, SolverSettings::default());
        hold(&mut p, &targets, 5);
        let tau = p.joint_torques()[0];
        let expected = -ARM_KG * 9.81 * L_C * theta.sin();
        assert!(
            (tau - expected).abs() < 1e-9 * ARM_KG * 9.81 * L_C,
            "θ {theta}: {tau} N·m, expected {expected}"
        );
        let f = p.finger_outputs()[0].constraint_force_n;
        let finger = (arm_dir(theta) * L_F).cross(&-f).y;
        assert!((finger - tau).abs() < 1e-9 * ARM_KG * 9.81 * L_C);
    }
}

/// A failed tick reports no torque (NaN), not a zero.
#[test]
fn a_failed_tick_reports_no_torque() {
    let model = pendulum_with_motor(0.5);
    let mut p = program(model, SolverSettings::default());
    let bad = [FingerTarget::at(Vector3::new(f64::NAN, 0.0, 0.0))];
    assert_ne!(p.tick(&bad, DT).status, TickOutcome::Ok);
    assert!(p.joint_torques()[0].is_nan());
}

/// `report_torque` on a joint without an axis coordinate is refused.
#[test]
fn a_spherical_joint_has_no_torque_to_report() {
    let mut b = ModelBuilder::new();
    b.body(BodySpec::fixed("ground"));
    b.body(BodySpec::new("ball"));
    b.joint(
        JointSpec::new(JointKind::Spherical, "ground", "ball")
            .named("socket")
            .report_torque(),
    );
    let e = b.build().unwrap_err().to_string();
    assert!(
        e.contains("joint `socket`") && e.contains("revolute or prismatic"),
        "{e}"
    );
}
