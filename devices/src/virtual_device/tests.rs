use super::*;
use crate::passivity::colgate_bound_n_per_m;

fn device() -> (VirtualDevice, Pointer) {
    let pointer = Pointer::new();
    let d = VirtualDevice::new(VirtualParams::default(), pointer.clone()).unwrap();
    (d, pointer)
}

/// With no force rendered, a pointer step is answered exactly as the
/// documented mass-spring-damper answers it: the closed-form underdamped
/// step response e(t) = e₀ e^{−ζω₀t}(cos ω_d t + ζω₀/ω_d sin ω_d t).
#[test]
fn a_pointer_step_follows_the_closed_form_mass_spring_damper() {
    let (mut d, pointer) = device();
    let p = *d.params();
    let step = 0.01;
    pointer.set(&Vector3::new(step, 0.0, 0.0));
    let w0 = (p.pointer_stiffness_n_per_m / p.mass_kg).sqrt();
    let zeta = p.damping_n_s_per_m / (2.0 * (p.pointer_stiffness_n_per_m * p.mass_kg).sqrt());
    assert!(zeta < 1.0, "the defaults are underdamped: ζ = {zeta}");
    let wd = w0 * (1.0 - zeta * zeta).sqrt();
    let mut worst: f64 = 0.0;
    for k in 0..=300u32 {
        let now = Duration::from_millis(u64::from(k));
        let r = d.read(now).unwrap();
        d.write(Vector3::zeros(), now).unwrap();
        let t = now.as_secs_f64();
        let e = -step * (-zeta * w0 * t).exp() * ((wd * t).cos() + zeta * w0 / wd * (wd * t).sin());
        let exact = step + e;
        worst = worst.max((d.true_tip_m_device().x - exact).abs());
        // The sensed tip is the true one to the micrometre.
        assert!((r.tip_m_device.x - d.true_tip_m_device().x).abs() <= 0.5e-6 + 1e-12);
        assert_eq!((r.tip_m_device.y, r.tip_m_device.z), (0.0, 0.0));
    }
    // 0.2 % of the step: the integrator's error at quarter-period
    // sub-steps; a parameter off by 10 % would be off by millimetres.
    assert!(
        worst < 2e-5,
        "largest deviation from the closed form {worst:e} m (of a {step} m step)"
    );
}

/// One wall experiment as `passivity::run_wall` does it for the arm: a
/// sampled, quantised unilateral spring K held between 1 kHz writes, the
/// pointer pressing the tip into it with 2 N. Returns the largest energy
/// excess over the last fifth of 3 s divided by the initial excess.
fn wall_growth(k_wall: f64) -> f64 {
    let (mut d, pointer) = device();
    let kp = d.params().pointer_stiffness_n_per_m;
    let push = 2.0;
    pointer.set(&Vector3::new(0.0, -(push / kp + push / k_wall), 0.0));
    let e_eq = 0.5 * push * push / k_wall + 0.5 * push * push / kp;
    let excess = |d: &VirtualDevice| {
        let pen = (-d.true_tip_m_device().y).max(0.0);
        d.energy_j() + 0.5 * k_wall * pen * pen - d.pointer_work_j() - e_eq
    };
    let ticks = 3000u64;
    let (mut initial, mut late) = (f64::NAN, 0.0f64);
    for tick in 0..=ticks {
        let now = Duration::from_millis(tick);
        let r = d.read(now).unwrap();
        if tick == 0 {
            // The pointer's first move is the hand's input, not growth.
            initial = excess(&d) + d.pointer_work_j();
            d.pointer_work_j = 0.0;
        }
        if tick >= ticks - ticks / 5 {
            late = late.max(excess(&d));
        }
        let pen = -r.tip_m_device.y;
        let f = if pen > 0.0 { k_wall * pen } else { 0.0 };
        d.write(Vector3::new(0.0, f, 0.0), now).unwrap();
    }
    late / initial
}

/// Passivity on both sides of Colgate's bound 2b/T: half of it decays,
/// twice it grows (the bound is close to tight for a damped mass whose
/// bT/m is small, here 0.05).
#[test]
fn a_sampled_wall_is_passive_below_colgates_bound_and_grows_above_it() {
    let p = VirtualParams::default();
    let bound = colgate_bound_n_per_m(p.damping_n_s_per_m, 0.0, p.loop_period);
    assert_eq!(bound, p.info().limits.stable_stiffness_1khz_n_per_m);
    let below = wall_growth(0.5 * bound);
    let above = wall_growth(2.0 * bound);
    assert!(below < 1.0, "energy grew at half the bound: ratio {below}");
    assert!(
        above > 1.0,
        "energy did not grow at twice the bound: ratio {above}"
    );
    // The scenes' 400 N/m coupling is far inside.
    assert!(wall_growth(400.0) < 1e-2);
}

/// A recorded reading's counts rebuild the very reading (what replay does).
#[test]
fn counts_rebuild_the_live_reading_bit_for_bit() {
    let (mut d, pointer) = device();
    pointer.set(&Vector3::new(0.0123, -0.0456, 0.0789));
    for k in 1..50u64 {
        let now = Duration::from_millis(k);
        let r = d.read(now).unwrap();
        assert_eq!(VirtualParams::reading_from_counts(&r.joint_counts, now), r);
        d.write(Vector3::new(0.1, 0.0, -0.2), now).unwrap();
    }
}

/// The force is clamped to the peak with its direction kept; a non-finite
/// force and a stop leave nothing applied to the tip.
#[test]
fn force_is_clamped_and_a_stop_or_a_nan_applies_nothing() {
    let (mut d, _pointer) = device();
    let now = Duration::from_millis(1);
    let r = d.write(Vector3::new(30.0, 40.0, 0.0), now).unwrap();
    assert!(r.saturated);
    assert!((r.force_n_device - Vector3::new(6.0, 8.0, 0.0)).norm() < 1e-12);
    assert_eq!(d.applied_torque_nm(), Some(Vector3::new(6.0, 8.0, 0.0)));
    d.motors_off(Duration::from_millis(2));
    assert_eq!(d.applied_torque_nm(), Some(Vector3::zeros()));
    d.write(Vector3::new(1.0, 0.0, 0.0), Duration::from_millis(3))
        .unwrap();
    let r = d
        .write(Vector3::new(f64::NAN, 0.0, 0.0), Duration::from_millis(4))
        .unwrap();
    assert_eq!(r, MotorReport::off());
    assert_eq!(d.applied_torque_nm(), Some(Vector3::zeros()));
}
