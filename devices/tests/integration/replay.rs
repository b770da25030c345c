//! Record a deterministic closed-loop run, write the trace file, read it back,
//! replay it: the forces come out bit for bit.

use std::time::Duration;

use haptloop_devices::{
    Device, Hand, ReplayDevice, SafeDevice, SafetyConfig, Trace, TraceHeader, TraceRecorder,
    TraceRow, Trajectory,
};
use nalgebra::Vector3;

use crate::common::{safe_sim, tick, wall};

const K: f64 = 600.0;
const TICKS: u64 = 1500;

fn record() -> Trace {
    let hand = Hand::new(Trajectory::Line {
        to_m: Vector3::new(0.01, -0.012, 0.004),
        duration: Duration::from_secs(1),
    });
    let mut dev = safe_sim("phantom-premium-1.5", hand.clone(), SafetyConfig::default());
    let header = TraceHeader {
        scene: "wall".into(),
        model: "phantom-premium-1.5".into(),
        rate_hz: 1000,
    };
    let mut rec = TraceRecorder::with_capacity(header, TICKS as usize + 1);
    for k in 0..=TICKS {
        let now = tick(k);
        let r = dev.read(now);
        let cmd = wall(K, &r.tip_m_device);
        let out = dev.write(cmd, now);
        rec.record(TraceRow {
            time: now,
            counts: r.joint_counts,
            command_n_device: cmd,
            output_n_device: out.force_n_device,
            hand_offset_m_device: hand.trajectory.sample(now).offset_m,
            orientation_wxyz: {
                let q = r.orientation_device.quaternion();
                [q.w, q.i, q.j, q.k]
            },
        });
    }
    assert_eq!(rec.dropped(), 0);
    rec.finish()
}

#[test]
fn replaying_a_trace_file_reproduces_forces_bit_for_bit() {
    let trace = record();
    let peak = trace
        .rows
        .iter()
        .map(|r| r.output_n_device.norm())
        .fold(0.0, f64::max);
    assert!(
        peak > 2.0,
        "the run must press into the wall (peak {peak} N)"
    );
    let path = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("replay_round_trip.trace");
    trace.save(&path).unwrap();
    let loaded = Trace::load(&path).unwrap();
    assert_eq!(loaded.rows.len(), trace.rows.len());

    let mut dev =
        SafeDevice::new(ReplayDevice::new(loaded).unwrap(), SafetyConfig::default()).unwrap();
    for row in &trace.rows {
        let r = dev.read(row.time);
        assert_eq!(r.joint_counts, row.counts);
        let cmd = wall(K, &r.tip_m_device);
        let out = dev.write(cmd, row.time);
        let bits = |v: Vector3<f64>| v.map(f64::to_bits);
        assert_eq!(
            bits(cmd),
            bits(row.command_n_device),
            "command at {:?}",
            row.time
        );
        assert_eq!(
            bits(out.force_n_device),
            bits(row.output_n_device),
            "output at {:?}",
            row.time
        );
    }
    assert!(dev.device().finished());
}

#[test]
fn replay_before_the_first_row_is_a_dropped_reading_and_unknown_model_errors() {
    let mut trace = record();
    trace.rows.drain(..10);
    let mut replay = ReplayDevice::new(trace.clone()).unwrap();
    assert!(replay.read(tick(5)).is_err());
    assert!(replay.read(tick(10)).is_ok());
    trace.header.model = "phantom-9000".into();
    let err = ReplayDevice::new(trace).unwrap_err().to_string();
    assert!(
        err.contains("phantom-9000") && err.contains("phantom-omni"),
        "{err}"
    );
}
