//! Reported values against closed forms, and the dexterity guard at
//! singular poses: finite values, finite (here zero) gradients.

use haptloop_solver::{
    BodySpec, JointKind as K, JointSpec, Model, ModelBuilder, ObjectiveSpec, objective::DET_FLOOR,
};

use crate::common::{self, gradient};

fn reports(model: &Model, q: &[f64]) -> Vec<f64> {
    let mut ev = model.objective_evaluation();
    let mut out = vec![0.0; model.objectives().terms.len()];
    ev.reports(model, q, &mut out).unwrap();
    out
}

/// A planar 2R arm (links l1, l2, elbow θ) in the xy plane, dexterity in x
/// and y: det J = l1 l2 sin θ, so Eq. 14 gives f = R² / (l1 l2 |sin θ|)
/// with R = l1 + l2 (J̃ = J / R).
fn planar(theta: f64) -> Model {
    let (l1, l2) = (0.3, 0.2);
    let mut b = ModelBuilder::new();
    b.body(BodySpec::fixed("ground"));
    b.body(BodySpec::new("upper").at([l1 / 2.0, 0.0, 0.0]));
    let (s, c) = theta.sin_cos();
    let q = nalgebra::UnitQuaternion::from_axis_angle(&nalgebra::Vector3::z_axis(), theta);
    let q = q.quaternion();
    b.body(
        BodySpec::new("fore")
            .at([l1 + c * l2 / 2.0, s * l2 / 2.0, 0.0])
            .oriented([q.w, q.i, q.j, q.k]),
    );
    let z = [0.0, 0.0, 1.0];
    b.joint(
        JointSpec::new(K::Revolute, "ground", "upper")
            .anchors([0.0; 3], [-l1 / 2.0, 0.0, 0.0])
            .axes(z, z),
    );
    b.joint(
        JointSpec::new(K::Revolute, "upper", "fore")
            .anchors([l1 / 2.0, 0.0, 0.0], [-l2 / 2.0, 0.0, 0.0])
            .axes(z, z),
    );
    b.objective(ObjectiveSpec::Dexterity {
        name: None,
        weight: 1.0,
        chain: ["ground", "upper", "fore"].map(String::from).to_vec(),
        point_m: [l2 / 2.0, 0.0, 0.0],
        directions: vec![[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
    });
    b.build().unwrap()
}

#[test]
fn dexterity_of_a_planar_2r_arm_is_eq_14() {
    for theta in [0.3f64, 1.0, std::f64::consts::FRAC_PI_2, 2.5] {
        let m = planar(theta);
        let f = reports(&m, m.q0())[0];
        let det = (0.3 * 0.2 * theta.sin() / 0.25).powi(2);
        let expected = 1.0 / (det + DET_FLOOR).sqrt();
        assert!(
            (f - expected).abs() < 1e-9 * expected,
            "θ = {theta}: f = {f}, closed form {expected}"
        );
    }
    // Bent at 90° is the most dexterous: f grows toward both ends.
    let at = |t| reports(&planar(t), planar(t).q0())[0];
    assert!(at(std::f64::consts::FRAC_PI_2) < at(1.0) && at(1.0) < at(0.3));
}

/// At a singular pose (the arm outstretched; the planar arm straight) the
/// value is finite and at most 1/√ε, and the gradient is finite: zero for a
/// square J (det G = det² J is stationary there), bounded otherwise.
#[test]
fn dexterity_is_finite_at_singular_poses() {
    for m in [planar(0.0), planar(std::f64::consts::PI)] {
        let f = reports(&m, m.q0())[0];
        assert!(
            f.is_finite() && f <= 1.0 / DET_FLOOR.sqrt() + 1e-6,
            "f = {f}"
        );
        assert!(f > 0.5 / DET_FLOOR.sqrt(), "not singular: f = {f}");
        let (g, value) = gradient(&m, m.q0());
        assert!(value.is_finite());
        assert!(g.iter().all(|v| v.is_finite() && v.abs() < 1e-9), "{g:?}");
    }
    // The spatial arm outstretched (elbow 0): rank 2 of 3.
    let mut b = common::arm(0.0);
    b.objective(ObjectiveSpec::Dexterity {
        name: None,
        weight: 1.0,
        chain: ["base", "turret", "upper", "fore"]
            .map(String::from)
            .to_vec(),
        point_m: [0.125, 0.0, 0.0],
        directions: Vec::new(),
    });
    let m = b.build().unwrap();
    let (g, value) = gradient(&m, m.q0());
    assert!(value.is_finite() && g.iter().all(|v| v.is_finite()));
    // Nearly singular (elbow 1e-5 rad): bounded by ½ R² |∂ det| / ε, no blow-up.
    let mut b = common::arm(1e-5);
    b.objective(ObjectiveSpec::Dexterity {
        name: None,
        weight: 1.0,
        chain: ["base", "turret", "upper", "fore"]
            .map(String::from)
            .to_vec(),
        point_m: [0.125, 0.0, 0.0],
        directions: Vec::new(),
    });
    let m = b.build().unwrap();
    let (g, _) = gradient(&m, m.q0());
    let largest = g.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    assert!(
        largest.is_finite() && largest < 1e3,
        "largest gradient entry {largest}"
    );
}

#[test]
fn straight_line_and_joint_limit_values() {
    let m = common::straight_line();
    // The point [0.05, -0.03, 0.02] of `a` against the line through
    // (0, 0.1, 0) along (1, 0.5, 0): distance from the closed form.
    let p = m.body_position(m.q0(), m.body_id("a").unwrap()).unwrap()
        + m.body_rotation(m.q0(), m.body_id("a").unwrap()).unwrap()
            * nalgebra::Vector3::new(0.05, -0.03, 0.02);
    let d = p - nalgebra::Vector3::new(0.0, 0.1, 0.0);
    let u = nalgebra::Vector3::new(1.0, 0.5, 0.0).normalize();
    let expected = (d - u * u.dot(&d)).norm();
    assert!((reports(&m, m.q0())[0] - expected).abs() < 1e-15);
    // The joints' coordinates from their limit rows (x − lo ≥ 0, hi − x ≥ 0):
    // the report is the RMS of |x − mid| / half over the three joints.
    let m = common::joint_limits();
    let mut ev = m.evaluation();
    ev.evaluate(&m, m.q0(), &m.initial_targets()).unwrap();
    let t: Vec<f64> = m
        .constraints()
        .iter()
        .filter(|c| c.limits.is_some())
        .map(|c| {
            let (a, b) = (ev.values()[c.rows.start], ev.values()[c.rows.start + 1]);
            // a = x − lo, b = hi − x: (x − mid) / half = (a − b) / (a + b).
            (a - b) / (a + b)
        })
        .collect();
    assert_eq!(t.len(), 3);
    let rms = (t.iter().map(|x| x * x).sum::<f64>() / 3.0).sqrt();
    let r = reports(&m, m.q0())[0];
    assert!((r - rms).abs() < 1e-12, "{r} vs {rms}");
}
