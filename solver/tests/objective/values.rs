//! Reported values against closed forms, and the dexterity guard at
//! singular poses: finite values, finite (here zero) gradients.

use haptloop_solver::{
    BodySpec, JointKind as K, JointSpec, ModelBuilder, ObjectiveSpec, objective::DET_FLOOR,
};

use crate::common::{self, Designed, Designer, gradient};

fn reports(model: &Designed, q: &[f64]) -> Vec<f64> {
    let mut ev = model.objectives.evaluation(model);
    let mut out = vec![0.0; model.objectives.terms.len()];
    ev.reports(model, q, &mut out).unwrap();
    out
}

/// A planar 2R arm (links l1, l2, elbow θ) in the xy plane, dexterity in x
/// and y: det J = l1 l2 sin θ, so Eq. 14 gives f = R² / (l1 l2 |sin θ|)
/// with R = l1 + l2 (J̃ = J / R).
fn planar(theta: f64) -> Designed {
    planar_with(theta, [0.1, 0.0, 0.0], Vec::new())
}

/// [`planar`] with its point x at `point` on the forearm and angular rows.
fn planar_with(theta: f64, point_m: [f64; 3], angular_directions: Vec<[f64; 3]>) -> Designed {
    let (l1, l2) = (0.3, 0.2);
    let mut b = Designer::new();
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
        point_m,
        directions: vec![[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
        angular_directions,
        closure: Vec::new(),
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
        angular_directions: Vec::new(),
        closure: Vec::new(),
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
        angular_directions: Vec::new(),
        closure: Vec::new(),
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

/// Eq. 13 with its angular row: the planar 2R arm's J̃ has the rows
/// d·(z × (x − o))/R for x and y and the angular row z·z = 1 per joint;
/// three rows on two columns, so G = J̃ᵀ J̃ and, by Cauchy–Binet, det G is
/// the sum of the squared 2 × 2 minors: (l1 l2 sin θ / R²)² + (l1 / R)²
/// (the linear pair, and each linear row with the angular one).
#[test]
fn dexterity_with_an_angular_row_is_cauchy_binet_of_eq_13() {
    for theta in [0.0f64, 0.4, 1.3, 2.8] {
        let m = planar_with(theta, [0.1, 0.0, 0.0], vec![[0.0, 0.0, 1.0]]);
        let (l1, l2) = (0.3, 0.2);
        let r = l1 + l2;
        let det = (l1 * l2 * theta.sin() / (r * r)).powi(2) + (l1 / r).powi(2);
        let f = reports(&m, m.q0())[0];
        let want = 1.0 / (det + DET_FLOOR).sqrt();
        assert!((f - want).abs() < 1e-12 * want, "θ {theta}: {f} vs {want}");
    }
}

/// A planar four-bar A–B–C–D (revolutes about z) as a closed chain, the
/// point x on the coupler BC, one task direction d: G = (J̃ n)², n the unit
/// joint-rate vector that keeps the loop closed. Computed here
/// independently in the plane: each revolute at p turns the bodies after it
/// with planar twist (1, p_y, −p_x) (ω, v at the origin); n spans the null
/// space of the 3 × 4 loop matrix (SVD); J̃ = d · (z × (x − p)) / R over
/// the path joints A, B, R = |AB| + |Bx|.
#[test]
fn dexterity_of_a_closed_planar_four_bar_matches_a_planar_null_space() {
    use nalgebra::{DMatrix, Vector3};
    let (pa, pb, pc, pd) = (
        Vector3::new(0.0, 0.0, 0.0),
        Vector3::new(0.03, 0.04, 0.0),
        Vector3::new(0.12, 0.06, 0.0),
        Vector3::new(0.10, 0.0, 0.0),
    );
    let x = (pb + pc) / 2.0 + Vector3::new(0.0, 0.01, 0.0);
    let d = Vector3::new(0.6, 0.8, 0.0);
    let mut b = Designer::new();
    b.body(BodySpec::fixed("ground"));
    let rod = |b: &mut ModelBuilder, name: &str, p: Vector3<f64>, q: Vector3<f64>| {
        b.body(BodySpec::new(name).at(((p + q) / 2.0).into()));
    };
    rod(&mut b, "crank", pa, pb);
    rod(&mut b, "coupler", pb, pc);
    rod(&mut b, "rocker", pd, pc);
    let z = [0.0, 0.0, 1.0];
    let joint = |b: &mut ModelBuilder,
                 i: &str,
                 j: &str,
                 ci: Vector3<f64>,
                 cj: Vector3<f64>,
                 at: Vector3<f64>| {
        b.joint(
            JointSpec::new(K::Revolute, i, j)
                .anchors((at - ci).into(), (at - cj).into())
                .axes(z, z),
        );
    };
    let (c_crank, c_coupler, c_rocker) = ((pa + pb) / 2.0, (pb + pc) / 2.0, (pd + pc) / 2.0);
    joint(&mut b, "ground", "crank", Vector3::zeros(), c_crank, pa);
    joint(&mut b, "crank", "coupler", c_crank, c_coupler, pb);
    joint(&mut b, "coupler", "rocker", c_coupler, c_rocker, pc);
    joint(&mut b, "rocker", "ground", c_rocker, Vector3::zeros(), pd);
    b.objective(ObjectiveSpec::Dexterity {
        name: None,
        weight: 1.0,
        chain: ["ground", "crank", "coupler"].map(String::from).to_vec(),
        point_m: (x - c_coupler).into(),
        directions: vec![d.into()],
        angular_directions: Vec::new(),
        closure: ["rocker", "ground"].map(String::from).to_vec(),
    });
    let m = b.build().unwrap();
    let f = reports(&m, m.q0())[0];
    let pts = [pa, pb, pc, pd];
    let h = DMatrix::from_fn(3, 4, |r, c| match r {
        0 => 1.0,
        1 => pts[c].y,
        _ => -pts[c].x,
    });
    // The null vector of a rank-3 3 × 4 matrix: its signed 3 × 3 minors.
    let minor = |c: usize| {
        let cols: Vec<usize> = (0..4).filter(|&k| k != c).collect();
        DMatrix::from_fn(3, 3, |r, k| h[(r, cols[k])]).determinant()
    };
    let mut n: Vec<f64> = (0..4)
        .map(|c| if c % 2 == 0 { minor(c) } else { -minor(c) })
        .collect();
    let norm = n.iter().map(|v| v * v).sum::<f64>().sqrt();
    n.iter_mut().for_each(|v| *v /= norm);
    assert!((&h * nalgebra::DVector::from_vec(n.clone())).norm() < 1e-15);
    let r = (pb - pa).norm() + (x - pb).norm();
    let perp = |p: Vector3<f64>| d.dot(&Vector3::z().cross(&(x - p))) / r;
    let jn = perp(pa) * n[0] + perp(pb) * n[1];
    let want = 1.0 / (jn * jn + DET_FLOOR).sqrt();
    assert!((f - want).abs() < 1e-9 * want, "{f} vs {want}");
}

/// Eq. 15 as written follows the nearest point only: F = L³ / d_min, its
/// report d_min; the smooth `obstacle` barrier is zero beyond its
/// activation distance where this one still pulls.
#[test]
fn inverse_distance_is_the_nearest_points_inverse() {
    let m = common::inverse_distance();
    let q = m.q0();
    let o = nalgebra::Vector3::new(0.05, 0.05, 0.1);
    let pts = [
        ("a", [0.05, 0.0, 0.0]),
        ("b", [0.0, -0.05, 0.02]),
        ("ground", [0.02, 0.02, 0.0]),
    ];
    let d_min = pts
        .iter()
        .map(|(b, p)| {
            let id = m.body_id(b).unwrap();
            let w = m.body_rotation(q, id).unwrap() * nalgebra::Vector3::from(*p)
                + m.body_position(q, id).unwrap();
            (w - o).norm()
        })
        .fold(f64::INFINITY, f64::min);
    assert!((reports(&m, q)[0] - d_min).abs() < 1e-15);
    let l = m.characteristic_length_m();
    let (_, f) = gradient(&m, q);
    assert!((f - 0.8 * l.powi(3) / d_min).abs() < 1e-12 * f, "{f}");
}

/// Two links (0.3 and 0.1 m) reach the shell between 0.2 and 0.4 m:
/// V = 4/3 π (0.4³ − 0.2³); F starts at 0 and falls as a link lengthens.
#[test]
fn workspace_volume_of_two_links_is_the_shell_between_their_sum_and_difference() {
    let mut b = Designer::new();
    b.body(BodySpec::fixed("ground"));
    b.body(BodySpec::new("upper").at([0.15, 0.0, 0.0]));
    b.body(BodySpec::new("fore").at([0.35, 0.0, 0.0]));
    b.joint(JointSpec::new(K::Spherical, "ground", "upper").anchors([0.0; 3], [-0.15, 0.0, 0.0]));
    b.joint(
        JointSpec::new(K::Revolute, "upper", "fore")
            .anchors([0.15, 0.0, 0.0], [-0.05, 0.0, 0.0])
            .axes([0.0, 0.0, 1.0], [0.0, 0.0, 1.0])
            .free(&[haptloop_solver::DesignParam::AnchorI]),
    );
    b.objective(ObjectiveSpec::WorkspaceVolume {
        name: None,
        weight: 1.0,
        chain: ["ground", "upper", "fore"].map(String::from).to_vec(),
        point_m: [0.05, 0.0, 0.0],
    });
    let m = b.build().unwrap();
    let want = 4.0 / 3.0 * std::f64::consts::PI * (0.4f64.powi(3) - 0.2f64.powi(3));
    let v = reports(&m, m.q0())[0];
    assert!((v - want).abs() < 1e-15, "{v} vs {want}");
    let (g, f) = gradient(&m, m.q0());
    assert!(f.abs() < 1e-15);
    // Lengthening the upper link (its anchor's x) grows the shell's outer
    // radius and its inner one alike: dV/dl₁ = 4π (0.4² − 0.2²) > 0.
    let col = m.layout().body_coords();
    let l = m.characteristic_length_m();
    let want = -(l * l / 3.0) * 4.0 * std::f64::consts::PI * (0.16 - 0.04) / v;
    assert!(
        (g[col] - want).abs() < 1e-12 * want.abs(),
        "{} vs {want}",
        g[col]
    );
}
