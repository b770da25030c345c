//! Friction over a patch resists twisting: a block on a table pushed off
//! its centre line does not pivot while the push is below what can make it
//! move, then slides and turns with a mean push inside the patch's limit.
//!
//! Reference: a rigid square block (half side a) on a uniformly pressed
//! patch, pushed with F at a lever d from its centre, stays put while (F,
//! F d) lies inside the patch's limit surface. That surface is convex and
//! passes through F = μ N (pure sliding) and τ = μ N r̄ (pure twist; r̄ =
//! 0.765 a, the mean distance of the square from its centre), so it holds
//! the diamond F/(μ N) + F d/(μ N r̄) ≤ 1 and lies within F ≤ μ N: below
//! μ N / (1 + d/r̄) nothing may move, and no steady slide takes more than
//! μ N.

use haptloop_solver::{BodySpec, FingerSpec, FingerTarget, ModelBuilder, TickOutcome};
use nalgebra::{Rotation3, Vector3};

use crate::common::{G, RATES, cuboid, lockstep, ticks};

/// A 100 g block (half side `A`) on a table, μ = 0.5, pushed along +x by
/// a frictionless fingertip at `d` off its centre line, its target moving
/// at 1 cm/s: (block x, block yaw, |push|) per tick.
fn push(rate: u32, d: f64, seconds: f64) -> Vec<(f64, f64, f64)> {
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
            .at([0.0, 0.0, A])
            .shape(cuboid([A, A, A]))
            .mass(0.1)
            .friction(mu),
    );
    let x0 = -A - 0.008 - 0.002;
    b.finger(FingerSpec::contact("index", [x0, d, A], 0.008, 0.0));
    let mut l = lockstep(b.build().unwrap(), rate);
    let id = l.program.model().body_id("block").unwrap();
    let dt = 1.0 / f64::from(rate);
    (0..ticks(seconds, rate))
        .map(|k| {
            let t = (k + 1) as f64 * dt;
            let target = Vector3::new(x0 + 0.01 * t, d, A);
            let r = l.tick(&[FingerTarget::at(target)]);
            assert_eq!(r.status, TickOutcome::Ok, "{rate} Hz tick {k}");
            let m = l.program.model();
            let rot = m.body_rotation(l.program.q(), id).unwrap();
            let yaw = Rotation3::from_matrix_unchecked(rot).euler_angles().2;
            let push = l.program.finger_outputs()[0].force_n.x.abs();
            (l.position("block").x, yaw, push)
        })
        .collect()
}

/// Half side of the block, m.
const A: f64 = 0.03;

#[test]
fn a_block_pushed_off_centre_does_not_pivot_below_its_limit_and_then_slides() {
    let (mu_n, d) = (0.5 * 0.1 * G, 0.02);
    let r = 0.765 * A;
    let safe = mu_n / (1.0 + d / r);
    for rate in RATES {
        let s = push(rate, d, 2.0);
        // Until the push first reaches 95 % of the safe bound: no turn, no move.
        let k = s
            .iter()
            .position(|v| v.2 > 0.95 * safe)
            .expect("the push rises");
        let turned = s[..k].iter().map(|v| v.1.abs()).fold(0.0, f64::max);
        let moved = s[..k].iter().map(|v| v.0.abs()).fold(0.0, f64::max);
        let most = s.iter().map(|v| v.2).fold(0.0, f64::max);
        // Sliding and turning: the mean push over the last second lies
        // between the diamond's bound and μ m g (on the limit surface).
        let tail = ticks(1.0, rate);
        let sliding = s[s.len() - tail..].iter().map(|v| v.2).sum::<f64>() / tail as f64;
        let (x, yaw) = (s[s.len() - 1].0, s[s.len() - 1].1);
        println!(
            "off-centre push {rate} Hz: below {:.4} N turned {turned:.2e} rad, moved {moved:.2e} m; \
             sliding push {sliding:.4} N, peak {most:.4} N (μ m g {mu_n:.4}); ends at x {x:.4} m, yaw {yaw:.3} rad",
            0.95 * safe
        );
        assert!(
            turned < 1e-3,
            "{rate} Hz: pivoted {turned} rad under a push below its limit"
        );
        assert!(
            moved < 0.05e-3,
            "{rate} Hz: moved {moved} m under a push below its limit"
        );
        assert!(
            sliding < 1.02 * mu_n && sliding > 0.95 * safe,
            "{rate} Hz: sliding push {sliding} N"
        );
        // Pushed at +y along +x, it turns clockwise (about −z) as it slides.
        assert!(
            x > 2e-3 && yaw < -0.1,
            "{rate} Hz: ends at x {x} m, yaw {yaw} rad"
        );
    }
}
