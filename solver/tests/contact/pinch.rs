//! Two contact fingers (proxies on their virtual couplings, inertial motion
//! on) pinch a 100 g box off a table: Coulomb friction at the fingertips
//! decides whether it lifts, holds and falls when they open.
//!
//! The script (thumb; the index mirrors it in x): squeeze 12 mm toward the
//! box over 0.5 s (the fingertips stop at its faces after 4 mm, so the
//! coupling presses with 400 N/m × 8 mm = 3.2 N), hold, lift 5 cm over 1 s,
//! hold 2.5 s, open.

use haptloop_solver::geometry::ContactSettings;
use haptloop_solver::{
    BodySpec, FingerSpec, FingerTarget, Model, ModelBuilder, SolverSettings, TickOutcome,
};
use nalgebra::Vector3;

use crate::common::{Lockstep, cuboid};

const BOX_Z: f64 = 0.025;
const WEIGHT_N: f64 = 0.1 * 9.81;

pub fn pinch_model(mu: f64) -> Model {
    let mut b = ModelBuilder::new();
    b.gravity([0.0, 0.0, -9.81]);
    b.body(
        BodySpec::fixed("table")
            .at([0.0, 0.0, -0.02])
            .shape(cuboid([0.15, 0.15, 0.02])),
    );
    b.body(
        BodySpec::new("box")
            .at([0.0, 0.0, BOX_Z])
            .shape(cuboid([0.025, 0.025, 0.025]))
            .density(800.0),
    );
    b.finger(FingerSpec::contact(
        "thumb",
        [-0.037, 0.0, BOX_Z],
        0.008,
        mu,
    ));
    b.finger(FingerSpec::contact("index", [0.037, 0.0, BOX_Z], 0.008, mu));
    b.build().unwrap()
}

/// The thumb's target offset at time t.
fn script(t: f64) -> Vector3<f64> {
    let pts = [
        (0.0, [0.0, 0.0, 0.0]),
        (0.5, [0.012, 0.0, 0.0]),
        (1.0, [0.012, 0.0, 0.0]),
        (2.0, [0.012, 0.0, 0.05]),
        (4.5, [0.012, 0.0, 0.05]),
        (5.0, [-0.01, 0.0, 0.05]),
    ];
    let k = pts.partition_point(|p| p.0 <= t);
    let at = |i: usize| Vector3::from(pts[i].1);
    if k == 0 {
        return at(0);
    }
    if k >= pts.len() {
        return at(pts.len() - 1);
    }
    let s = (t - pts[k - 1].0) / (pts[k].0 - pts[k - 1].0);
    at(k - 1) + (at(k) - at(k - 1)) * s
}

/// What a pinch run did.
struct Run {
    /// Box height per tick.
    z: Vec<f64>,
    /// Largest contact pull of any tick's force solve, N.
    max_pull_n: f64,
    /// Largest pushing force on the thumb, N (for the pull's scale).
    max_push_n: f64,
    /// Thumb's rendered force (z) per tick, N.
    thumb_fz: Vec<f64>,
}

fn pinch(mu: f64, seconds: f64) -> Run {
    let settings = SolverSettings {
        dynamics: true,
        ..SolverSettings::default()
    };
    let mut l = Lockstep::new(pinch_model(mu), settings, ContactSettings::default());
    let start = [
        Vector3::new(-0.037, 0.0, BOX_Z),
        Vector3::new(0.037, 0.0, BOX_Z),
    ];
    let mut run = Run {
        z: Vec::new(),
        max_pull_n: 0.0,
        max_push_n: 0.0,
        thumb_fz: Vec::new(),
    };
    let ticks = (seconds * 1e3) as usize;
    for k in 0..ticks {
        let o = script((k + 1) as f64 * 1e-3);
        let targets = [
            FingerTarget::at(start[0] + o),
            FingerTarget::at(start[1] + Vector3::new(-o.x, o.y, o.z)),
        ];
        let r = l.tick(&targets);
        assert_eq!(r.status, TickOutcome::Ok, "tick {k}");
        let f = l.program.finger_outputs()[0].force_n;
        run.z.push(l.position("box").z);
        run.thumb_fz.push(f.z);
        run.max_pull_n = run.max_pull_n.max(l.program.contact_pull_n());
        run.max_push_n = run.max_push_n.max(f.norm());
    }
    // Fingertips sliding over the box's edges press into it by at most a
    // few tens of µm between two witness updates (5 ms), far below the
    // backup tolerance.
    assert_eq!(l.backups, 0, "no penetration needed a backup");
    assert!(
        l.max_penetration_m < 5e-5,
        "penetrated {} m",
        l.max_penetration_m
    );
    run
}

/// μ = 0.8: the 3.2 N squeeze carries 2.56 N per finger, far above half
/// the weight: the box lifts 5 cm with the fingertips, holds still for 2 s
/// (from 0.25 s after the lift ends, once the proxies have settled) with
/// each finger carrying half its weight, and falls back onto the table when
/// they open.
#[test]
fn a_pinch_with_friction_lifts_holds_and_drops_the_box() {
    let run = pinch(0.8, 6.0);
    let z = |t: f64| run.z[(t * 1e3) as usize - 1];
    assert!(z(2.0) - BOX_Z > 0.045, "lifted only {} m", z(2.0) - BOX_Z);
    let held = &run.z[2250..4250];
    let (lo, hi) = held
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    assert!(hi - lo < 1e-3, "the held box moved {} m", hi - lo);
    // Each finger carries half the weight (the coupling's pull down).
    let mean_fz = run.thumb_fz[2250..4250].iter().sum::<f64>() / 2000.0;
    assert!(
        (mean_fz + WEIGHT_N / 2.0).abs() < 0.05 * WEIGHT_N,
        "thumb carries {mean_fz} N, half the weight is {} N",
        WEIGHT_N / 2.0
    );
    // Released: back on the table.
    assert!(
        (z(6.0) - BOX_Z).abs() < 1e-4,
        "box at {} after the drop",
        z(6.0)
    );
    assert!(
        run.max_pull_n <= 1e-9 * run.max_push_n,
        "a contact pulled {} N",
        run.max_pull_n
    );
}

/// μ = 0: nothing carries the weight: the fingertips slide up the faces
/// and the box stays on the table.
#[test]
fn without_friction_the_pinch_cannot_lift() {
    let run = pinch(0.0, 2.5);
    let top = run.z.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    assert!(top - BOX_Z < 1e-6, "the box rose {} m", top - BOX_Z);
    assert!(
        run.max_pull_n <= 1e-9 * run.max_push_n,
        "a contact pulled {} N",
        run.max_pull_n
    );
}

/// μ = 0.1: the cone holds 0.1 × 3.2 N = 0.32 N per finger, less than half
/// the weight (0.49 N): the box slips out of the grip.
#[test]
fn the_coulomb_cone_bounds_what_a_pinch_carries() {
    let run = pinch(0.1, 2.5);
    assert!(run.z[2499] - BOX_Z < 1e-3, "box at {} m", run.z[2499]);
    let run = pinch(0.3, 2.5);
    assert!(
        run.z[2499] - BOX_Z > 0.045,
        "μ = 0.3 (0.96 N per finger) lifts: box at {}",
        run.z[2499]
    );
}
