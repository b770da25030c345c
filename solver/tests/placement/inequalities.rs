//! Slack inequalities (Eq. 17): at the solution every inequality holds
//! (C_j ≥ −tolerance), active rows push (λ_j ≤ 0 in the fast loop's sign
//! convention W(q − q_ref) + C_qᵀλ = 0), inactive rows have λ_j = 0 and
//! Y_j² = C_j, and the KKT stationarity holds.

use haptloop_solver::{
    BodySpec, ConstraintKind, JointKind, JointSpec, Model, ModelBuilder, Placement,
    PlacementOptions, PlaneOwner, PointPlaneSpec, SolveStatus,
};
use nalgebra::{UnitQuaternion, Vector3};

use super::common::finite;

/// Checks every inequality claim and returns the indices of active rows.
fn check_kkt(model: &Model, p: &Placement, q: &[f64], q_ref: &[f64]) -> Vec<usize> {
    let mut ev = model.evaluation();
    ev.evaluate(model, q, &model.initial_targets()).unwrap();
    let (c, lam, ineq) = (ev.values(), p.multipliers(), model.inequality_rows());
    let mut active = Vec::new();
    for (j, row) in ineq.clone().enumerate() {
        let (phi, l, y) = (c[row], lam[row], p.slacks()[j]);
        assert!(phi >= -1e-9, "row {row}: C = {phi:e} < 0");
        assert!(l <= 1e-12, "row {row} pulls: λ = {l:e}");
        assert!((l * phi).abs() <= 1e-12, "row {row}: λC = {:e}", l * phi);
        assert!(
            (y * y - phi).abs() <= 1e-9,
            "row {row}: Y² = {:e}, C = {phi:e}",
            y * y
        );
        if phi <= 1e-9 {
            active.push(row);
        } else {
            assert!(l.abs() <= 1e-12, "inactive row {row} has λ = {l:e}");
        }
    }
    // Stationarity: (q − q_ref) + C_qᵀλ = 0.
    let mut g = vec![0.0; model.n_coords()];
    ev.jacobian().mul_t_vec(lam, &mut g).unwrap();
    let worst = g
        .iter()
        .zip(q.iter().zip(q_ref))
        .map(|(g, (a, b))| (g + a - b).abs());
    assert!(worst.fold(0.0, f64::max) <= 1e-9);
    assert!(finite(q) && finite(lam));
    active
}

/// A 10 cm arm on a hinge about world z at the origin, limited to ±0.5 rad.
fn pendulum() -> Model {
    let mut b = ModelBuilder::new();
    b.body(BodySpec::fixed("ground"));
    b.body(BodySpec::new("arm").at([0.1, 0.0, 0.0]));
    b.joint(
        JointSpec::new(JointKind::Revolute, "ground", "arm")
            .anchors([0.0; 3], [-0.1, 0.0, 0.0])
            .axes([0.0, 0.0, 1.0], [0.0, 0.0, 1.0])
            .limits(-0.5, 0.5),
    );
    b.build().unwrap()
}

#[test]
fn a_joint_limit_stops_the_arm_and_pushes() {
    let model = pendulum();
    // The reference wants the arm at 0.8 rad, beyond the upper limit.
    let a = 0.8f64;
    let q_ref = vec![
        0.1 * a.cos(),
        0.1 * a.sin(),
        0.0,
        (a / 2.0).cos(),
        0.0,
        0.0,
        (a / 2.0).sin(),
    ];
    let mut p = Placement::analyze(&model, &PlacementOptions::default()).unwrap();
    let mut q = q_ref.clone();
    let info = p.solve(&model, &mut q, &q_ref, &[]).unwrap();
    assert_eq!(info.status, SolveStatus::Converged, "{info:?}");
    let active = check_kkt(&model, &p, &q, &q_ref);
    let limits = model
        .constraints()
        .iter()
        .find(|c| c.kind == ConstraintKind::RevoluteLimit);
    let rows = limits.unwrap().rows.clone();
    assert_eq!(active, vec![rows.start + 1], "only hi − x ≥ 0 is active");
    assert!(
        p.multipliers()[rows.start + 1] < -1e-4,
        "the limit pushes back"
    );
    let angle = q[1].atan2(q[0]);
    assert!((angle - 0.5).abs() <= 1e-9, "arm at {angle} rad");
    let lo = p.slacks()[0];
    assert!((lo * lo - 1.0).abs() <= 1e-9, "lower slack² = x − lo = 1");
}

/// A 4 × 4 × 2 cm box whose four bottom corners must stay above the world
/// plane z = 0.
fn box_on_plane() -> Model {
    let mut b = ModelBuilder::new();
    b.body(BodySpec::new("box").at([0.0, 0.0, 0.01]));
    let model = b.build().unwrap();
    let body = model.body_id("box").unwrap();
    let corners: Vec<PointPlaneSpec> = [[1.0, 1.0], [1.0, -1.0], [-1.0, 1.0], [-1.0, -1.0]]
        .iter()
        .enumerate()
        .map(|(k, [x, y])| PointPlaneSpec {
            name: format!("corner{k}"),
            body,
            point_m: [0.02 * x, 0.02 * y, -0.01],
            plane: PlaneOwner::World,
            plane_point_m: [0.0; 3],
            normal: [0.0, 0.0, 1.0],
        })
        .collect();
    model.with_inequalities(&corners).unwrap()
}

#[test]
fn a_sunk_tilted_box_is_lifted_onto_the_plane() {
    let model = box_on_plane();
    // Reference: 5 mm into the plane, tilted 5° about x.
    let tilt = UnitQuaternion::from_axis_angle(&Vector3::x_axis(), 5f64.to_radians());
    let e = tilt.quaternion();
    let q_ref = vec![0.0, 0.0, 0.005, e.w, e.i, e.j, e.k];
    let mut p = Placement::analyze(&model, &PlacementOptions::default()).unwrap();
    let mut q = q_ref.clone();
    let info = p.solve(&model, &mut q, &q_ref, &[]).unwrap();
    assert_eq!(info.status, SolveStatus::Converged, "{info:?}");
    let active = check_kkt(&model, &p, &q, &q_ref);
    assert!(!active.is_empty(), "the box rests on the plane");
    assert!(q[2] > 0.005, "lifted");
}

#[test]
fn a_box_above_the_plane_is_not_touched() {
    let model = box_on_plane();
    let q_ref = vec![0.003, 0.0, 0.05, 1.0, 0.0, 0.0, 0.0];
    let mut p = Placement::analyze(&model, &PlacementOptions::default()).unwrap();
    let mut q = q_ref.clone();
    let info = p.solve(&model, &mut q, &q_ref, &[]).unwrap();
    assert_eq!(info.status, SolveStatus::Converged, "{info:?}");
    assert!(check_kkt(&model, &p, &q, &q_ref).is_empty());
    let moved = q
        .iter()
        .zip(&q_ref)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(moved <= 1e-12, "moved {moved:e}");
}
