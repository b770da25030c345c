//! Coulomb friction between bodies (inertial motion on): a box pushed along
//! a table by a contact finger needs μ m g to slide, stops when the finger
//! stops, and a frictionless one glides on.

use haptloop_solver::geometry::ContactSettings;
use haptloop_solver::{
    BodySpec, FingerSpec, FingerTarget, ModelBuilder, SolverSettings, TickOutcome,
};
use nalgebra::Vector3;

use crate::common::{Lockstep, cuboid};

/// (box x per tick, rendered |F_x| per tick) for a box of `mass_kg` on a
/// table, both with Coulomb `mu`, pushed 4 cm at 4 cm/s.
fn push(mu: f64) -> (Vec<f64>, Vec<f64>) {
    let mut b = ModelBuilder::new();
    b.gravity([0.0, 0.0, -9.81]);
    b.body(
        BodySpec::fixed("table")
            .at([0.0, 0.0, -0.02])
            .shape(cuboid([0.3, 0.3, 0.02]))
            .friction(mu),
    );
    // 6 cm cube at 500 kg/m³: 108 g.
    b.body(
        BodySpec::new("box")
            .at([0.0, 0.0, 0.03])
            .shape(cuboid([0.03, 0.03, 0.03]))
            .density(500.0)
            .friction(mu),
    );
    b.finger(FingerSpec::contact(
        "index",
        [-0.045, 0.0, 0.03],
        0.008,
        0.0,
    ));
    let settings = SolverSettings {
        dynamics: true,
        ..SolverSettings::default()
    };
    let mut l = Lockstep::new(b.build().unwrap(), settings, ContactSettings::default());
    let (mut x, mut f) = (Vec::new(), Vec::new());
    for k in 0..2500 {
        let t = (k + 1) as f64 * 1e-3;
        let target = Vector3::new(-0.045 + (0.04 * t).min(0.04), 0.0, 0.03);
        let r = l.tick(&[FingerTarget::at(target)]);
        assert_eq!(r.status, TickOutcome::Ok, "tick {k}");
        x.push(l.position("box").x);
        f.push(l.program.finger_outputs()[0].force_n.x.abs());
    }
    assert_eq!(l.backups, 0);
    (x, f)
}

#[test]
fn sliding_a_box_takes_mu_m_g_and_it_stops_with_the_finger() {
    let mu = 0.5;
    let (x, f) = push(mu);
    let weight = 0.108 * 9.81;
    // While it slides (0.4–0.95 s), the push averages μ m g.
    let mean = f[400..950].iter().sum::<f64>() / 550.0;
    assert!(
        (mean - mu * weight).abs() < 0.1 * mu * weight,
        "push {mean} N while sliding, μ m g = {} N",
        mu * weight
    );
    assert!(x[950] > 0.02, "the box slid only {} m", x[950]);
    // The finger stops at 1 s: the box stops within 0.1 s and stays.
    let settled = x[1100];
    assert!(
        (x[2499] - settled).abs() < 1e-6,
        "it crept {} m",
        x[2499] - settled
    );
}

#[test]
fn a_frictionless_box_glides_on_after_the_push() {
    let (x, f) = push(0.0);
    let (x_mu, _) = push(0.5);
    // Nothing to push against but inertia: a light touch.
    let mean = f[400..950].iter().sum::<f64>() / 550.0;
    assert!(mean < 0.05, "{mean} N");
    // After the finger stops the box keeps sliding, far past the rough one.
    assert!(x[2499] - x[1100] > 0.01, "glided {} m", x[2499] - x[1100]);
    assert!(x[2499] > x_mu[2499] + 0.01);
}
