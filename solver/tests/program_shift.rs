//! `Program::shift_q` applies a correction without disturbing the motion
//! history. A free 1 kg body is carried around a circle by a point finger;
//! at one tick both the body and the target path are translated by δ, so the
//! motion after it is the reference motion translated. `shift_q` then
//! reproduces the reference force to round-off, while `set_q` (a jump: the
//! motion restarts at rest) loses one tick of inertial force m·a. The coupling
//! damper is off: translating the target path (which a real re-projection never
//! does) would otherwise show up in it as a one-tick velocity δ/dt.

use std::sync::Arc;
use std::time::Duration;

use haptloop_solver::{BodySpec, FingerSpec, FingerTarget, ModelBuilder, Program, SolverSettings};
use nalgebra::Vector3;

const DT: Duration = Duration::from_millis(1);

/// A 1 cm circle at 2 Hz: centripetal acceleration r ω² ≈ 1.58 m/s².
fn target(k: usize, offset: Vector3<f64>) -> [FingerTarget; 1] {
    let w = 2.0 * std::f64::consts::PI * 2.0 * k as f64 * DT.as_secs_f64();
    [FingerTarget::at(
        Vector3::new(0.01 * (w.cos() - 1.0), 0.01 * w.sin(), 0.0) + offset,
    )]
}

#[test]
fn a_shift_keeps_the_inertial_force_and_a_reset_loses_it() {
    let mut b = ModelBuilder::new();
    b.body(BodySpec::new("box").mass(1.0).inertia([1e-3; 3]));
    b.finger(FingerSpec::point("index", "box", [0.0; 3]));
    let model = Arc::new(b.build().unwrap());
    let settings = SolverSettings {
        coupling_damping_n_s_per_m: 0.0,
        ..SolverSettings::default()
    };
    let mut programs: Vec<Program> = (0..3)
        .map(|_| Program::new(model.clone(), settings).unwrap())
        .collect();
    for k in 0..300 {
        for p in &mut programs {
            p.tick(&target(k, Vector3::zeros()), DT);
        }
    }
    let delta = Vector3::new(2e-4, -1e-4, 3e-4);
    let mut dq = vec![0.0; model.n_coords()];
    dq[..3].copy_from_slice(delta.as_slice());
    programs[1].shift_q(&dq).unwrap();
    let moved: Vec<f64> = programs[2]
        .q()
        .iter()
        .zip(&dq)
        .map(|(q, d)| q + d)
        .collect();
    programs[2].set_q(&moved).unwrap();
    let f = |p: &Program| p.finger_outputs()[0].force_n;
    let (mut shifted, mut reset, mut inertial) = (0.0f64, 0.0f64, 0.0f64);
    for k in 300..305 {
        programs[0].tick(&target(k, Vector3::zeros()), DT);
        programs[1].tick(&target(k, delta), DT);
        programs[2].tick(&target(k, delta), DT);
        inertial = inertial.max(f(&programs[0]).norm());
        shifted = shifted.max((f(&programs[1]) - f(&programs[0])).norm());
        reset = reset.max((f(&programs[2]) - f(&programs[0])).norm());
    }
    // F = m (g − a) with g = 0: |F| ≈ m r ω² = 1.58 N.
    assert!(
        (inertial - 1.579).abs() < 0.05,
        "reference force {inertial} N"
    );
    assert!(shifted < 1e-6, "shift_q disturbed the force by {shifted} N");
    assert!(
        reset > 0.5 * inertial,
        "set_q should lose a tick of inertia: {reset} N"
    );
    assert!(
        programs[1].shift_q(&dq[1..]).is_err(),
        "a wrong length is refused"
    );
}
