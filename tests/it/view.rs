//! The viewer's data and the virtual device, without a browser: every
//! scene's track, `haptloop view`'s refusals, the live flags' refusals, the
//! virtual device's equilibrium in a session, record and replay of it, and
//! the fast loop's zero-allocation rule with the live exchange on.

use haptloop::scenes::resolve;
use haptloop::session::{self, Plan, SessionOptions};
use haptloop_rt::clock::{MockClock, Nanos};
use haptloop_rt::schedule::{Periodic, RunLimit, StopFlag, Tick, TickBody};
use nalgebra::Vector3;

fn deterministic(seconds: f64) -> SessionOptions {
    SessionOptions {
        seconds,
        deterministic: true,
        ..SessionOptions::default()
    }
}

/// The four-bar on a virtual device whose pointer is moved 1 cm at 0.2 s:
/// the tip comes to rest at pointer + F/k (the documented mass-spring-
/// damper against the rendered force), with a force rendered.
#[test]
fn a_virtual_device_comes_to_rest_where_its_pointer_spring_balances_the_force() {
    let scene = resolve("four-bar")
        .unwrap()
        .with_device_model("virtual")
        .unwrap();
    let plan = Plan::new(&scene, &deterministic(3.0)).unwrap();
    let clock = MockClock::new(Nanos(0));
    let mut b = session::build(&scene, &plan, clock.clone()).unwrap();
    let pointer = b.fast.rig().pointers[0].clone().unwrap();
    let mount = b.fast.rig().devices[0].mount.clone();
    let (mut periodic, _iv) = Periodic::new(&plan.schedule(), clock).unwrap();
    let stop = StopFlag::new();
    let (mut worst_late, mut force_late) = (0.0f64, f64::INFINITY);
    for chunk in 0..600u64 {
        periodic.run(&mut b.fast, RunLimit::slots(5), &stop);
        b.slow.step();
        if chunk == 40 {
            pointer.set(&Vector3::new(0.01, 0.0, 0.0));
        }
        let mut last = None;
        while let Some(s) = b.trace.pop() {
            last = Some(s);
        }
        let s = last.unwrap();
        let tip = Vector3::from(s.target_m);
        let f = Vector3::from(s.force_n);
        let target = mount.point_to_scene(&pointer.get().unwrap_or_default());
        let k = 300.0 / (mount.scale * mount.scale);
        let off = (tip - (target + f / k)).norm();
        // Settled after 1.5 s (the linkage creeps for about a second).
        if chunk >= 300 {
            worst_late = worst_late.max(off);
            force_late = force_late.min(f.norm());
        }
    }
    // A few µm: the tip is sensed to 1 µm, the pointer kept to 1 µm.
    assert!(
        worst_late < 5e-6,
        "tip − (pointer + F/k) up to {worst_late:e} m"
    );
    assert!(
        force_late > 0.5,
        "the linkage held the tip back with {force_late} N"
    );
}
