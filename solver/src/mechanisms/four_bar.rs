//! A spatial four-bar linkage with a revolute, a spherical, a universal and a
//! revolute joint (R-S-U-R), as in Nelson & Cohen Fig. 14.
//!
//! Bodies: `ground` (fixed), `crank`, `coupler`, `rocker` (links are slender
//! rods along their body z). Joints, in order:
//! - `crank-pivot`: revolute ground–crank at A = (0, 0, 0) about world z;
//! - `crank-coupler`: spherical at B = (0.04, 0, 0.03);
//! - `coupler-rocker`: universal at C = (0.09, 0.07, 0.08), rocker cross axis
//!   along the rocker pivot axis, coupler cross axis ⟂ to it and to BC;
//! - `rocker-pivot`: revolute ground–rocker at D = (0.12, 0.08, 0) about
//!   (1, 0, 1)/√2 (skew to the crank axis: a genuinely spatial loop).
//!
//! Grübler: 6·3 − (5 + 3 + 4 + 5) = 1 degree of freedom; the universal joint
//! removes the coupler's idle spin about BC that an R-S-S-R would have. The
//! Jacobian rank confirms it (21 coordinates − 20 independent rows = 1, tested).
//! Finger `index`: point grasp at the middle of the coupler. Gravity −z.

use nalgebra::{UnitQuaternion, Vector3};

use super::{Assembly, rod_inertia, z_to};
use crate::{BodySpec, FingerSpec, JointKind as K, Model, ModelBuilder};

/// The spatial R-S-U-R four-bar (metres, kilograms), assembled at q0.
pub fn four_bar() -> Model {
    four_bar_builder()
        .build()
        .expect("the four-bar is valid by construction")
}

/// The specs of [`four_bar`] before building (bodies, body-frame joints, fingers,
/// gravity), e.g. to write them as a scene file.
pub fn four_bar_builder() -> ModelBuilder {
    let a = Vector3::new(0.0, 0.0, 0.0);
    let b = Vector3::new(0.04, 0.0, 0.03);
    let c = Vector3::new(0.09, 0.07, 0.08);
    let d = Vector3::new(0.12, 0.08, 0.0);
    let crank_axis = Vector3::z();
    let rocker_axis = Vector3::new(1.0, 0.0, 1.0).normalize();

    let mut m = Assembly::new();
    m.body(
        BodySpec::fixed("ground"),
        Vector3::zeros(),
        UnitQuaternion::identity(),
    );
    for (name, p, q, mass) in [
        ("crank", a, b, 0.05),
        ("coupler", b, c, 0.08),
        ("rocker", d, c, 0.06),
    ] {
        let len = (q - p).norm();
        let spec = BodySpec::new(name)
            .mass(mass)
            .inertia(rod_inertia(mass, len));
        m.body(spec, (p + q) / 2.0, z_to(&((q - p) / len)));
    }
    let bc = (c - b).normalize();
    let cross = bc.cross(&rocker_axis).normalize();
    let joints = [
        m.joint(K::Revolute, "ground", "crank", a, Some([crank_axis; 2]))
            .named("crank-pivot"),
        m.joint(K::Spherical, "crank", "coupler", b, None)
            .named("crank-coupler"),
        m.joint(
            K::Universal,
            "coupler",
            "rocker",
            c,
            Some([cross, rocker_axis]),
        )
        .named("coupler-rocker"),
        m.joint(K::Revolute, "ground", "rocker", d, Some([rocker_axis; 2]))
            .named("rocker-pivot"),
    ];
    for j in joints {
        m.builder.joint(j);
    }
    m.builder
        .finger(FingerSpec::point("index", "coupler", [0.0; 3]));
    m.builder
}
