//! Gears and racks (Nelson & Cohen Fig. 12) in the fast loop: the ratio held
//! through whole turns, and Eq. 7 transmitting torque by the ratio. Angles
//! and slides are read from the bodies' poses (not from the constraint code)
//! and unwrapped tick by tick.

use std::f64::consts::PI;

use haptloop_solver::{
    BodySpec, FingerSpec, FingerTarget, GearSpec, JointKind, JointSpec, Model, ModelBuilder,
    SolverSettings, TickOutcome,
};
use nalgebra::{UnitQuaternion, Vector3};

use crate::common::*;

/// Drive gear radius to the finger, m.
const R_F: f64 = 0.04;
/// The driven gear's centre of mass from its axis, m.
const ARM: f64 = 0.05;
/// Driven gear mass, kg.
const M2: f64 = 0.4;
/// ρ: the driven gear turns −½ per turn of the drive (20 and 40 teeth).
const RHO: f64 = -0.5;
/// Rack travel per radian of pinion, m/rad.
const R_RACK: f64 = 0.03;
/// Rack mass, kg, and its slide's tilt above horizontal, rad.
const M_RACK: f64 = 0.7;
const TILT: f64 = 0.4;

/// Both gears turn about world y. The drive (balanced) at the origin holds
/// the finger at radius `R_F` straight up; the driven one, 0.1 m along x,
/// carries its mass `ARM` from its axis at angle `phi` above horizontal.
fn gear_pair(phi: f64) -> Model {
    gear_pair_with_motor(phi, None)
}

/// [`gear_pair`] with `report_torque` on the axle `motor`.
fn gear_pair_with_motor(phi: f64, motor: Option<&str>) -> Model {
    let mut b = ModelBuilder::new();
    b.gravity(G);
    b.body(BodySpec::fixed("ground"));
    b.body(BodySpec::new("drive").mass(0.3).inertia([2e-4, 3e-4, 2e-4]));
    let com = Vector3::new(0.1 + ARM * phi.cos(), 0.0, ARM * phi.sin());
    b.body(
        BodySpec::new("driven")
            .at(com.into())
            .mass(M2)
            .inertia([5e-4, 8e-4, 5e-4]),
    );
    let y = [0.0, 1.0, 0.0];
    let motor_on = |j: JointSpec| match (motor, &j.name) {
        (Some(m), Some(n)) if m == n => j.report_torque(),
        _ => j,
    };
    b.joint(motor_on(
        JointSpec::new(JointKind::Revolute, "ground", "drive")
            .named("drive-axle")
            .axes(y, y),
    ));
    b.joint(motor_on(
        JointSpec::new(JointKind::Revolute, "ground", "driven")
            .named("driven-axle")
            .anchors([0.1, 0.0, 0.0], (Vector3::new(0.1, 0.0, 0.0) - com).into())
            .axes(y, y),
    ));
    b.gear(GearSpec::gear("mesh", "drive-axle", "driven-axle", RHO));
    b.finger(FingerSpec::point("index", "drive", [0.0, 0.0, R_F]));
    b.build().expect("gear pair builds")
}

/// The pinion (balanced, about world y at the origin, the finger at `R_F`
/// straight up) and a rack sliding along `rack_dir()`, tilted `TILT` above
/// +x.
fn rack_and_pinion() -> Model {
    let mut b = ModelBuilder::new();
    b.gravity(G);
    b.body(BodySpec::fixed("ground"));
    b.body(
        BodySpec::new("pinion")
            .mass(0.3)
            .inertia([2e-4, 3e-4, 2e-4]),
    );
    b.body(
        BodySpec::new("rack")
            .at([0.0, 0.0, -0.05])
            .mass(M_RACK)
            .inertia([1e-3, 2e-3, 2e-3]),
    );
    let y = [0.0, 1.0, 0.0];
    b.joint(
        JointSpec::new(JointKind::Revolute, "ground", "pinion")
            .named("axle")
            .axes(y, y),
    );
    b.joint(
        JointSpec::new(JointKind::Prismatic, "ground", "rack")
            .named("slide")
            .anchors([0.0, 0.0, -0.05], [0.0; 3])
            .axes(rack_dir().into(), rack_dir().into()),
    );
    b.gear(GearSpec::rack_pinion("teeth", "axle", "slide", R_RACK));
    b.finger(FingerSpec::point("index", "pinion", [0.0, 0.0, R_F]));
    b.build().expect("rack and pinion builds")
}

fn rack_dir() -> Vector3<f64> {
    Vector3::new(TILT.cos(), 0.0, TILT.sin())
}

/// A body's rotation about world y from its Euler parameters, unwrapped
/// against `prev` (the last value).
fn angle_about_y(q: &[f64], offset: usize, prev: f64) -> f64 {
    let e = &q[offset + 3..offset + 7];
    let r = UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(e[0], e[1], e[2], e[3]));
    let (axis_angle, about_y) = (r.scaled_axis(), Vector3::y());
    let a = axis_angle.dot(&about_y);
    a + 2.0 * PI * ((prev - a) / (2.0 * PI)).round()
}

/// The finger's target on its circle after `turns` turns of the drive
/// about +y (starting straight up).
fn on_circle(turns: f64) -> FingerTarget {
    let a = 2.0 * PI * turns;
    // +y rotation takes z towards +x.
    FingerTarget::at(Vector3::new(a.sin(), 0.0, a.cos()) * R_F)
}

/// The finger drives the drive gear 1.5 turns (through ±π twice as seen by
/// the wrapped joint angles); after every tick the driven gear's angle is ρ
/// times the drive's to 1e-9 rad, both read from the bodies' quaternions.
#[test]
fn a_gear_pair_holds_its_ratio_through_whole_turns() {
    let model = gear_pair(0.0);
    let [o1, o2] = ["drive", "driven"].map(|n| {
        model
            .layout()
            .body_offset(model.body_id(n).unwrap())
            .unwrap()
    });
    let mut p = program(model, SolverSettings::default());
    let (mut t1, mut t2, mut worst) = (0.0, 0.0, 0.0f64);
    let ticks = 1500;
    for k in 1..=ticks {
        let r = p.tick(&[on_circle(1.5 * k as f64 / ticks as f64)], DT);
        assert_eq!(r.status, TickOutcome::Ok, "tick {k}");
        t1 = angle_about_y(p.q(), o1, t1);
        t2 = angle_about_y(p.q(), o2, t2);
        worst = worst.max((t2 - RHO * t1).abs());
    }
    assert!(t1 > 1.4 * 2.0 * PI, "the drive turned {t1} rad");
    assert!(worst < 1e-9, "ratio error {worst:e} rad");
}

/// Held still under gravity, the driven gear's weight puts τ₂ = m g l cos φ
/// about its axle; by virtual work the drive must hold τ₁ = −ρ τ₂, and
/// Eq. 7's finger force (tangential, the smallest that balances) is
/// τ₁ / R_F.
#[test]
fn eq_7_transmits_torque_by_the_gear_ratio() {
    for phi in [0.0, 0.7, 2.5] {
        let model = gear_pair(phi);
        let targets = model.initial_targets();
        let mut p = program(model, SolverSettings::default());
        hold(&mut p, &targets, 5);
        let f = p.finger_outputs()[0].constraint_force_n;
        let tau2 = M2 * 9.81 * ARM * phi.cos();
        let tau1 = -RHO * tau2;
        // The force the finger applies is −f, at (0, 0, R_F).
        let applied = Vector3::new(0.0, 0.0, R_F).cross(&-f).y;
        assert!(
            (applied - tau1).abs() < 1e-9 * M2 * 9.81 * ARM,
            "φ {phi}: finger torque {applied} N·m, expected {tau1}"
        );
        assert!(f.z.abs() < 1e-9 * f.norm().max(1e-12) && f.y.abs() < 1e-9);
    }
}

/// §5.2's joint torque through the gears: a motor on the drive axle must
/// hold −ρ τ₂ against the driven gear's weight, one on the driven axle −τ₂
/// (τ₂ = m g l cos φ, gravity's torque about +y), whatever the finger does.
#[test]
fn a_motor_torque_is_transmitted_by_the_gear_ratio() {
    for phi in [0.0f64, 0.7, 2.5] {
        let tau2 = M2 * 9.81 * ARM * phi.cos();
        for (axle, expected) in [("drive-axle", -RHO * tau2), ("driven-axle", -tau2)] {
            let model = gear_pair_with_motor(phi, Some(axle));
            let targets = model.initial_targets();
            let mut p = program(model, SolverSettings::default());
            hold(&mut p, &targets, 5);
            let tau = p.joint_torques()[0];
            assert!(
                (tau - expected).abs() < 1e-9 * M2 * 9.81 * ARM,
                "φ {phi}, motor on {axle}: {tau} N·m, expected {expected}"
            );
        }
    }
}

/// The pinion turned 1.2 turns by the finger slides the rack by r θ to
/// 1e-9 m; held still, the rack's weight along its tilted slide needs a
/// pinion torque r m g sin β, which Eq. 7 puts on the finger.
#[test]
fn a_rack_follows_its_pinion_and_loads_it_by_the_ratio() {
    let model = rack_and_pinion();
    let [op, or] = ["pinion", "rack"].map(|n| {
        model
            .layout()
            .body_offset(model.body_id(n).unwrap())
            .unwrap()
    });
    let s0 = Vector3::new(model.q0()[or], model.q0()[or + 1], model.q0()[or + 2]);
    let targets = model.initial_targets();
    let mut p = program(model, SolverSettings::default());
    hold(&mut p, &targets, 5);
    let f = p.finger_outputs()[0].constraint_force_n;
    let applied = Vector3::new(0.0, 0.0, R_F).cross(&-f).y;
    // The rack's weight pulls it down the slide: −m g sin β along rack_dir;
    // the pinion must push it up, τ = r · m g sin β (s = r θ).
    let expected = R_RACK * M_RACK * 9.81 * TILT.sin();
    assert!(
        (applied - expected).abs() < 1e-9 * expected,
        "pinion torque {applied} N·m, expected {expected}"
    );
    let (mut theta, mut worst) = (0.0, 0.0f64);
    let ticks = 1200;
    for k in 1..=ticks {
        let r = p.tick(&[on_circle(1.2 * k as f64 / ticks as f64)], DT);
        assert_eq!(r.status, TickOutcome::Ok, "tick {k}");
        theta = angle_about_y(p.q(), op, theta);
        let s = (Vector3::new(p.q()[or], p.q()[or + 1], p.q()[or + 2]) - s0).dot(&rack_dir());
        worst = worst.max((s - R_RACK * theta).abs());
    }
    assert!(theta > 1.1 * 2.0 * PI, "the pinion turned {theta} rad");
    assert!(worst < 1e-9, "rack error {worst:e} m");
}
