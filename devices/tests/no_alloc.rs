//! The fast path allocates nothing: read + write through the safety layer and
//! the mount, trace recording, fault handling and replay, counted by the
//! project's counting allocator (its own test binary: it installs the global
//! allocator).

use std::time::Duration;

use haptloop_devices::{
    Device, Hand, InjectedFault, Mount, MountedDevice, ReplayDevice, SafeDevice, SafetyConfig,
    SimOptions, SimPhantom, TraceHeader, TraceRecorder, TraceRow, Trajectory,
};
use haptloop_rt::alloc::{CountingAllocator, count};
use nalgebra::Vector3;

#[global_allocator]
static ALLOC: CountingAllocator = CountingAllocator;

const T: Duration = Duration::from_millis(1);

fn mounted(model: &str) -> MountedDevice<SimPhantom> {
    let hand = Hand::new(Trajectory::Circle {
        radius_m: 0.01,
        frequency_hz: 1.0,
        u: Vector3::x(),
        v: -Vector3::y(),
    });
    let mut sim = SimPhantom::by_name(model, SimOptions::default(), hand).unwrap();
    // Every fault kind fires during the counted window.
    sim.inject(InjectedFault::NanReading, T * 100, Some(T * 3))
        .unwrap();
    sim.inject(InjectedFault::DroppedReading, T * 200, Some(T * 20))
        .unwrap();
    sim.inject(
        InjectedFault::EncoderJump {
            joint: 0,
            counts: 900,
        },
        T * 300,
        Some(T),
    )
    .unwrap();
    sim.inject(
        InjectedFault::StuckEncoder { joint: 2 },
        T * 400,
        Some(T * 5),
    )
    .unwrap();
    sim.inject(InjectedFault::Disconnect, T * 900, None)
        .unwrap();
    MountedDevice::new(
        model,
        sim,
        SafetyConfig::default(),
        Mount::new(Vector3::zeros(), [0.9, 0.1, 0.2, 0.3], 1.5).unwrap(),
    )
    .unwrap()
}

#[test]
fn read_write_safety_trace_and_replay_do_not_allocate() {
    let mut devices = [mounted("phantom-premium-1.5"), mounted("phantom-omni")];
    let header = TraceHeader {
        scene: "no-alloc".into(),
        model: "phantom-premium-1.5".into(),
        rate_hz: 1000,
    };
    let mut rec = TraceRecorder::with_capacity(header.clone(), 500); // fills up: drops are counted, not allocated
    // The session's recorder: a bounded queue, never drained here, so it
    // fills and counts drops without allocating.
    let (mut streaming, stream) = TraceRecorder::streaming(header, 300);
    let finger = Vector3::new(0.0, -0.005, 0.0);
    let ((), stats) = count(|| {
        for k in 1..=1000u32 {
            let now = T * k;
            for (i, d) in devices.iter_mut().enumerate() {
                let r = d.read_scene(now);
                let f = (finger - r.tip_m_scene) * 400.0;
                let f = if k % 97 == 0 {
                    Vector3::new(f64::NAN, 0.0, 0.0)
                } else {
                    f
                };
                let out = d.write_scene(f, now);
                if k % 251 == 0 {
                    d.device.clear_fault();
                }
                if k % 333 == 0 {
                    d.device.stop(now); // zero force and motors off
                }
                if i == 0 {
                    let q = r.reading.orientation_device.quaternion();
                    let row = TraceRow {
                        time: now,
                        counts: r.reading.joint_counts,
                        command_n_device: f,
                        output_n_device: out.force_n_device,
                        hand_offset_m_device: Vector3::zeros(),
                        orientation_wxyz: [q.w, q.i, q.j, q.k],
                    };
                    rec.record(row);
                    streaming.record(row);
                }
            }
        }
    });
    assert_eq!(stats.total(), 0, "fast path allocated: {stats:?}");
    assert_eq!(rec.dropped(), 500);
    assert_eq!((streaming.dropped(), stream.dropped()), (700, 700));
    // The faults did fire (the counted path was the faulty one too).
    assert!(devices[0].device.counters().events().count() >= 5);

    let trace = rec.finish();
    let mut replay =
        SafeDevice::new(ReplayDevice::new(trace).unwrap(), SafetyConfig::default()).unwrap();
    let ((), stats) = count(|| {
        for k in 1..=600u32 {
            let r = replay.read(T * k);
            replay.write(r.tip_m_device * -300.0, T * k);
        }
    });
    assert_eq!(stats.total(), 0, "replay allocated: {stats:?}");
    assert!(replay.device().finished());
    let _ = replay.device_mut().read(T);
}
