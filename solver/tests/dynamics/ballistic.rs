//! Bodies nothing touches: free fall, a projectile, torque-free spin; and a
//! block gliding on a frictionless table.

use std::sync::Arc;

use haptloop_solver::geometry::Shape;
use haptloop_solver::{BodySpec, ModelBuilder, Program, TickOutcome};
use nalgebra::{Matrix3, UnitQuaternion, Vector3};

use crate::common::{G, RATES, cuboid, dynamics, lockstep, period, rel, ticks};

/// A 1 cm ball alone in gravity, starting at the origin with velocity `v0`.
fn ball(v0: [f64; 3]) -> Program {
    let mut b = ModelBuilder::new();
    b.gravity([0.0, 0.0, -G]);
    b.body(
        BodySpec::new("ball")
            .shape(Shape::Sphere { radius_m: 0.01 })
            .moving(v0, [0.0; 3]),
    );
    Program::new(Arc::new(b.build().unwrap()), dynamics()).unwrap()
}

#[test]
fn free_fall_follows_half_g_t_squared() {
    for rate in RATES {
        let mut p = ball([0.0; 3]);
        let dt = period(rate);
        let mut worst: f64 = 0.0;
        for k in 1..=ticks(1.0, rate) {
            assert_eq!(p.tick(&[], dt).status, TickOutcome::Ok);
            let t = k as f64 * dt.as_secs_f64();
            let fallen = -p.q()[2];
            if t >= 0.1 {
                worst = worst.max(rel(fallen, 0.5 * G * t * t));
            }
        }
        let fallen = -p.q()[2];
        println!(
            "free fall {rate} Hz: {fallen:.9} m in 1 s (½ g t² = {:.9}), worst {worst:.2e} from 0.1 s",
            0.5 * G
        );
        assert!(worst < 5e-3, "{rate} Hz: off by {worst:.2e} of ½ g t²");
        assert!(rel(fallen, 0.5 * G) < 5e-3);
    }
}

#[test]
fn a_projectile_lands_at_its_range() {
    let (vx, vz) = (3.0, 4.0);
    let range = 2.0 * vx * vz / G;
    for rate in RATES {
        let mut p = ball([vx, 0.0, vz]);
        let dt = period(rate);
        let (mut prev, mut landed) = ([0.0; 3], None);
        for _ in 0..ticks(2.0, rate) {
            assert_eq!(p.tick(&[], dt).status, TickOutcome::Ok);
            let now = [p.q()[0], p.q()[1], p.q()[2]];
            if prev[2] > 0.0 && now[2] <= 0.0 {
                // Linear interpolation to z = 0 within the tick.
                let s = prev[2] / (prev[2] - now[2]);
                landed = Some(prev[0] + s * (now[0] - prev[0]));
                break;
            }
            prev = now;
        }
        let x = landed.expect("it lands");
        println!("projectile {rate} Hz: range {x:.6} m (2 vx vz / g = {range:.6} m)");
        assert!(
            rel(x, range) < 1e-2,
            "{rate} Hz: range {x} m, analytic {range} m"
        );
    }
}

/// |L| of a body spinning at `w0` (world) with principal moments `j` and
/// orientation `e0`, over `seconds`: (largest relative change, final
/// angle between L and L₀).
fn spin(
    rate: u32,
    j: [f64; 3],
    e0: UnitQuaternion<f64>,
    w0: Vector3<f64>,
    seconds: f64,
) -> (f64, f64) {
    let mut b = ModelBuilder::new();
    let q = e0.quaternion();
    b.body(
        BodySpec::new("top")
            .mass(1.0)
            .inertia(j)
            .oriented([q.w, q.i, q.j, q.k])
            .moving([0.0; 3], w0.into()),
    );
    let model = Arc::new(b.build().unwrap());
    let mut p = Program::new(model.clone(), dynamics()).unwrap();
    let id = model.body_id("top").unwrap();
    let dt = period(rate);
    let jw = |p: &Program| {
        let r = model.body_rotation(p.q(), id).unwrap();
        r * Matrix3::from_diagonal(&Vector3::from(j)) * r.transpose()
    };
    let l0 = jw(&p) * w0;
    let mut worst: f64 = 0.0;
    let mut before = p.q().to_vec();
    let mut l = l0;
    for _ in 0..ticks(seconds, rate) {
        assert_eq!(p.tick(&[], dt).status, TickOutcome::Ok);
        // L at the step's midpoint orientation, ω of the step (independent
        // of the program's own momentum: from q alone).
        let (_, w) = p.body_velocity(id).unwrap();
        let after = p.q().to_vec();
        let mid: Vec<f64> = before
            .iter()
            .zip(&after)
            .map(|(a, b)| 0.5 * (a + b))
            .collect();
        let r = model.body_rotation(&mid, id).unwrap();
        l = r * Matrix3::from_diagonal(&Vector3::from(j)) * r.transpose() * w;
        worst = worst.max(rel(l.norm(), l0.norm()));
        before = after;
    }
    (worst, l.angle(&l0))
}

#[test]
fn a_torque_free_body_keeps_its_angular_momentum() {
    let j = [1e-3, 2e-3, 3e-3];
    let e0 = UnitQuaternion::from_euler_angles(0.3, -0.5, 0.7);
    for rate in RATES {
        // About the major principal axis, 10 rad/s, 10 s.
        let (dl, turn) = spin(rate, j, e0, e0 * Vector3::z() * 10.0, 10.0);
        println!("spin {rate} Hz: |L| within {dl:.2e}, direction {turn:.2e} rad");
        assert!(dl < 1e-3, "{rate} Hz: |L| changed by {dl:.2e}");
        assert!(turn < 1e-3, "{rate} Hz: L turned {turn:.2e} rad");
    }
}

#[test]
fn a_frictionless_block_glides_at_constant_speed() {
    for rate in RATES {
        let mut b = ModelBuilder::new();
        b.gravity([0.0, 0.0, -G]);
        b.body(
            BodySpec::fixed("table")
                .at([0.0, 0.0, -0.02])
                .shape(cuboid([1.0, 1.0, 0.02])),
        );
        b.body(
            BodySpec::new("block")
                .at([-0.5, 0.0, 0.03])
                .shape(cuboid([0.03, 0.03, 0.03]))
                .density(500.0)
                .moving([0.2, 0.0, 0.0], [0.0; 3]),
        );
        let mut l = lockstep(b.build().unwrap(), rate);
        let mut xs = Vec::new();
        for k in 0..ticks(2.0, rate) {
            assert_eq!(l.tick(&[]).status, TickOutcome::Ok, "{rate} Hz tick {k}");
            xs.push(l.position("block"));
        }
        // Speed over each 0.1 s window against the initial 0.2 m/s.
        let w = ticks(0.1, rate);
        let mut worst: f64 = 0.0;
        for k in (w..xs.len()).step_by(w) {
            let v = (xs[k].x - xs[k - w].x) / 0.1;
            worst = worst.max(rel(v, 0.2));
        }
        let sink = xs.iter().map(|p| (p.z - 0.03).abs()).fold(0.0, f64::max);
        println!(
            "glide {rate} Hz: speed within {worst:.2e}, height within {sink:.2e} m, {} backups",
            l.backups
        );
        assert!(worst < 5e-3, "{rate} Hz: speed off by {worst:.2e}");
        assert!(sink < 1e-4, "{rate} Hz: height changed {sink} m");
    }
}
