//! Shared builders: boxes, spheres and capsules as models and colliders.
#![allow(dead_code)] // shared by the test modules; not every module uses every helper

use haptloop_solver::geometry::{PairSpec, Pose3, Shape};
use haptloop_solver::{BodySpec, Model, ModelBuilder};
use nalgebra::{Matrix3, Rotation3, Vector3};

/// A box shape of half extents `h`.
pub fn cuboid(h: [f64; 3]) -> Shape {
    Shape::Box { half_extents_m: h }
}

/// Three bodies: moving A, moving B, fixed C, each with a shape, and the
/// contact rows of pairs (A, B) and (A, C) with `slots` rows each, plus
/// friction rows on (A, B) when `friction`.
pub fn three_bodies(shapes: [Shape; 3], slots: u32) -> Model {
    let mut b = ModelBuilder::new();
    b.body(
        BodySpec::new("a")
            .at([0.0, 0.0, 0.3])
            .shape(shapes[0].clone()),
    );
    b.body(
        BodySpec::new("b")
            .at([0.0, 0.0, 0.6])
            .shape(shapes[1].clone()),
    );
    b.body(BodySpec::fixed("c").shape(shapes[2].clone()));
    let base = b.build().expect("model");
    base.with_contacts(&[
        PairSpec {
            bodies: [0, 1],
            slots,
            friction: true,
        },
        PairSpec {
            bodies: [0, 2],
            slots,
            friction: false,
        },
    ])
    .expect("contacts")
}

/// A pose at `r` rotated by `angle` about `axis`.
pub fn pose(r: [f64; 3], axis: [f64; 3], angle: f64) -> Pose3 {
    let rot =
        Rotation3::from_axis_angle(&nalgebra::Unit::new_normalize(Vector3::from(axis)), angle);
    Pose3 {
        r: Vector3::from(r),
        rot: rot.into_inner(),
    }
}

/// The identity pose at `r`.
pub fn at(r: [f64; 3]) -> Pose3 {
    Pose3 {
        r: Vector3::from(r),
        rot: Matrix3::identity(),
    }
}
