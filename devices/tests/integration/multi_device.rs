//! Several devices at once, each with its own origin, orientation and scale.

use std::time::Duration;

use haptloop_devices::{
    Hand, Mount, MountedDevice, SafetyConfig, SimOptions, SimPhantom, Trajectory,
};
use nalgebra::{UnitQuaternion, Vector3};

use crate::common::tick;

fn rig(model: &str, mount: Mount, hand_scene: &Trajectory) -> MountedDevice<SimPhantom> {
    let hand = Hand::new(mount.trajectory_to_device(hand_scene));
    let sim = SimPhantom::by_name(model, SimOptions::default(), hand).unwrap();
    let cfg = SafetyConfig {
        ramp: Duration::ZERO,
        ..SafetyConfig::default()
    };
    MountedDevice::new(model, sim, cfg, mount).unwrap()
}

#[test]
fn two_devices_register_onto_their_fingers_and_follow_scene_trajectories() {
    let circle = Trajectory::Circle {
        radius_m: 0.02,
        frequency_hz: 0.25,
        u: Vector3::x(),
        v: Vector3::y(),
    };
    // Left: Omni, turned 90° about z, workspace doubled. Right: Premium, tilted, 1:1.
    let left_q = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), std::f64::consts::FRAC_PI_2);
    let right_q = UnitQuaternion::from_euler_angles(0.2, -0.1, 0.4);
    let (wl, wr) = (left_q.quaternion(), right_q.quaternion());
    let mut left = rig(
        "phantom-omni",
        Mount::new(Vector3::zeros(), [wl.w, wl.i, wl.j, wl.k], 2.0).unwrap(),
        &circle,
    );
    let mut right = rig(
        "phantom-premium-1.5",
        Mount::new(Vector3::zeros(), [wr.w, wr.i, wr.j, wr.k], 1.0).unwrap(),
        &Trajectory::Still,
    );
    let (finger_l, finger_r) = (Vector3::new(-0.1, 0.4, 0.2), Vector3::new(0.15, 0.4, 0.2));
    left.register(Duration::ZERO, &finger_l);
    right.register(Duration::ZERO, &finger_r);
    assert!((left.read_scene(tick(1)).tip_m_scene - finger_l).norm() < 1e-12);
    assert!((right.read_scene(tick(1)).tip_m_scene - finger_r).norm() < 1e-12);

    // Free motion (zero force): the left tip traces the scene circle. At 0.25 Hz
    // the grip lags by ~ω·b/k ≈ 5e-3 rad of phase and the encoder quantises
    // 0.055 mm × scale 2: 0.5 mm of scene-frame tracking error is ample but a
    // wrong rotation or scale (errors of centimetres) fails.
    let mut worst = 0.0f64;
    for k in 2..=4000u64 {
        let now = tick(k);
        let l = left.read_scene(now);
        left.write_scene(Vector3::zeros(), now);
        right.read_scene(now);
        right.write_scene(Vector3::zeros(), now);
        let expected = finger_l + circle.sample(now).offset_m;
        worst = worst.max((l.tip_m_scene - expected).norm());
    }
    assert!(
        worst < 5e-4,
        "left tip strays {worst} m from the scene circle"
    );
}

#[test]
fn scene_forces_map_to_each_device_frame_with_power_consistent_scaling() {
    let q = UnitQuaternion::from_euler_angles(0.5, 0.3, -0.7);
    let c = q.quaternion();
    let mut dev = rig(
        "phantom-premium-1.5",
        Mount::new(Vector3::new(1.0, 2.0, 3.0), [c.w, c.i, c.j, c.k], 3.0).unwrap(),
        &Trajectory::Still,
    );
    dev.read_scene(tick(1));
    let f_scene = Vector3::new(0.2, -0.1, 0.3);
    let out = dev.write_scene(f_scene, tick(1));
    // F_device = s Rᵀ F_scene (3× larger at the device for a 3× workspace).
    let expected = q.inverse() * f_scene * 3.0;
    assert!(
        (out.force_n_device - expected).norm() < 1e-12,
        "{} vs {expected}",
        out.force_n_device
    );
    assert!((out.force_n_device.norm() - 3.0 * f_scene.norm()).abs() < 1e-12);
}
