//! One test per degenerate input: `build` fails with the right variant and a
//! message naming the offending joint, finger, body or inequality.

use haptloop_solver::{
    BodySpec, BuildError as E, DesignParam as P, FingerSpec, JointKind as K, JointSpec,
    ModelBuilder, PlaneOwner, PointPlaneSpec,
};

use crate::common::bodies;

/// Builds `bodies()`, a second fixed body `ground2`, a body `a2` with the pose
/// of `a`, and `joint` (named `bad`); returns the error.
fn joint_err(joint: JointSpec) -> E {
    let mut b = bodies();
    b.body(BodySpec::fixed("ground2"));
    b.body(
        BodySpec::new("a2")
            .at([0.3, 0.1, 0.2])
            .oriented([0.8, 0.2, 0.4, -0.1]),
    );
    b.joint(JointSpec::new(K::Spherical, "a", "b").named("good"));
    b.joint(joint.named("bad"));
    b.build().expect_err("the joint is degenerate")
}

fn names(err: &E, who: &str) {
    let msg = err.to_string();
    assert!(msg.starts_with(who), "`{msg}` does not start with {who}");
}

macro_rules! joint_case {
    ($name:ident, $spec:expr, $pat:pat $(if $guard:expr)?) => {
        #[test]
        fn $name() {
            let err = joint_err($spec);
            assert!(matches!(err, $pat $(if $guard)?), "{err:?}");
            names(&err, "joint `bad`");
        }
    };
}

const X: [f64; 3] = [1.0, 0.0, 0.0];
const Z: [f64; 3] = [0.0, 0.0, 1.0];

joint_case!(unknown_body, JointSpec::new(K::Spherical, "a", "cranck"), E::UnknownBody { ref body, .. } if body == "cranck");
joint_case!(
    same_body_twice,
    JointSpec::new(K::Spherical, "a", "a"),
    E::SameBody { .. }
);
joint_case!(
    both_bodies_fixed,
    JointSpec::new(K::Spherical, "ground", "ground2"),
    E::BothFixed { .. }
);
joint_case!(
    zero_length_axis,
    JointSpec::new(K::Revolute, "a", "b").axes(Z, [0.0; 3]),
    E::ZeroAxis {
        field: "axes[1]",
        ..
    }
);
joint_case!(
    non_finite_axis,
    JointSpec::new(K::Revolute, "a", "b").axes([f64::NAN, 0.0, 1.0], Z),
    E::NonFinite { field: "axes", .. }
);
joint_case!(
    non_finite_anchor,
    JointSpec::new(K::Spherical, "a", "b").anchors([0.0, f64::INFINITY, 0.0], X),
    E::NonFinite {
        field: "anchors",
        ..
    }
);
joint_case!(
    missing_axes,
    JointSpec::new(K::Universal, "a", "b"),
    E::MissingAxes {
        kind: K::Universal,
        ..
    }
);
joint_case!(
    parallel_universal_axes,
    JointSpec::new(K::Universal, "a", "a2").axes(Z, Z),
    E::ParallelAxes {
        kind: K::Universal,
        ..
    }
);
joint_case!(
    parallel_perpendicular_axes,
    JointSpec::new(K::Perpendicular, "a", "a2").axes(X, X),
    E::ParallelAxes { .. }
);
joint_case!(
    coincident_distance_anchors,
    JointSpec::new(K::Distance, "a", "a2"),
    E::CoincidentAnchors { .. }
);
joint_case!(
    non_positive_length,
    JointSpec::new(K::Distance, "a", "b").length(0.0),
    E::NonPositiveLength { .. }
);
joint_case!(
    length_on_a_spherical,
    JointSpec::new(K::Spherical, "a", "b").length(0.1),
    E::UnexpectedLength { .. }
);
joint_case!(
    limits_reversed,
    JointSpec::new(K::Prismatic, "a", "b")
        .axes(Z, Z)
        .limits(0.2, -0.2),
    E::LimitsReversed { .. }
);
joint_case!(
    limits_on_a_spherical,
    JointSpec::new(K::Spherical, "a", "b").limits(-1.0, 1.0),
    E::LimitsUnsupported { .. }
);
joint_case!(
    angle_limits_beyond_pi,
    JointSpec::new(K::Revolute, "a", "b")
        .axes(Z, Z)
        .limits(-1.0, 3.2),
    E::AngleLimitsOutOfRange { .. }
);
joint_case!(
    fixed_length_outside_limits,
    JointSpec::new(K::Distance, "a", "b")
        .length(0.5)
        .limits(0.1, 0.3),
    E::LengthOutsideLimits { .. }
);
joint_case!(
    length_design_var_on_revolute,
    JointSpec::new(K::Revolute, "a", "b")
        .axes(Z, Z)
        .free(&[P::Length]),
    E::UnsupportedFree {
        param: P::Length,
        ..
    }
);
joint_case!(
    anchor_design_var_on_perpendicular,
    JointSpec::new(K::Perpendicular, "a", "b")
        .axes(X, Z)
        .free(&[P::AnchorI]),
    E::UnsupportedFree { .. }
);
joint_case!(
    design_var_listed_twice,
    JointSpec::new(K::Spherical, "a", "b").free(&[P::AnchorJ, P::AnchorJ]),
    E::DuplicateFree { .. }
);
#[test]
fn duplicate_joint_name() {
    let mut b = bodies();
    b.joint(JointSpec::new(K::Spherical, "a", "b").named("j3"));
    b.joint(JointSpec::new(K::Spherical, "b", "ground").named("j3"));
    let err = b.build().unwrap_err();
    assert!(matches!(err, E::DuplicateName { .. }), "{err:?}");
    names(&err, "joint `j3`");
}

#[test]
fn empty_joint_name_is_named_by_position() {
    let mut b = bodies();
    b.joint(JointSpec::new(K::Spherical, "a", "b").named(""));
    let err = b.build().unwrap_err();
    assert!(matches!(err, E::EmptyName { .. }));
    names(&err, "joint `#1`");
}

fn finger_err(finger: FingerSpec) -> E {
    let mut b = bodies();
    b.finger(finger);
    b.build().expect_err("the finger is degenerate")
}

#[test]
fn finger_on_fixed_body() {
    let err = finger_err(FingerSpec::point("index", "ground", [0.0; 3]));
    assert!(matches!(err, E::FingerOnFixedBody { .. }));
    names(&err, "finger `index`");
    assert!(err.to_string().contains("`ground`"));
}

#[test]
fn finger_on_unknown_body() {
    let err = finger_err(FingerSpec::rigid("thumb", "nowhere", [0.0; 3]));
    assert!(matches!(err, E::UnknownBody { .. }));
    names(&err, "finger `thumb`");
}

#[test]
fn finger_point_not_finite() {
    let err = finger_err(FingerSpec::point("index", "a", [0.0, f64::NAN, 0.0]));
    assert!(matches!(err, E::NonFinite { field: "point", .. }));
    names(&err, "finger `index`");
}

#[test]
fn duplicate_finger_name() {
    let mut b = bodies();
    b.finger(FingerSpec::point("index", "a", [0.0; 3]));
    b.finger(FingerSpec::point("index", "b", [0.0; 3]));
    let err = b.build().unwrap_err();
    assert!(matches!(err, E::DuplicateName { .. }));
    names(&err, "finger `index`");
}

fn body_err(spec: BodySpec) -> E {
    let mut b = bodies();
    b.body(spec);
    b.build().expect_err("the body is degenerate")
}

#[test]
fn duplicate_body_name() {
    let err = body_err(BodySpec::new("a"));
    assert!(matches!(err, E::DuplicateName { .. }));
    names(&err, "body `a`");
}

#[test]
fn body_position_not_finite() {
    let err = body_err(BodySpec::new("c").at([0.0, f64::NEG_INFINITY, 0.0]));
    assert!(matches!(
        err,
        E::NonFinite {
            field: "position",
            ..
        }
    ));
    names(&err, "body `c`");
}

#[test]
fn body_orientation_zero() {
    let err = body_err(BodySpec::new("c").oriented([0.0; 4]));
    assert!(matches!(err, E::ZeroOrientation { .. }));
    names(&err, "body `c`");
}

#[test]
fn body_mass_not_positive() {
    let err = body_err(BodySpec::new("c").mass(-1.0));
    assert!(matches!(err, E::NonPositiveMass { .. }));
    names(&err, "body `c`");
}

#[test]
fn body_inertia_not_physical() {
    let err = body_err(BodySpec::new("c").inertia([1.0, 0.1, 0.1]));
    assert!(matches!(err, E::BadInertia { .. }));
    names(&err, "body `c`");
}

#[test]
fn gravity_not_finite() {
    let mut b = ModelBuilder::new();
    b.gravity([0.0, 0.0, f64::NAN]);
    let err = b.build().unwrap_err();
    assert!(matches!(
        err,
        E::NonFinite {
            field: "gravity",
            ..
        }
    ));
    names(&err, "scene");
}

fn inequality_err(body: &str, plane: Option<&str>, normal: [f64; 3]) -> E {
    let m = bodies().build().unwrap();
    let id = |n: &str| m.body_id(n).unwrap_or(haptloop_solver::BodyId(99));
    let spec = PointPlaneSpec {
        name: "w1".into(),
        body: id(body),
        point_m: [0.0; 3],
        plane: plane.map_or(PlaneOwner::World, |p| PlaneOwner::Body(id(p))),
        plane_point_m: [0.0; 3],
        normal,
    };
    let err = m.with_inequalities(&[spec]).unwrap_err();
    names(&err, "inequality `w1`");
    err
}

#[test]
fn inequality_unknown_body() {
    assert!(matches!(
        inequality_err("nowhere", None, Z),
        E::UnknownBody { .. }
    ));
}

#[test]
fn inequality_between_fixed_body_and_world() {
    assert!(matches!(
        inequality_err("ground", None, Z),
        E::BothFixed { .. }
    ));
}

#[test]
fn inequality_zero_normal() {
    assert!(matches!(
        inequality_err("a", Some("b"), [0.0; 3]),
        E::ZeroAxis {
            field: "normal",
            ..
        }
    ));
}

#[test]
fn inequality_same_body() {
    assert!(matches!(
        inequality_err("a", Some("a"), Z),
        E::SameBody { .. }
    ));
}
