//! Restitution and fast bodies: a ball with e = 0.5 rebounds to e² h; a
//! 10 m/s ball stays on its side of a 4 mm plate.

use haptloop_solver::geometry::Shape;
use haptloop_solver::{BodySpec, ModelBuilder, TickOutcome};

use crate::common::{G, RATES, cuboid, lockstep, rel, ticks};

/// A 1 cm ball at `height` above a fixed 4 mm plate (its top at z = 0),
/// with restitution `e` and initial vertical velocity `vz`: its centre's
/// height above the plate's top minus its radius (the gap), per tick.
fn drop(rate: u32, height: f64, e: f64, vz: f64, seconds: f64) -> (Vec<f64>, u64) {
    let r = 0.01;
    let mut b = ModelBuilder::new();
    b.gravity([0.0, 0.0, -G]);
    b.body(
        BodySpec::fixed("plate")
            .at([0.0, 0.0, -0.002])
            .shape(cuboid([0.1, 0.1, 0.002])),
    );
    b.body(
        BodySpec::new("ball")
            .at([0.0, 0.0, r + height])
            .shape(Shape::Sphere { radius_m: r })
            .restitution(e)
            .moving([0.0, 0.0, vz], [0.0; 3]),
    );
    let mut l = lockstep(b.build().unwrap(), rate);
    let gaps = (0..ticks(seconds, rate))
        .map(|k| {
            assert_eq!(l.tick(&[]).status, TickOutcome::Ok, "{rate} Hz tick {k}");
            l.position("ball").z - r
        })
        .collect();
    (gaps, l.backups)
}

#[test]
fn a_ball_with_restitution_rebounds_to_e_squared_h() {
    let (h, e) = (0.2, 0.5);
    for rate in RATES {
        let (z, _) = drop(rate, h, e, 0.0, 0.6);
        // The first contact, then the highest point after it.
        let hit = z.iter().position(|&g| g < 1e-4).expect("it lands");
        let apex = z[hit..].iter().copied().fold(f64::MIN, f64::max);
        println!(
            "bounce {rate} Hz: rebounds to {apex:.5} m (e² h = {:.5} m)",
            e * e * h
        );
        assert!(rel(apex, e * e * h) < 0.05, "{rate} Hz: rebound {apex} m");
    }
}

#[test]
fn a_ball_without_restitution_stays_down() {
    for rate in RATES {
        let (z, _) = drop(rate, 0.2, 0.0, 0.0, 0.6);
        let hit = z.iter().position(|&g| g < 1e-4).expect("it lands");
        let apex = z[hit..].iter().copied().fold(f64::MIN, f64::max);
        assert!(apex < 1e-4, "{rate} Hz: bounced to {apex} m");
    }
}

#[test]
fn a_ball_at_10_m_s_does_not_cross_a_4_mm_plate() {
    for rate in RATES {
        let (z, backups) = drop(rate, 0.3, 0.0, -10.0, 0.2);
        let lowest = z.iter().copied().fold(f64::MAX, f64::min);
        println!("10 m/s {rate} Hz: lowest gap {lowest:.3e} m, {backups} backups");
        assert!(
            lowest > -1e-4,
            "{rate} Hz: went {lowest} m into or through the plate"
        );
        assert!(
            z[z.len() - 1].abs() < 1e-4,
            "{rate} Hz: ended at {} m",
            z[z.len() - 1]
        );
    }
}
