//! A 6-UPS Stewart platform (Nelson & Cohen Figs. 2, 15): six legs, each a
//! `cylinder` and a `piston` joined by a prismatic joint, with a universal joint
//! at the fixed `base` and a spherical joint at the `platform`.
//!
//! Geometry (metres): base points on a circle of radius 0.10 at azimuths
//! 120°·p ∓ 15°, platform points on a circle of radius 0.06, 0.12 above the base,
//! at 120°·p ∓ 45° (p = 0, 1, 2), so neighbouring legs cross like a classic
//! 6-6 platform. Per leg k (bodies `cylinder{k}`, `piston{k}`):
//! - `base{k}`: universal base–cylinder at the base point; base cross axis
//!   horizontal and ⟂ to the leg, cylinder cross axis ⟂ to both (this blocks
//!   the leg's spin about its own axis);
//! - `slider{k}`: prismatic cylinder–piston along the leg, anchors at the leg
//!   midpoint, stroke limits ±0.04 m around the initial length;
//! - `top{k}`: spherical piston–platform at the platform point.
//!
//! 13 moving bodies, 91 coordinates. Grübler: 6·13 − 6·(4 + 5 + 3) = 6 degrees
//! of freedom (the platform's pose; rank-tested). Finger `index`: rigid grasp
//! of the platform 1 cm above its centre, which pins all 6. Gravity −z.
//!
//! Masses are a tabletop model's: a 150 g platform, 30 g cylinders and 15 g
//! pistons (0.42 kg in all). The legs are unactuated, so a finger holding the
//! platform carries all of it; rendering a heavier mechanism's inertia from
//! quantised encoder positions is noisy (BENCHMARKS.md, sessions).

use std::f64::consts::PI;

use nalgebra::{UnitQuaternion, Vector3};

use super::{Assembly, rod_inertia, z_to};
use crate::{BodySpec, FingerSpec, JointKind as K, Model, ModelBuilder};

/// Stroke limit of each leg's slider, metres either side of the initial length.
pub const STROKE_M: f64 = 0.04;

/// The Stewart platform, assembled at q0.
pub fn stewart() -> Model {
    stewart_builder()
        .build()
        .expect("the Stewart platform is valid by construction")
}

/// The specs of [`stewart`] before building (bodies, body-frame joints, fingers,
/// gravity), e.g. to write them as a scene file.
pub fn stewart_builder() -> ModelBuilder {
    let height = 0.12;
    let on_circle = |r: f64, deg: f64, z: f64| {
        let t = deg * PI / 180.0;
        Vector3::new(r * t.cos(), r * t.sin(), z)
    };
    let mut m = Assembly::new();
    m.body(
        BodySpec::fixed("base"),
        Vector3::zeros(),
        UnitQuaternion::identity(),
    );
    let platform = BodySpec::new("platform")
        .mass(0.15)
        .inertia([6e-4, 6e-4, 1.05e-3]);
    m.body(
        platform,
        Vector3::new(0.0, 0.0, height),
        UnitQuaternion::from_euler_angles(0.0, 0.0, 0.1),
    );
    let mut joints = Vec::new();
    for k in 0..6 {
        let (p, side) = ((k / 2) as f64, if k % 2 == 0 { -1.0 } else { 1.0 });
        let base = on_circle(0.10, 120.0 * p + side * 15.0, 0.0);
        let top = on_circle(0.06, 120.0 * p + side * 45.0, height);
        let len = (top - base).norm();
        let u = (top - base) / len;
        let (cyl, pis) = (format!("cylinder{k}"), format!("piston{k}"));
        let cylinder = BodySpec::new(&cyl)
            .mass(0.03)
            .inertia(rod_inertia(0.03, 0.6 * len));
        let piston = BodySpec::new(&pis)
            .mass(0.015)
            .inertia(rod_inertia(0.015, 0.6 * len));
        m.body(cylinder, base + u * (0.3 * len), z_to(&u));
        m.body(piston, top - u * (0.3 * len), z_to(&u));
        let h_base = Vector3::z().cross(&u).normalize();
        let h_cyl = u.cross(&h_base);
        joints.push(
            m.joint(K::Universal, "base", &cyl, base, Some([h_base, h_cyl]))
                .named(format!("base{k}")),
        );
        joints.push(
            m.joint(K::Prismatic, &cyl, &pis, (base + top) / 2.0, Some([u, u]))
                .named(format!("slider{k}"))
                .limits(-STROKE_M, STROKE_M),
        );
        joints.push(
            m.joint(K::Spherical, &pis, "platform", top, None)
                .named(format!("top{k}")),
        );
    }
    for j in joints {
        m.builder.joint(j);
    }
    m.builder
        .finger(FingerSpec::rigid("index", "platform", [0.0, 0.0, 0.01]));
    m.builder
}
