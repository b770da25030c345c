//! Each injected fault and its defined outcome.

use std::time::Duration;

use haptloop_devices::{
    CutReason, FaultKind, Hand, Health, InjectedFault, ReadingFlags, SafeDevice, SimPhantom,
    Trajectory,
};
use nalgebra::Vector3;

use crate::common::{no_ramp, safe_sim, tick};

fn moving_hand() -> Hand {
    Hand::new(Trajectory::Circle {
        radius_m: 0.02,
        frequency_hz: 1.0,
        u: Vector3::x(),
        v: Vector3::z(),
    })
}

fn device_with(fault: InjectedFault, duration: Option<Duration>) -> SafeDevice<SimPhantom> {
    let mut dev = safe_sim("phantom-premium-1.5", moving_hand(), no_ramp());
    dev.device_mut().inject(fault, tick(100), duration).unwrap();
    dev
}

const F: Vector3<f64> = Vector3::new(0.0, 0.2, 0.0);

/// Runs ticks `from..=to`, returning (reading, output force) per tick.
fn run(
    dev: &mut SafeDevice<SimPhantom>,
    from: u64,
    to: u64,
) -> Vec<(haptloop_devices::DeviceReading, Vector3<f64>)> {
    (from..=to)
        .map(|k| {
            let r = dev.read(tick(k));
            (r, dev.write(F, tick(k)).force_n_device)
        })
        .collect()
}

/// Transient bad readings: the last good one is held and flagged, force stays.
fn assert_held_transient(fault: InjectedFault, flag: ReadingFlags, kind: FaultKind) {
    let mut dev = device_with(fault, Some(Duration::from_millis(3)));
    let before = run(&mut dev, 1, 99);
    let last_good = before.last().unwrap().0;
    for (r, f) in run(&mut dev, 100, 102) {
        assert!(
            r.flags.contains(ReadingFlags::HELD.with(flag)),
            "{:?}",
            r.flags
        );
        assert_eq!(r.tip_m_device, last_good.tip_m_device);
        assert!((f - F).norm() < 1e-12, "a short hold keeps force: {f}");
        assert_eq!(dev.health(), Health::Holding(kind));
    }
    let (r, _) = run(&mut dev, 103, 103)[0];
    assert_eq!(r.flags, ReadingFlags::EMPTY);
    assert_ne!(
        r.tip_m_device, last_good.tip_m_device,
        "the hand kept moving"
    );
    assert_eq!(dev.health(), Health::Ok);
    assert_eq!(dev.counters().faults(kind), 3);
    assert_eq!(dev.counters().held_readings, 3);
}

#[test]
fn nan_reading_is_held_and_flagged() {
    assert_held_transient(
        InjectedFault::NanReading,
        ReadingFlags::NON_FINITE,
        FaultKind::NonFiniteReading,
    );
}

#[test]
fn dropped_reading_is_held_and_flagged() {
    assert_held_transient(
        InjectedFault::DroppedReading,
        ReadingFlags::DROPPED,
        FaultKind::DroppedReading,
    );
}

#[test]
fn long_run_of_bad_readings_latches_and_cuts_until_cleared() {
    let mut dev = device_with(InjectedFault::NanReading, Some(Duration::from_millis(20)));
    run(&mut dev, 1, 99);
    let during = run(&mut dev, 100, 119);
    // 10 held ticks are tolerated (max_consecutive_bad_readings), the 11th latches.
    for (k, (_, f)) in during.iter().enumerate() {
        assert_eq!(f.norm() == 0.0, k >= 10, "tick {}", 100 + k);
    }
    assert_eq!(dev.health(), Health::Fault(FaultKind::NonFiniteReading));
    let (_, f) = run(&mut dev, 120, 120)[0];
    assert_eq!(
        f,
        Vector3::zeros(),
        "latched: good readings alone do not re-enable force"
    );
    assert_eq!(dev.last_cut().unwrap().reason, CutReason::Fault);
    dev.clear_fault();
    let (_, f) = run(&mut dev, 121, 121)[0];
    assert!((f - F).norm() < 1e-12);
}

#[test]
fn stuck_encoder_cuts_force_at_once() {
    let mut dev = device_with(InjectedFault::StuckEncoder { joint: 1 }, None);
    run(&mut dev, 1, 99);
    let (r, f) = run(&mut dev, 100, 100)[0];
    assert!(
        r.flags
            .contains(ReadingFlags::HELD.with(ReadingFlags::ENCODER_SIGNAL_LOST))
    );
    assert_eq!(r.flags.joint_mask(), 0b010);
    assert_eq!(f, Vector3::zeros());
    assert_eq!(dev.health(), Health::Fault(FaultKind::EncoderSignalLost));
    assert_eq!(dev.last_fault().unwrap().joint, Some(1));
    let work = dev.device().motor_work_j();
    run(&mut dev, 101, 150);
    assert_eq!(dev.device().motor_work_j(), work, "motors stay off");
}

#[test]
fn disconnect_cuts_force_and_stays_latched() {
    let mut dev = device_with(InjectedFault::Disconnect, None);
    run(&mut dev, 1, 99);
    let (r, f) = run(&mut dev, 100, 100)[0];
    assert!(
        r.flags
            .contains(ReadingFlags::HELD.with(ReadingFlags::DISCONNECTED))
    );
    assert_eq!(f, Vector3::zeros());
    assert_eq!(dev.health(), Health::Fault(FaultKind::Disconnected));
    let work = dev.device().motor_work_j();
    run(&mut dev, 101, 130);
    assert_eq!(dev.device().motor_work_j(), work);
    assert_eq!(dev.counters().faults(FaultKind::Disconnected), 31);
}

#[test]
fn transient_encoder_jump_is_rejected() {
    let mut dev = device_with(
        InjectedFault::EncoderJump {
            joint: 0,
            counts: 5000,
        },
        Some(Duration::from_millis(1)),
    );
    let before = run(&mut dev, 1, 99);
    let (r, f) = run(&mut dev, 100, 100)[0];
    assert!(
        r.flags
            .contains(ReadingFlags::HELD.with(ReadingFlags::ENCODER_JUMP))
    );
    assert_eq!(r.flags.joint_mask(), 0b001);
    assert_eq!(r.tip_m_device, before.last().unwrap().0.tip_m_device);
    assert!((f - F).norm() < 1e-12);
    let (r, _) = run(&mut dev, 101, 101)[0];
    assert_eq!((r.flags, dev.health()), (ReadingFlags::EMPTY, Health::Ok));
    assert_eq!(dev.counters().faults(FaultKind::EncoderJump), 1);
}

#[test]
fn persistent_encoder_jump_latches_until_rehomed() {
    let mut dev = device_with(
        InjectedFault::EncoderJump {
            joint: 2,
            counts: -3000,
        },
        None,
    );
    run(&mut dev, 1, 99);
    run(&mut dev, 100, 110);
    assert_eq!(dev.health(), Health::Fault(FaultKind::EncoderJump));
    let (_, f) = run(&mut dev, 111, 111)[0];
    assert_eq!(f, Vector3::zeros());
    // Re-homing accepts the offset counts as the new reference.
    dev.clear_fault();
    let (r, f) = run(&mut dev, 112, 112)[0];
    assert_eq!((r.flags, dev.health()), (ReadingFlags::EMPTY, Health::Ok));
    assert!((f - F).norm() < 1e-12);
}
