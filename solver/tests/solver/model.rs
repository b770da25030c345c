//! Model-level behaviour: layout, q0, row metadata, joint-coordinate
//! conventions, the rotation form's scale invariance, derived models and
//! evaluation errors.

use haptloop_solver::{
    BodySpec, ConstraintId, ConstraintKind, DEFAULT_INERTIA_RADIUS_M, DesignParam as P, EvalError,
    FingerId, FingerTarget, JointKind as K, JointSpec, ModelBuilder, PlaneOwner, PointPlaneSpec,
    RowUnit, Sense,
};
use nalgebra::{UnitQuaternion, Vector3};

use crate::common::{self, initial_residual};
use crate::fd::values;

#[test]
fn layout_puts_bodies_then_design_vars() {
    let m = common::distance();
    let l = m.layout();
    let [ground, a, b] = ["ground", "a", "b"].map(|n| m.body_id(n).unwrap());
    assert_eq!(l.body_offset(ground), None);
    assert_eq!((l.body_offset(a), l.body_offset(b)), (Some(0), Some(7)));
    assert_eq!(l.body_coords(), 14);
    let names: Vec<_> = l
        .design_vars()
        .iter()
        .map(|d| (d.name.as_str(), d.offset, d.width))
        .collect();
    assert_eq!(
        names,
        [
            ("#1.length", 14, 1),
            ("#1.anchor_i", 15, 3),
            ("#1.anchor_j", 18, 3)
        ]
    );
    assert_eq!(m.n_coords(), 21);
    assert_eq!(&m.q0()[14..21], &[0.4, 0.1, -0.05, 0.2, -0.15, 0.1, 0.05]);
    let id = l.design_var_id("#1.anchor_j").unwrap();
    assert_eq!(l.design_var_range(id), Some(18..21));
    // q0 holds the normalised initial quaternion of `a`.
    let e = &m.q0()[3..7];
    assert!((e.iter().map(|v| v * v).sum::<f64>() - 1.0).abs() < 1e-15);
}

#[test]
fn row_metadata_orders_equalities_first_with_units() {
    let m = common::revolute();
    let units: Vec<_> = m.rows()[m.constraints()[0].rows.clone()]
        .iter()
        .map(|r| r.unit)
        .collect();
    use RowUnit::{Angle, Length};
    assert_eq!(units, [Length, Length, Length, Angle, Angle]);
    let eq = m.equality_rows();
    assert!(
        m.rows()[eq.clone()]
            .iter()
            .all(|r| r.sense == Sense::Equality)
    );
    assert!(
        m.rows()[m.inequality_rows()]
            .iter()
            .all(|r| r.sense == Sense::Inequality)
    );
    let limit = &m.constraints()[m.rows()[eq.end].constraint.index()];
    assert_eq!(
        (limit.kind, limit.limits, limit.name.as_str()),
        (
            ConstraintKind::RevoluteLimit,
            Some(ConstraintId(0)),
            "#1.limits"
        )
    );
    let norm = m.constraint_id("a.norm").unwrap();
    assert_eq!(
        m.rows()[m.constraints()[norm.index()].rows.start].unit,
        RowUnit::Dimensionless
    );
}

/// A hinge about world z between fixed ground and `arm`, with limits, and a
/// slider along world x; the arm is then rotated/moved by known amounts.
#[test]
fn joint_coordinates_follow_the_documented_conventions() {
    let mut b = ModelBuilder::new();
    b.body(BodySpec::fixed("ground"));
    b.body(BodySpec::new("arm").at([0.1, 0.0, 0.0]));
    b.body(BodySpec::new("slide").at([0.0, 0.0, 0.3]));
    b.joint(
        JointSpec::new(K::Revolute, "ground", "arm")
            .anchors([0.0; 3], [-0.1, 0.0, 0.0])
            .axes([0.0, 0.0, 1.0], [0.0, 0.0, 1.0])
            .limits(-0.5, 1.0),
    );
    b.joint(
        JointSpec::new(K::Prismatic, "ground", "slide")
            .anchors([0.0, 0.0, 0.3], [0.0; 3])
            .axes([1.0, 0.0, 0.0], [1.0, 0.0, 0.0])
            .limits(-0.2, 0.4),
    );
    b.joint(JointSpec::new(K::Distance, "arm", "slide").limits(0.1, 1.0));
    let m = b.build().unwrap();
    assert!(initial_residual(&m) < 1e-15);
    let mut q = m.q0().to_vec();
    // Rotate the arm by +0.3 rad about +z around the pivot, slide by +0.05 along +x.
    let rot = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), 0.3);
    let r = rot * Vector3::new(0.1, 0.0, 0.0);
    q[0..3].copy_from_slice(r.as_slice());
    let e = rot.quaternion();
    q[3..7].copy_from_slice(&[e.w, e.i, e.j, e.k]);
    q[7] += 0.05;
    let c = values(&m, &q, &[]);
    let ineq = &c[m.inequality_rows()];
    let length = (Vector3::new(0.05, 0.0, 0.3) - r).norm();
    let expected = [
        0.3 + 0.5,
        1.0 - 0.3,
        0.05 + 0.2,
        0.4 - 0.05,
        length - 0.1,
        1.0 - length,
    ];
    for (v, x) in ineq.iter().zip(expected) {
        assert!((v - x).abs() < 1e-14, "{ineq:?} vs {expected:?}");
    }
    let hinge_and_slider = 0..m.constraints()[1].rows.end;
    assert!(
        c[hinge_and_slider].iter().all(|v| v.abs() < 1e-14),
        "hinge and slider still assembled"
    );
}

#[test]
fn joint_rows_ignore_the_quaternion_scale() {
    let m = common::fixed();
    let (q, targets) = common::state(&m, &vec![0.3; common::state_len(&m)]);
    let mut scaled = q.clone();
    for (_, o) in m.layout().moving_bodies() {
        scaled[o + 3..o + 7].iter_mut().for_each(|v| *v *= 1.7);
    }
    let (c, cs) = (values(&m, &q, &targets), values(&m, &scaled, &targets));
    for (r, info) in m.rows().iter().enumerate() {
        if info.unit != RowUnit::Dimensionless {
            assert!(
                (c[r] - cs[r]).abs() < 1e-14,
                "row {r}: {} vs {}",
                c[r],
                cs[r]
            );
        } else {
            assert!(
                (c[r] - cs[r]).abs() > 0.1,
                "norm row {r} must see the scale"
            );
        }
    }
}

#[test]
fn defaults_for_mass_inertia_and_distance_length() {
    let mut b = common::bodies();
    b.joint(
        JointSpec::new(K::Distance, "a", "b")
            .anchors([0.1, 0.0, 0.0], [0.0; 3])
            .free(&[P::Length]),
    );
    let m = b.build().unwrap();
    let a = &m.bodies()[m.body_id("a").unwrap().index()];
    assert_eq!(a.mass_kg, 1.0);
    let i = 0.4 * DEFAULT_INERTIA_RADIUS_M.powi(2);
    assert_eq!(a.inertia_kg_m2, Vector3::new(i, i, i));
    assert!(
        initial_residual(&m) < 1e-15,
        "default length = initial anchor distance"
    );
}

#[test]
fn derived_model_keeps_ids_and_appends_inequalities() {
    let base = common::revolute();
    let [a, b] = ["a", "b"].map(|n| base.body_id(n).unwrap());
    let spec = PointPlaneSpec {
        name: "w".into(),
        body: a,
        point_m: [0.0; 3],
        plane: PlaneOwner::Body(b),
        plane_point_m: [0.0; 3],
        normal: [0.0, 0.0, 2.0],
    };
    let derived = base
        .with_inequalities(&[
            spec.clone(),
            PointPlaneSpec {
                plane: PlaneOwner::World,
                ..spec
            },
        ])
        .unwrap();
    assert_eq!(
        &derived.constraints()[..base.constraints().len()],
        base.constraints()
    );
    assert_eq!(&derived.rows()[..base.n_rows()], base.rows());
    assert_eq!(derived.equality_rows(), base.equality_rows());
    assert_eq!(derived.n_rows(), base.n_rows() + 2);
    assert_eq!(
        derived.constraints().last().unwrap().kind,
        ConstraintKind::PointPlaneInequality
    );
    let mut ev = base.evaluation();
    assert_eq!(
        ev.evaluate(&derived, derived.q0(), &[]),
        Err(EvalError::ModelMismatch)
    );
}

#[test]
fn evaluation_errors_leave_outputs_untouched() {
    let m = common::fingers();
    let targets = m.initial_targets();
    let mut ev = m.evaluation();
    ev.evaluate(&m, m.q0(), &targets).unwrap();
    let (c, j) = (ev.values().to_vec(), ev.jacobian().values().to_vec());
    let mut q = m.q0().to_vec();
    let n = q.len();
    assert_eq!(
        ev.evaluate(&m, &q[1..], &targets),
        Err(EvalError::CoordinateCount {
            expected: n,
            got: n - 1
        })
    );
    assert_eq!(
        ev.evaluate(&m, &q, &targets[1..]),
        Err(EvalError::TargetCount {
            expected: 2,
            got: 1
        })
    );
    let mut bad = targets.clone();
    bad[1].position_m.y = f64::NAN;
    assert_eq!(
        ev.evaluate(&m, &q, &bad),
        Err(EvalError::NonFiniteTarget {
            finger: FingerId(1)
        })
    );
    q[2] += 0.1;
    q[10..14].fill(0.0);
    assert_eq!(
        ev.evaluate(&m, &q, &targets),
        Err(EvalError::DegenerateQuaternion {
            body: m.body_id("b").unwrap()
        })
    );
    q[10] = 1e200;
    assert_eq!(
        ev.evaluate_values(&m, &q, &targets),
        Err(EvalError::DegenerateQuaternion {
            body: m.body_id("b").unwrap()
        })
    );
    assert_eq!((ev.values(), ev.jacobian().values()), (&c[..], &j[..]));
}

#[test]
fn initial_targets_satisfy_the_finger_rows() {
    let m = common::fingers();
    assert!(initial_residual(&m) < 1e-15);
    let p = m.finger_point(m.q0(), FingerId(0)).unwrap();
    assert!((p - m.initial_targets()[0].position_m).norm() < 1e-15);
    let moved = FingerTarget::at(p + Vector3::new(0.01, 0.0, 0.0));
    let c = values(&m, m.q0(), &[moved, m.initial_targets()[1]]);
    assert!(
        (c[m.constraints()[m.fingers()[0].constraint.index()]
            .rows
            .start]
            + 0.01)
            .abs()
            < 1e-15
    );
}

#[test]
fn scene_words_round_trip() {
    for k in K::ALL {
        assert_eq!(k.as_str().parse::<K>(), Ok(*k));
    }
    let err = "hinge".parse::<K>().unwrap_err();
    assert!(err.to_string().contains("`hinge`") && err.to_string().contains("revolute"));
    assert_eq!("anchor_j".parse::<P>(), Ok(P::AnchorJ));
}
