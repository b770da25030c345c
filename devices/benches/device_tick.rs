//! `device_tick/<model>`: one fast-loop tick of a simulated arm — safety-layer
//! read (4 physics sub-steps at 1 kHz, encoders, kinematics), a wall force law,
//! safety-layer write (clamp, ramp, rate limit, Jᵀ torque mapping, thermal).
//!
//! Run: `CARGO_TARGET_DIR=target/devices cargo bench -p haptloop-devices --bench device_tick`

use std::hint::black_box;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use haptloop_devices::{Hand, SafeDevice, SafetyConfig, SimOptions, SimPhantom, Trajectory};
use nalgebra::Vector3;

fn device_tick(c: &mut Criterion) {
    let mut group = c.benchmark_group("device_tick");
    for model in ["phantom-premium-1.5", "phantom-omni"] {
        let hand = Hand::new(Trajectory::Circle {
            radius_m: 0.01,
            frequency_hz: 1.0,
            u: Vector3::x(),
            v: -Vector3::y(),
        });
        let sim = SimPhantom::by_name(model, SimOptions::default(), hand).unwrap();
        let mut dev = SafeDevice::new(sim, SafetyConfig::default()).unwrap();
        let period = Duration::from_millis(1);
        let mut now = Duration::ZERO;
        group.bench_function(model, |b| {
            b.iter(|| {
                now += period;
                let r = dev.read(black_box(now));
                let f = Vector3::new(0.0, (-r.tip_m_device.y).max(0.0) * 800.0, 0.0);
                black_box(dev.write(f, now))
            })
        });
    }
    group.finish();
}

criterion_group!(benches, device_tick);
criterion_main!(benches);
