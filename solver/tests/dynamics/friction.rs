//! Coulomb friction: a block on an incline sticks when tan θ < μ and
//! accelerates at g (sin θ − μ cos θ) when tan θ > μ; a block pushed by a
//! contact finger does not move until the push reaches μ m g, then slides
//! with the push at μ m g.

use haptloop_solver::{BodySpec, FingerSpec, FingerTarget, ModelBuilder, TickOutcome};
use nalgebra::{UnitQuaternion, Vector3};

use crate::common::{G, RATES, cuboid, lockstep, rel, ticks};

/// Ramp angle, rad.
const THETA: f64 = 20.0 * std::f64::consts::PI / 180.0;

/// Distances the block moved along the incline (downhill +), one per tick
/// over `seconds`, with Coulomb `mu` on both.
fn incline(rate: u32, mu: f64, seconds: f64) -> Vec<f64> {
    let tilt = UnitQuaternion::from_axis_angle(&Vector3::y_axis(), THETA);
    let q = tilt.quaternion();
    let n = tilt * Vector3::z();
    let down = tilt * Vector3::x();
    let mut b = ModelBuilder::new();
    b.gravity([0.0, 0.0, -G]);
    b.body(
        BodySpec::fixed("ramp")
            .oriented([q.w, q.i, q.j, q.k])
            .shape(cuboid([0.6, 0.2, 0.02]))
            .friction(mu),
    );
    let start = n * 0.05 - down * 0.4;
    b.body(
        BodySpec::new("block")
            .at(start.into())
            .oriented([q.w, q.i, q.j, q.k])
            .shape(cuboid([0.03, 0.03, 0.03]))
            .density(500.0)
            .friction(mu),
    );
    let mut l = lockstep(b.build().unwrap(), rate);
    (0..ticks(seconds, rate))
        .map(|k| {
            assert_eq!(l.tick(&[]).status, TickOutcome::Ok, "{rate} Hz tick {k}");
            (l.position("block") - start).dot(&down)
        })
        .collect()
}

#[test]
fn a_block_sticks_on_an_incline_flatter_than_its_friction_angle() {
    // tan 20° = 0.364 < μ = 0.5.
    for rate in RATES {
        let s = incline(rate, 0.5, 10.0);
        let moved = s.iter().map(|x| x.abs()).fold(0.0, f64::max);
        println!("incline stick {rate} Hz: moved at most {moved:.3e} m in 10 s");
        assert!(moved < 1e-4, "{rate} Hz: crept {moved} m");
    }
}

#[test]
fn a_block_slides_down_a_steeper_incline_at_g_sin_minus_mu_cos() {
    let mu = 0.1;
    let a = G * (THETA.sin() - mu * THETA.cos());
    for rate in RATES {
        let s = incline(rate, mu, 0.5);
        let t = s.len() as f64 / f64::from(rate);
        let measured = 2.0 * s[s.len() - 1] / (t * t);
        println!("incline slip {rate} Hz: {measured:.5} m/s² (g (sin θ − μ cos θ) = {a:.5})");
        assert!(
            rel(measured, a) < 0.02,
            "{rate} Hz: {measured} m/s², analytic {a}"
        );
    }
}

/// A 100 g block on a table, both μ = 0.5, pushed by a frictionless contact
/// finger whose target moves at 1 cm/s: (block x, |push| felt, in-tick
/// activations) per tick.
fn push(rate: u32, seconds: f64) -> (Vec<f64>, Vec<f64>, Vec<u32>) {
    let mu = 0.5;
    let mut b = ModelBuilder::new();
    b.gravity([0.0, 0.0, -G]);
    b.body(
        BodySpec::fixed("table")
            .at([0.0, 0.0, -0.02])
            .shape(cuboid([0.3, 0.3, 0.02]))
            .friction(mu),
    );
    b.body(
        BodySpec::new("block")
            .at([0.0, 0.0, 0.03])
            .shape(cuboid([0.03, 0.03, 0.03]))
            .mass(0.1)
            .friction(mu),
    );
    let x0 = -0.03 - 0.008 - 0.002;
    b.finger(FingerSpec::contact("index", [x0, 0.0, 0.03], 0.008, 0.0));
    let mut l = lockstep(b.build().unwrap(), rate);
    let dt = 1.0 / f64::from(rate);
    let (mut x, mut f, mut act) = (Vec::new(), Vec::new(), Vec::new());
    for k in 0..ticks(seconds, rate) {
        let t = (k + 1) as f64 * dt;
        let target = Vector3::new(x0 + 0.01 * t, 0.0, 0.03);
        let r = l.tick(&[FingerTarget::at(target)]);
        assert_eq!(r.status, TickOutcome::Ok, "{rate} Hz tick {k}");
        x.push(l.position("block").x);
        f.push(l.program.finger_outputs()[0].force_n.x.abs());
        act.push(r.activations);
    }
    (x, f, act)
}

#[test]
fn a_pushed_block_starts_to_slide_at_mu_m_g_and_slides_at_it() {
    let limit = 0.5 * 0.1 * G;
    for rate in RATES {
        let (x, f, act) = push(rate, 2.0);
        // Onset: the first tick the block has moved 10 nm; the push then.
        let onset = x.iter().position(|&v| v > 1e-8).expect("it slides");
        let before = f[onset];
        // Until the push reached 95 % of μ m g, no motion (< 0.05 mm).
        let rising = f.iter().position(|&v| v > 0.95 * limit).expect("it pushes");
        let still = x[..rising].iter().fold(0.0_f64, |a, v| a.max(v.abs()));
        // Sliding: the mean push over the last second.
        let tail = ticks(1.0, rate);
        let sliding = f[f.len() - tail..].iter().sum::<f64>() / tail as f64;
        let speed = (x[x.len() - 1] - x[x.len() - tail]) / (tail - 1) as f64 * f64::from(rate);
        println!(
            "push {rate} Hz: slides at {before:.4} N (μ m g = {limit:.4} N) after {} ms, \
             at rest within {still:.2e} m until 95 %; sliding push {sliding:.4} N at {speed:.5} m/s",
            onset * 1000 / rate as usize
        );
        assert!(rel(before, limit) < 0.05, "{rate} Hz: onset at {before} N");
        assert!(still < 0.05e-3);
        assert!(
            rel(sliding, limit) < 0.03,
            "{rate} Hz: sliding push {sliding} N"
        );
        assert!(rel(speed, 0.01) < 0.05, "{rate} Hz: slides at {speed} m/s");
        // The slide keeps the table's rows active: none is pressed in again
        // within a tick (each would be a refactorisation). The rows were let
        // go and re-activated on every tick of the slide before (the slow
        // slip's attempt to stick tipped the block onto its front edge).
        let sliding_act: u32 = act[act.len() - tail..].iter().sum();
        let all: u32 = act.iter().sum();
        println!("push {rate} Hz: {all} in-tick activations, {sliding_act} while sliding");
        assert!(
            sliding_act * 100 < tail as u32,
            "{rate} Hz: {sliding_act} activations in the last second's slide"
        );
    }
}
