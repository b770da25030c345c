//! A physical pendulum on a revolute joint, released at 0.1 rad: its
//! period is 2π √(I/(m g d)) (1 + θ₀²/16) and its energy stays put without
//! damping, over 20 s at 1 kHz and 250 Hz.

use std::f64::consts::PI;
use std::sync::Arc;

use haptloop_solver::{BodySpec, JointKind, JointSpec, ModelBuilder, Program, TickOutcome};
use nalgebra::{UnitQuaternion, Vector3};

use crate::common::{G, RATES, dynamics, period, rel, ticks};

/// Mass, kg; distance pivot → centre of mass, m; moment about the centre
/// of mass (the default: a solid 5 cm sphere), kg·m².
const M: f64 = 0.05;
const D: f64 = 0.1;
const J: f64 = 0.4 * M * 0.05 * 0.05;

/// The pendulum released at `theta0` about y: per tick, its angle and the
/// program's energy figure.
fn swing(rate: u32, theta0: f64, seconds: f64) -> (Vec<f64>, Vec<f64>) {
    let tilt = UnitQuaternion::from_axis_angle(&Vector3::y_axis(), theta0);
    let at = tilt * Vector3::new(0.0, 0.0, -D);
    let e = tilt.quaternion();
    let mut b = ModelBuilder::new();
    b.gravity([0.0, 0.0, -G]);
    b.body(BodySpec::fixed("pivot"));
    b.body(
        BodySpec::new("bob")
            .at(at.into())
            .oriented([e.w, e.i, e.j, e.k])
            .mass(M),
    );
    b.joint(
        JointSpec::new(JointKind::Revolute, "pivot", "bob")
            .anchors([0.0; 3], [0.0, 0.0, D])
            .axes([0.0, 1.0, 0.0], [0.0, 1.0, 0.0]),
    );
    let model = Arc::new(b.build().unwrap());
    let id = model.body_id("bob").unwrap();
    let mut p = Program::new(model.clone(), dynamics()).unwrap();
    let dt = period(rate);
    let (mut theta, mut energy) = (Vec::new(), Vec::new());
    for k in 0..ticks(seconds, rate) {
        let r = p.tick(&[], dt);
        assert_eq!(r.status, TickOutcome::Ok, "{rate} Hz tick {k}");
        let x = model.body_position(p.q(), id).unwrap();
        theta.push(x.x.atan2(-x.z));
        energy.push(r.energy.energy_j);
    }
    (theta, energy)
}

#[test]
fn a_pendulum_keeps_its_period_and_its_energy() {
    let theta0 = 0.1;
    let inertia = J + M * D * D;
    let analytic = 2.0 * PI * (inertia / (M * G * D)).sqrt() * (1.0 + theta0 * theta0 / 16.0);
    // Energy above the pendulum at rest at the bottom.
    let swing_j = M * G * D * (1.0 - theta0.cos());
    for rate in RATES {
        let (theta, energy) = swing(rate, theta0, 20.0);
        let dt = 1.0 / f64::from(rate);
        // Upward zero crossings, interpolated within the tick.
        let ups: Vec<f64> = (1..theta.len())
            .filter(|&k| theta[k - 1] < 0.0 && theta[k] >= 0.0)
            .map(|k| (k as f64 + theta[k - 1] / (theta[k - 1] - theta[k])) * dt)
            .collect();
        let measured = (ups[ups.len() - 1] - ups[0]) / (ups.len() - 1) as f64;
        // The program's energy, against the bottom's (−m g d): from the
        // second tick on (the first reports the start).
        let bottom = -M * G * D;
        let worst = energy[1..]
            .iter()
            .map(|e| rel(e - bottom, swing_j))
            .fold(0.0, f64::max);
        // Independently of the program's figure: the amplitude of the last
        // swing against θ₀.
        let last = ticks(analytic, rate);
        let amplitude = theta[theta.len() - last..]
            .iter()
            .fold(0.0_f64, |a, t| a.max(t.abs()));
        println!(
            "pendulum {rate} Hz: period {measured:.6} s (analytic {analytic:.6}), energy within {worst:.2e}, \
             amplitude after 20 s {amplitude:.5} rad"
        );
        assert!(
            rel(measured, analytic) < 0.01,
            "{rate} Hz: period {measured} s"
        );
        assert!(worst < 0.02, "{rate} Hz: energy off by {worst:.2e}");
        assert!(
            rel(amplitude, theta0) < 0.01,
            "{rate} Hz: amplitude {amplitude} rad"
        );
    }
}
