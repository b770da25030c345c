//! The simulated arm: the hand and the motors both move the tip; determinism;
//! the thermal cut; gimbal sensing; configuration errors.

use std::time::Duration;

use haptloop_devices::{
    CutReason, Device, Grip, Hand, PREMIUM_1_5, SafetyConfig, SimOptions, SimPhantom, Trajectory,
};
use nalgebra::{UnitQuaternion, Vector3};

use crate::common::{no_ramp, safe_sim, tick, wall};

#[test]
fn motor_force_displaces_the_tip_against_the_grip_spring() {
    // Static balance: F = k_h·x, so x = 0.5 N / 300 N/m = 1.667 mm. After 2 s the
    // transient (ζ ≈ 0.11, ω ≈ 63 rad/s) has decayed to ~1e-6 of 1.7 mm; the
    // remaining error comes from mapping with Jᵀ at the quantised angles
    // (~1e-4 relative), so 1e-6 m is a tolerance a wrong sign or Jacobian fails.
    let mut sim =
        SimPhantom::by_name("phantom-premium-1.5", SimOptions::default(), Hand::still()).unwrap();
    let f = Vector3::new(0.5, -0.3, 0.2);
    for k in 0..=2000 {
        sim.read(tick(k)).unwrap();
        sim.write(f, tick(k)).unwrap();
    }
    let expected = f / Grip::default().stiffness_n_per_m;
    let err = (sim.true_tip_m_device() - expected).norm();
    assert!(
        err < 1e-6,
        "tip {} expected {expected}, error {err}",
        sim.true_tip_m_device()
    );
}

#[test]
fn hand_line_drags_the_tip_and_reading_is_within_quantisation() {
    let to = Vector3::new(0.02, -0.01, 0.015);
    let hand = Hand::new(Trajectory::Line {
        to_m: to,
        duration: Duration::from_secs(1),
    });
    let mut sim = SimPhantom::by_name("phantom-omni", SimOptions::default(), hand).unwrap();
    let mut r = sim.read(tick(0)).unwrap();
    for k in 1..=3000 {
        r = sim.read(tick(k)).unwrap();
    }
    // 2 s after the target stopped, the tip has settled on it (decay e^-13).
    assert!((sim.true_tip_m_device() - to).norm() < 1e-6);
    // The sensed tip is within one count's worth of the true tip (0.055 mm·√3).
    let q = PREMIUM_1_5
        .nominal_resolution_m()
        .max(haptloop_devices::OMNI.nominal_resolution_m());
    assert!(
        (r.tip_m_device - to).norm() < q * 3f64.sqrt(),
        "{} vs {to}",
        r.tip_m_device
    );
}

fn closed_loop_run() -> Vec<(Vector3<f64>, Vector3<f64>)> {
    let hand = Hand::new(Trajectory::Circle {
        radius_m: 0.01,
        frequency_hz: 2.0,
        u: Vector3::x(),
        v: -Vector3::y(),
    });
    let mut dev = safe_sim("phantom-premium-1.5", hand, SafetyConfig::default());
    (0..800)
        .map(|k| {
            let r = dev.read(tick(k));
            let out = dev.write(wall(800.0, &r.tip_m_device), tick(k));
            (dev.device().true_tip_m_device(), out.motor.force_n_device)
        })
        .collect()
}

#[test]
fn same_inputs_give_bit_identical_outputs() {
    let (a, b) = (closed_loop_run(), closed_loop_run());
    assert!(
        a.iter().any(|(_, f)| f.norm() > 1.0),
        "the wall must have been touched"
    );
    for (k, (x, y)) in a.iter().zip(&b).enumerate() {
        let bits = |v: &Vector3<f64>| v.map(f64::to_bits);
        assert_eq!(
            (bits(&x.0), bits(&x.1)),
            (bits(&y.0), bits(&y.1)),
            "tick {k}"
        );
    }
}

#[test]
fn thermal_model_cuts_sustained_force_to_the_continuous_rating() {
    // 8.5 N from cold trips after −τ·ln(1 − (1.4/8.5)²) = 0.553 s (τ = 20 s).
    let hand = Hand::still().with_grip(Grip {
        stiffness_n_per_m: 2000.0,
        damping_n_s_per_m: 5.0,
    });
    let mut dev = safe_sim("phantom-premium-1.5", hand, no_ramp());
    let mut tripped_at = None;
    for k in 0..=1500u64 {
        dev.read(tick(k));
        let out = dev.write(Vector3::new(0.0, 8.5, 0.0), tick(k));
        if out.motor.thermal_limited && tripped_at.is_none() {
            tripped_at = Some(k);
        }
        if let Some(t0) = tripped_at
            && k > t0
        {
            // Cut to 1.4 N; J at true vs sensed angles differ by < 1e-4 relative.
            assert!(
                (out.motor.force_n_device.norm() - 1.4).abs() < 1e-3,
                "tick {k}: {}",
                out.motor.force_n_device
            );
        }
    }
    let expected_ms = (-20.0 * (1.0 - (1.4f64 / 8.5).powi(2)).ln() * 1000.0).ceil() as u64;
    let t0 = tripped_at.expect("8.5 N sustained must trip the thermal cut");
    assert!(
        t0.abs_diff(expected_ms) <= 2,
        "tripped at {t0} ms, expected {expected_ms} ms"
    );
    assert_eq!(dev.last_cut().unwrap().reason, CutReason::Thermal);
    assert_eq!(dev.counters().cut_ticks(CutReason::Thermal), 1500 - t0 + 1);
}

#[test]
fn continuous_rating_is_sustainable() {
    let mut dev = safe_sim(
        "phantom-omni",
        Hand::still().with_grip(Grip {
            stiffness_n_per_m: 2000.0,
            damping_n_s_per_m: 5.0,
        }),
        no_ramp(),
    );
    for k in 0..=30_000u64 {
        dev.read(tick(k));
        let out = dev.write(Vector3::new(0.0, 0.87, 0.0), tick(k));
        assert!(
            !out.motor.thermal_limited,
            "0.87 N < 0.88 N continuous must never be cut (tick {k})"
        );
    }
    assert!(
        dev.device().thermal_load() > 0.7,
        "after 30 s = 3τ the motors are warm: {}",
        dev.device().thermal_load()
    );
}

#[test]
fn gimbal_orientation_is_sensed_within_half_a_gimbal_count_per_angle() {
    let mut hand = Hand::still();
    hand.orientation_device = UnitQuaternion::from_euler_angles(0.3, -0.2, 1.1);
    let mut sim =
        SimPhantom::by_name("phantom-touch", SimOptions::default(), hand.clone()).unwrap();
    let r = sim.read(tick(1)).unwrap();
    // Three angles each within half a count: the rotation error is at most
    // 3 × π/4096 (triangle inequality on the composed rotations).
    let err = r.orientation_device.angle_to(&hand.orientation_device);
    assert!(err <= 3.0 * std::f64::consts::PI / 4096.0, "{err}");
}

#[test]
fn fewer_than_four_substeps_or_unknown_model_are_clear_errors() {
    let opts = SimOptions {
        substeps_per_period: 3,
        ..SimOptions::default()
    };
    let err = SimPhantom::by_name("phantom-omni", opts, Hand::still())
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("substeps_per_period") && err.contains("4x"),
        "{err}"
    );
    let err = SimPhantom::by_name("falcon", SimOptions::default(), Hand::still())
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("`falcon`")
            && err.contains("phantom-premium-1.5, phantom-omni, phantom-touch"),
        "{err}"
    );
}

#[test]
fn recorded_hand_trace_drives_the_tip() {
    let csv = "t,dx,dy,dz\n0,0,0,0\n0.5,0.01,0,0\n1.0,0.01,0.01,-0.005\n";
    let trace = haptloop_devices::HandTrace::parse(csv, "hand.csv").unwrap();
    let hand = Hand::new(Trajectory::Trace(trace));
    let mut sim = SimPhantom::by_name("phantom-omni", SimOptions::default(), hand).unwrap();
    for k in 0..=3000 {
        sim.read(tick(k)).unwrap();
    }
    // 2 s after the last sample the tip rests on it (transient decayed e^-13).
    assert!((sim.true_tip_m_device() - Vector3::new(0.01, 0.01, -0.005)).norm() < 1e-6);
}
