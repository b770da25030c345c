//! Design variables a user sees: free positions of fixed bodies (their
//! columns, frames and Jacobian blocks), bounds as rows, and the errors of
//! bad `free` and `bounds` entries.

use haptloop_solver::{
    BodySpec, Bounds, BuildError as E, ConstraintKind as C, DesignOwner, DesignParam as P,
    JointKind as K, JointSpec, Sense,
};
use nalgebra::Vector3;

use crate::common::{self, bodies};
use crate::fd::values;

#[test]
fn free_positions_come_first_among_design_columns() {
    let m = common::free_positions();
    let l = m.layout();
    let names: Vec<_> = l
        .design_vars()
        .iter()
        .map(|d| (d.name.as_str(), d.offset, d.width))
        .collect();
    assert_eq!(
        names,
        [
            ("foot.position", 14, 3),
            ("base.position", 17, 3),
            ("#3.length", 20, 1),
            ("#3.anchor_i", 21, 3),
        ]
    );
    let foot = m.body_id("foot").unwrap();
    assert_eq!(l.origin_offset(foot), Some(14));
    assert_eq!(l.design_vars()[0].owner, DesignOwner::Body(foot));
    assert_eq!(l.design_coords(), 10);
    assert_eq!(&m.q0()[14..17], &[0.2, 0.3, -0.1]);
    assert_eq!(l.design_vars()[1].component_name(2), "base.position.z");
}

#[test]
fn a_free_position_moves_the_fixed_body_and_only_its_origin() {
    let m = common::free_positions();
    let foot = m.body_id("foot").unwrap();
    let mut q = m.q0().to_vec();
    q[14] += 0.05;
    q[16] -= 0.02;
    let p = m.body_position(&q, foot).unwrap();
    assert!((p - Vector3::new(0.25, 0.3, -0.12)).norm() < 1e-15);
    let r0 = m.body_rotation(m.q0(), foot).unwrap();
    assert_eq!(m.body_rotation(&q, foot).unwrap(), r0);
    // The spherical joint foot–a sees the move: its rows change by exactly it.
    let rows = m.constraints()[0].rows.clone();
    let (c0, c1) = (
        values(&m, m.q0(), &m.initial_targets()),
        values(&m, &q, &m.initial_targets()),
    );
    let diff: Vec<f64> = rows.map(|r| c1[r] - c0[r]).collect();
    assert!((diff[0] - 0.05).abs() < 1e-15 && diff[1].abs() < 1e-15);
    assert!((diff[2] + 0.02).abs() < 1e-15);
}

#[test]
fn bounds_become_rows_and_a_pinned_component_an_equality() {
    let m = common::free_positions();
    let kinds: Vec<(&str, C, usize)> = m
        .constraints()
        .iter()
        .filter(|c| matches!(c.kind, C::DesignBound | C::DesignPin))
        .map(|c| (c.name.as_str(), c.kind, c.rows.len()))
        .collect();
    assert_eq!(
        kinds,
        [
            ("foot.position.z.bounds", C::DesignPin, 1),
            ("foot.position.x.bounds", C::DesignBound, 2),
            ("foot.position.y.bounds", C::DesignBound, 2),
            ("base.position.x.bounds", C::DesignBound, 2),
            ("base.position.y.bounds", C::DesignBound, 2),
            ("base.position.z.bounds", C::DesignBound, 2),
            ("#3.length.bounds", C::DesignBound, 2),
            ("#3.anchor_i.x.bounds", C::DesignBound, 2),
            ("#3.anchor_i.y.bounds", C::DesignBound, 2),
            ("#3.anchor_i.z.bounds", C::DesignBound, 2),
        ]
    );
    // The pin is an equality row, the bounds inequalities; values at q0.
    let c = values(&m, m.q0(), &m.initial_targets());
    let pin = m.constraint_id("foot.position.z.bounds").unwrap();
    let r = m.constraints()[pin.index()].rows.start;
    assert_eq!(m.rows()[r].sense, Sense::Equality);
    assert!(m.equality_rows().contains(&r));
    assert_eq!(c[r], 0.0);
    let len = m.constraint_id("#3.length.bounds").unwrap();
    let r = m.constraints()[len.index()].rows.start;
    assert_eq!(m.rows()[r].sense, Sense::Inequality);
    assert_eq!((c[r], c[r + 1]), (0.4 + 2.0, 2.0 - 0.4));
}

fn body_err(body: BodySpec) -> E {
    let mut b = bodies();
    b.body(body);
    b.build().expect_err("the body is refused")
}

#[test]
fn a_moving_body_cannot_free_its_position() {
    let err = body_err(BodySpec::new("c").free_position());
    assert!(
        matches!(
            err,
            E::UnsupportedBodyFree {
                param: P::Position,
                ..
            }
        ),
        "{err:?}"
    );
    assert!(err.to_string().starts_with("body `c`"), "{err}");
    let mut spec = BodySpec::fixed("d");
    spec.free = vec![P::Length];
    assert!(matches!(
        body_err(spec),
        E::UnsupportedBodyFree {
            param: P::Length,
            ..
        }
    ));
    let err = body_err(BodySpec::fixed("d").free_position().free_position());
    assert!(matches!(err, E::DuplicateFree { .. }), "{err:?}");
}

#[test]
fn bad_bounds_are_refused_with_what_is_wrong() {
    let at = |b: Bounds| {
        BodySpec::fixed("d")
            .at([0.1, 0.2, 0.3])
            .free_position()
            .bounds(b)
    };
    let err = body_err(BodySpec::fixed("d").bounds(Bounds::Scalar([0.0, 1.0])));
    assert!(matches!(err, E::BoundsWithoutFree { .. }), "{err:?}");
    let err = body_err(at(Bounds::Scalar([1.0, -1.0])));
    assert!(matches!(err, E::BoundsReversed { .. }), "{err:?}");
    let err = body_err(at(Bounds::Scalar([0.15, 1.0])));
    assert!(
        matches!(err, E::OutsideBounds { ref var, value, .. } if var == "d.position.x" && value == 0.1),
        "{err:?}"
    );
    assert!(
        err.to_string().contains("`d.position.x` starts at 0.1 m"),
        "{err}"
    );
    let err = body_err(at(Bounds::Scalar([f64::NAN, 1.0])));
    assert!(
        matches!(
            err,
            E::NonFinite {
                field: "bounds",
                ..
            }
        ),
        "{err:?}"
    );
    // Per-component bounds on a length.
    let mut b = bodies();
    b.joint(
        JointSpec::new(K::Distance, "a", "b")
            .free(&[P::Length])
            .bounds(Bounds::Vector([[0.0; 3], [1.0; 3]])),
    );
    let err = b.build().unwrap_err();
    assert!(
        matches!(
            err,
            E::BoundsShape {
                param: P::Length,
                ..
            }
        ),
        "{err:?}"
    );
    // A position is a body's design variable, not a joint's.
    let mut b = bodies();
    b.joint(JointSpec::new(K::Spherical, "a", "b").free(&[P::Position]));
    assert!(matches!(
        b.build().unwrap_err(),
        E::UnsupportedFree {
            param: P::Position,
            ..
        }
    ));
}

#[test]
fn two_fixed_bodies_still_cannot_share_a_joint() {
    let mut b = bodies();
    b.body(BodySpec::fixed("foot").free_position());
    b.joint(JointSpec::new(K::Spherical, "ground", "foot"));
    assert!(matches!(b.build().unwrap_err(), E::BothFixed { .. }));
}
