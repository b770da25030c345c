//! The safety layer's stages: clamp, ramp, rate limit, watchdog, NaN guard,
//! velocity limit.

use std::time::Duration;

use haptloop_devices::{CutReason, FaultKind, Grip, Hand, SafetyConfig, Trajectory};
use nalgebra::Vector3;

use crate::common::{no_ramp, safe_sim, tick};

#[test]
fn clamp_limits_magnitude_and_keeps_direction() {
    let mut dev = safe_sim("phantom-premium-1.5", Hand::still(), no_ramp());
    dev.read(tick(1));
    let out = dev.write(Vector3::new(12.0, -16.0, 0.0), tick(1));
    assert!(
        (out.force_n_device - Vector3::new(0.6, -0.8, 0.0) * 8.5).norm() < 1e-12,
        "{}",
        out.force_n_device
    );
    assert!(out.cuts.contains(CutReason::Clamp));
    let cut = dev.last_cut().unwrap();
    assert_eq!((cut.reason, cut.requested_n), (CutReason::Clamp, 20.0));
    assert!((cut.applied_n - 8.5).abs() < 1e-3, "{}", cut.applied_n);
}

#[test]
fn startup_ramp_is_linear_over_the_ramp_time() {
    let mut dev = safe_sim("phantom-omni", Hand::still(), SafetyConfig::default());
    let f = Vector3::new(0.0, 0.0, 1.0);
    for k in 1..=1200u64 {
        dev.read(tick(k));
        let out = dev.write(f, tick(k));
        let expected = ((k - 1) as f64 / 1000.0).min(1.0);
        assert!(
            (out.force_n_device.z - expected).abs() < 1e-12,
            "tick {k}: {} vs {expected}",
            out.force_n_device.z
        );
        assert_eq!(out.cuts.contains(CutReason::Ramp), k < 1001, "tick {k}");
    }
}

#[test]
fn rate_limit_bounds_change_per_tick() {
    let cfg = SafetyConfig {
        ramp: Duration::ZERO,
        ..SafetyConfig::default()
    }; // 2000 N/s = 2 N per ms
    let mut dev = safe_sim("phantom-premium-1.5", Hand::still(), cfg);
    let step = Vector3::new(3.0, 0.0, 4.0); // 5 N
    let mut outs = Vec::new();
    for k in 1..=4u64 {
        dev.read(tick(k));
        outs.push(dev.write(step, tick(k)).force_n_device.norm());
    }
    for (got, want) in outs.iter().zip([2.0, 4.0, 5.0, 5.0]) {
        assert!((got - want).abs() < 1e-12, "{outs:?}");
    }
    assert_eq!(dev.counters().cut_ticks(CutReason::RateLimit), 2);
}

#[test]
fn watchdog_switches_motors_off_when_writes_stop() {
    let mut dev = safe_sim("phantom-premium-1.5", Hand::still(), no_ramp());
    for k in 1..=50u64 {
        dev.read(tick(k));
        dev.write(Vector3::new(1.0, 0.0, 0.0), tick(k));
    }
    let work_at_50 = dev.device().motor_work_j();
    // The loop stalls: reads continue, writes stop. Timeout = 10 periods.
    dev.read(tick(60));
    let work_at_60 = dev.device().motor_work_j();
    // Until the timeout the held torque keeps working on the moving tip.
    assert!(work_at_60 != work_at_50 && dev.last_cut().is_none());
    for k in 61..=80u64 {
        dev.read(tick(k));
    }
    let cut = dev.last_cut().expect("watchdog must record a cut");
    assert_eq!((cut.reason, cut.at), (CutReason::Watchdog, tick(61)));
    // The hardware watchdog cut torque at exactly 60 ms: no motor work after it.
    assert_eq!(dev.device().motor_work_j(), work_at_60);
    // Re-engaging counts one watchdog episode and force returns.
    let out = dev.write(Vector3::new(1.0, 0.0, 0.0), tick(81));
    assert!(out.cuts.contains(CutReason::Watchdog));
    assert_eq!(dev.counters().cut_episodes(CutReason::Watchdog), 1);
    assert!(out.motor.force_n_device.norm() > 0.99);
}

#[test]
fn non_finite_commands_never_reach_a_motor() {
    let mut dev = safe_sim("phantom-omni", Hand::still(), no_ramp());
    let bad = [f64::NAN, f64::INFINITY, f64::NEG_INFINITY];
    for (i, v) in bad.iter().enumerate() {
        let k = 2 * i as u64 + 1;
        dev.read(tick(k));
        let out = dev.write(Vector3::new(0.1, *v, 0.0), tick(k));
        assert_eq!(out.force_n_device, Vector3::zeros());
        assert_eq!(out.motor.torque_nm, Vector3::zeros());
        assert_eq!(dev.last_cut().unwrap().reason, CutReason::NonFiniteForce);
        // A good command afterwards is delivered again.
        dev.read(tick(k + 1));
        let ok = dev.write(Vector3::new(0.5, 0.0, 0.0), tick(k + 1));
        assert!((ok.force_n_device.x - 0.5).abs() < 1e-12);
    }
    assert_eq!(dev.counters().faults(FaultKind::NonFiniteForce), 3);
    assert_eq!(dev.counters().cut_ticks(CutReason::NonFiniteForce), 3);
    // Whatever comes in, what goes out is finite and within the peak.
    for (k, f) in [1e300, -1e300, f64::MAX, f64::MIN_POSITIVE, 7.0]
        .into_iter()
        .enumerate()
    {
        let t = tick(100 + k as u64);
        dev.read(t);
        let out = dev.write(Vector3::new(f, -f, f), t);
        assert!(
            out.force_n_device.iter().all(|v| v.is_finite())
                && out.force_n_device.norm() <= 3.3 + 1e-12
        );
    }
}

#[test]
fn velocity_limit_cuts_force_while_the_tip_moves_too_fast() {
    // The hand yanks the stylus 6 cm in 10 ms (6 m/s target speed).
    let hand = Hand::new(Trajectory::Line {
        to_m: Vector3::new(0.06, 0.0, 0.0),
        duration: Duration::from_millis(10),
    })
    .with_grip(Grip {
        stiffness_n_per_m: 3000.0,
        damping_n_s_per_m: 20.0,
    });
    let mut dev = safe_sim("phantom-premium-1.5", hand, no_ramp());
    let mut cut_ticks = 0;
    for k in 1..=400u64 {
        dev.read(tick(k));
        let fast = dev.speed_m_per_s() > 2.0;
        let out = dev.write(Vector3::new(0.0, 0.3, 0.0), tick(k));
        assert_eq!(out.cuts.contains(CutReason::Velocity), fast, "tick {k}");
        if fast {
            cut_ticks += 1;
            assert_eq!(out.force_n_device, Vector3::zeros());
        }
    }
    assert!(cut_ticks > 0, "a 6 m/s yank must trip the 2 m/s limit");
    assert_eq!(dev.counters().cut_ticks(CutReason::Velocity), cut_ticks);
    // Once the stylus has settled, force is delivered again.
    let out = dev.write(Vector3::new(0.0, 0.3, 0.0), tick(401));
    assert!((out.force_n_device.y - 0.3).abs() < 1e-12);
}

/// Applied joint torque at the motor, N·m (never through the safety layer's
/// own bookkeeping).
fn at_motor(dev: &haptloop_devices::SafeDevice<haptloop_devices::SimPhantom>) -> Vector3<f64> {
    haptloop_devices::Device::applied_torque_nm(dev.device()).expect("the sim reports torque")
}

#[test]
fn zero_command_and_stop_reach_zero_force_on_the_same_write() {
    let cfg = SafetyConfig {
        ramp: Duration::ZERO,
        ..SafetyConfig::default()
    }; // 2 N per write up, nothing down
    let mut dev = safe_sim("phantom-premium-1.5", Hand::still(), cfg);
    for k in 1..=10u64 {
        dev.read(tick(k));
        dev.write(Vector3::new(0.0, 6.0, 0.0), tick(k));
    }
    assert!(at_motor(&dev).norm() > 0.1);
    // A cut (zero command) is not rate limited: 6 N → 0 N in one write.
    dev.read(tick(11));
    let out = dev.write(Vector3::zeros(), tick(11));
    assert_eq!(out.force_n_device, Vector3::zeros());
    assert!(!out.cuts.contains(CutReason::RateLimit));
    assert_eq!(at_motor(&dev), Vector3::zeros());
    // Shrinking along the same direction passes at once too.
    for k in 12..=20u64 {
        dev.read(tick(k));
        dev.write(Vector3::new(0.0, 6.0, 0.0), tick(k));
    }
    dev.read(tick(21));
    let out = dev.write(Vector3::new(0.0, 1.0, 0.0), tick(21));
    assert!((out.force_n_device - Vector3::new(0.0, 1.0, 0.0)).norm() < 1e-12);
    // Reversal is a fall to zero (free) and a limited rise: -2 N, not -6 N.
    dev.read(tick(22));
    let out = dev.write(Vector3::new(0.0, -6.0, 0.0), tick(22));
    assert!((out.force_n_device - Vector3::new(0.0, -2.0, 0.0)).norm() < 1e-12);
    // Stop: zero force and motors off on the same call, read at the motor.
    dev.read(tick(23));
    let out = dev.stop(tick(23));
    assert_eq!(out.force_n_device, Vector3::zeros());
    assert_eq!(at_motor(&dev), Vector3::zeros());
    assert!(!dev.device().motors_on());
}

#[test]
fn a_write_after_a_gap_steps_by_one_period_at_most() {
    let cfg = SafetyConfig {
        ramp: Duration::ZERO,
        ..SafetyConfig::default()
    };
    let mut dev = safe_sim("phantom-premium-1.5", Hand::still(), cfg);
    dev.read(tick(1));
    dev.write(Vector3::zeros(), tick(1));
    // A 7 ms stall (below the 10 ms watchdog): the old rule allowed 14 N.
    dev.read(tick(8));
    let out = dev.write(Vector3::new(8.0, 0.0, 0.0), tick(8));
    assert!(
        (out.force_n_device.norm() - 2.0).abs() < 1e-12,
        "{}",
        out.force_n_device
    );
    assert!(out.cuts.contains(CutReason::RateLimit));
}

#[test]
fn recovery_after_a_stall_ramps_in_proportion_to_the_gap() {
    let cfg = SafetyConfig::default(); // 1 s start-up ramp, 10 ms watchdog
    let mut dev = safe_sim("phantom-omni", Hand::still(), cfg);
    let f = Vector3::new(0.0, 0.0, 1.0);
    for k in 1..=1100u64 {
        dev.read(tick(k));
        dev.write(f, tick(k));
    }
    // Writes stop for 20 ms: the watchdog fires at 1111 ms.
    for k in 1101..=1120u64 {
        dev.read(tick(k));
    }
    assert_eq!(dev.last_cut().unwrap().reason, CutReason::Watchdog);
    // Ramp back over 10 × the 11 ms gap = 110 ms, not the 1 s start-up ramp.
    let mut outs = Vec::new();
    for k in 1121..=1300u64 {
        dev.read(tick(k));
        outs.push(dev.write(f, tick(k)).force_n_device.z);
    }
    let gap_ramp = 0.110;
    for (i, z) in outs.iter().enumerate() {
        let expected = (i as f64 * 0.001 / gap_ramp).min(1.0);
        assert!((z - expected).abs() < 1e-9, "write {i}: {z} vs {expected}");
    }
    assert_eq!(outs[150], 1.0);
}

#[test]
fn a_stall_during_the_start_up_ramp_does_not_shorten_it() {
    let mut dev = safe_sim("phantom-omni", Hand::still(), SafetyConfig::default());
    let f = Vector3::new(0.0, 0.0, 1.0);
    for k in 1..=100u64 {
        dev.read(tick(k));
        dev.write(f, tick(k));
    }
    // A 20 ms stall 0.1 s into the 1 s ramp: when the watchdog fires (at
    // 111 ms, 110 ms after the ramp began) 890 ms of it were left.
    for k in 101..=120u64 {
        dev.read(tick(k));
    }
    assert_eq!(dev.last_cut().unwrap().reason, CutReason::Watchdog);
    let mut last = 0.0;
    for k in 121..=1200u64 {
        dev.read(tick(k));
        let z = dev.write(f, tick(k)).force_n_device.z;
        let expected = ((k - 121) as f64 / 890.0).min(1.0);
        assert!((z - expected).abs() < 1e-9, "tick {k}: {z} vs {expected}");
        last = z;
    }
    assert_eq!(last, 1.0);
}
