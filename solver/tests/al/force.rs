//! Force feedback against closed forms and the dense reference (Eq. 5–8).
//! Convention: forces are **on the finger**, world frame.

use std::f64::consts::PI;

use haptloop_solver::force::body_wrench;
use haptloop_solver::mechanisms::{four_bar, stewart};
use haptloop_solver::{FingerTarget, SolverSettings, reference_finger_wrenches};
use nalgebra::{Vector3, Vector4};

use crate::common::*;

fn g() -> Vector3<f64> {
    Vector3::from(G)
}

#[test]
fn free_body_hanging_from_a_point_finger_pulls_it_down_with_m_g() {
    let model = free_body([0.0; 3], false);
    let targets = model.initial_targets();
    let mut p = program(model, SolverSettings::default());
    hold(&mut p, &targets, 5);
    let o = p.finger_outputs()[0];
    let expected = g() * 0.5;
    assert!(
        rel(&o.constraint_force_n, &expected) < 1e-9,
        "{:?}",
        o.constraint_force_n
    );
    assert!(rel(&o.force_n, &expected) < 1e-9, "{:?}", o.force_n);
    assert!(o.torque_nm.norm() < 1e-12);
}

/// A body carried along x(t) = x0 + A (sin ωt, 0, ½ sin 2ωt): the finger
/// feels F = m (g − a(t)). Accelerations are backward differences of q (one
/// tick old, O(dt²) accurate there) and the body trails the target by a
/// fraction of a tick, so the error is bounded by m |ȧ|max · 2 dt.
#[test]
fn carried_body_loads_the_finger_with_m_times_g_minus_a() {
    let model = free_body([0.0; 3], false);
    let x0 = model.initial_targets()[0].position_m;
    let (amp, w, m) = (0.01, 2.0 * PI * 2.0, 0.5);
    let pos = |t: f64| x0 + Vector3::new((w * t).sin(), 0.0, 0.5 * (2.0 * w * t).sin()) * amp;
    let acc =
        |t: f64| Vector3::new(-(w * t).sin(), 0.0, -2.0 * (2.0 * w * t).sin()) * (amp * w * w);
    let jerk_max = amp * w.powi(3) * (1.0f64 + 4.0).sqrt();
    let bound = m * jerk_max * 2.0 * DT.as_secs_f64();
    let settings = SolverSettings {
        iterations: 16,
        ..SolverSettings::default()
    };
    let mut p = program(model, settings);
    let mut worst = 0.0f64;
    for k in 0..1000 {
        let t = k as f64 * DT.as_secs_f64();
        let r = p.tick(&[FingerTarget::at(pos(t))], DT);
        assert_eq!(r.status, haptloop_solver::TickOutcome::Ok);
        if k >= 100 {
            let err = (p.finger_outputs()[0].constraint_force_n - (g() - acc(t)) * m).norm();
            worst = worst.max(err);
        }
    }
    // The bound is about 1 % of the 6 N load; the error must stay inside it
    // and must not be trivially zero either (then the test measures nothing).
    assert!(worst < bound, "worst {worst} N, bound {bound} N");
    assert!(worst > 1e-3 * bound);
}

/// A pendulum held still at θ: the finger force balances the gravity torque
/// about the hinge and, being the smallest load that does, is tangential.
#[test]
fn pendulum_finger_balances_the_gravity_torque() {
    for theta in [0.3, 1.0, 2.0] {
        let model = pendulum(theta, None);
        let targets = model.initial_targets();
        let mut p = program(model, SolverSettings::default());
        hold(&mut p, &targets, 5);
        let f = p.finger_outputs()[0].constraint_force_n;
        let d = arm_dir(theta);
        let y = Vector3::y();
        let tau_gravity = (d * L_C).cross(&(g() * ARM_KG)).dot(&y);
        let tau_finger = (d * L_F).cross(&-f).dot(&y);
        let scale = ARM_KG * 9.81 * L_C;
        assert!(
            (tau_gravity + tau_finger).abs() < 1e-9 * scale,
            "θ {theta}: {tau_gravity} vs {tau_finger}"
        );
        assert!(f.dot(&d).abs() < 1e-9 * f.norm() && f.dot(&y).abs() < 1e-9 * f.norm());
        let expected = ARM_KG * 9.81 * L_C * theta.sin() / L_F;
        assert!(
            (f.norm() - expected).abs() < 1e-9 * expected,
            "{} vs {expected}",
            f.norm()
        );
    }
}

/// The four-bar held still under gravity: the fast path (sparse Cholesky,
/// Schur complement) equals the dense null-space reference.
#[test]
fn four_bar_static_force_matches_the_dense_reference() {
    let model = four_bar();
    let targets = model.initial_targets();
    let mut p = program(model, SolverSettings::default());
    hold(&mut p, &targets, 5);
    let zeros = vec![0.0; p.model().n_coords()];
    let reference = reference_finger_wrenches(p.model(), p.q(), &zeros, &zeros).unwrap();
    let (f, f_ref) = (
        p.finger_outputs()[0].constraint_force_n,
        reference[0].force_n,
    );
    assert!(f_ref.norm() > 0.01, "a real load: {f_ref}");
    assert!(rel(&f, &f_ref) < 1e-6, "{f} vs {f_ref}");
}

/// The Stewart platform's rigid finger: force and torque (about the grasp
/// point) against the reference; the finger holds everything, so the force is
/// the weight of the platform plus its share of the legs'.
#[test]
fn stewart_rigid_grasp_force_and_torque_match_the_reference() {
    let model = stewart();
    let targets = model.initial_targets();
    let mut p = program(model, SolverSettings::default());
    hold(&mut p, &targets, 5);
    let zeros = vec![0.0; p.model().n_coords()];
    let reference = reference_finger_wrenches(p.model(), p.q(), &zeros, &zeros).unwrap();
    let o = p.finger_outputs()[0];
    assert!(rel(&o.constraint_force_n, &reference[0].force_n) < 1e-6);
    let scale = reference[0].force_n.norm() * 0.1;
    assert!((o.constraint_torque_nm - reference[0].torque_nm).norm() < 1e-6 * scale);
    // Vertical load between the platform's weight (150 g) and the whole
    // mechanism's (0.42 kg: the base joints carry part of the legs).
    let platform: f64 = 0.15;
    let whole: f64 = p
        .model()
        .bodies()
        .iter()
        .filter(|b| !b.fixed)
        .map(|b| b.mass_kg)
        .sum();
    assert!((whole - 0.42).abs() < 1e-9, "{whole}");
    let fz = -o.constraint_force_n.z;
    assert!(fz > platform * 9.81 && fz < whole * 9.81, "{fz}");
}

/// Eq. 8 by virtual work, for a non-unit e: a generalized force W_c on a
/// body's columns does the same work on any δq as the world force and torque
/// `body_wrench` returns do on δr and δθ = Ω δe.
#[test]
fn eq8_factor_by_virtual_work() {
    let mut rng = Lcg(11);
    for _ in 0..20 {
        let e = [1.0 + 0.3 * rng.next(), rng.next(), rng.next(), rng.next()];
        let w_c: [f64; 7] = std::array::from_fn(|_| rng.next());
        let de = Vector4::from_fn(|_, _| rng.next());
        let dr = Vector3::from_fn(|_, _| rng.next());
        // Keep δe off the norm direction (Ω e = 0): only rotations do work.
        let ev = Vector4::from(e);
        let de = de - ev * (ev.dot(&de) / ev.norm_squared());
        let omega = haptloop_solver::rotation::angular_map(e).unwrap();
        let dtheta = omega * de;
        let (f, tau) = body_wrench(e, &w_c).unwrap();
        let work_generalized = dr.dot(&Vector3::new(w_c[0], w_c[1], w_c[2]))
            + de.dot(&Vector4::new(w_c[3], w_c[4], w_c[5], w_c[6]));
        let work_world = f.dot(&dr) + tau.dot(&dtheta);
        assert!(
            (work_generalized - work_world).abs() < 1e-12,
            "{work_generalized} vs {work_world}"
        );
    }
}

/// Q_v: a body spun at constant ω about a non-principal axis needs the
/// gyroscopic torque ω × J_w ω; the rigid finger supplies it, so the torque
/// on the finger is its negative. Exact q̇, q̈ through the reference.
#[test]
fn spinning_body_needs_the_gyroscopic_torque() {
    let model = free_body([0.0; 3], true);
    let q = model.q0().to_vec();
    let e = Vector4::new(q[3], q[4], q[5], q[6]);
    let w = Vector3::new(3.0, -2.0, 5.0);
    // ė = ½ ω ⊗ e (world ω); ë = ½ ω ⊗ ė for constant ω.
    let mul = |a: &Vector3<f64>, b: &Vector4<f64>| {
        let (bw, bv) = (b[0], Vector3::new(b[1], b[2], b[3]));
        let v = bv * 0.0 + a * bw + a.cross(&bv);
        Vector4::new(-a.dot(&bv), v.x, v.y, v.z) * 0.5
    };
    let (e_dot, e_ddot) = (mul(&w, &e), mul(&w, &mul(&w, &e)));
    let mut q_dot = vec![0.0; 7];
    let mut q_ddot = vec![0.0; 7];
    q_dot[3..].copy_from_slice(e_dot.as_slice());
    q_ddot[3..].copy_from_slice(e_ddot.as_slice());
    let out = reference_finger_wrenches(&model, &q, &q_dot, &q_ddot).unwrap();
    let r = model.body_rotation(&q, haptloop_solver::BodyId(0)).unwrap();
    let j_w = r * nalgebra::Matrix3::from_diagonal(&Vector3::new(2e-3, 3e-3, 4e-3)) * r.transpose();
    let needed = w.cross(&(j_w * w));
    assert!(needed.norm() > 1e-3);
    assert!(
        (out[0].torque_nm + needed).norm() < 1e-9 * needed.norm(),
        "{} vs {}",
        out[0].torque_nm,
        -needed
    );
    assert!(rel(&out[0].force_n, &(g() * 0.5)) < 1e-12);
}
