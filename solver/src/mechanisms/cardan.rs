//! Nelson & Cohen Fig. 11: "a 1 DOF 4 bar driving a universal joint
//! mechanism ... attached to ground in 3 locations".
//!
//! A crank-rocker four-bar in the plane z = 0, jointed R-S-U-R like the
//! default scene's (a planar loop of four revolutes would repeat three rows):
//! crank pivot A = (0, 0, 0) about z, crank a = 3 cm starting at θ = 90°,
//! coupler b = 8 cm (spherical at the crank, universal at the rocker with
//! cross axes ⟂ BC in the plane and z), rocker c = 6 cm about D = (0.08, 0, 0)
//! (Grashof: a + d ≤ b + c, so the crank turns fully). The rocker is `shaft1`, a vertical shaft
//! turning about z through D; 5 cm up, at U, a Cardan (`cardan`: universal,
//! cross axes y on shaft1 and (cos β, 0, −sin β) on shaft2) drives `shaft2`,
//! whose axis s₂ = (sin β, 0, cos β) leans β = 30° from shaft1's and which
//! turns in its own bearing (`output`, the third ground attachment) 6 cm
//! along s₂. The two closed forms of the figure:
//!
//! - the four-bar: C is where the circles about B(θ) (radius b) and D
//!   (radius c) meet, on the side it starts on; shaft1 turns by φ₁, the
//!   change of the direction of DC;
//! - the Cardan: shaft2 turns by φ₂ = atan(cos β · tan φ₁) (φ₁ measured
//!   from the start, where shaft1's cross axis is normal to the shafts'
//!   plane; |φ₁| < 90° throughout the rocker's swing).
//!
//! 4 moving bodies, 28 coordinates; 26 joint rows and 4 norms, of rank 27:
//! the Cardan's centre is already on both shafts' axes, so its 3 spherical
//! rows repeat the bearings'; 1 degree of freedom (rank-tested). Finger `index`:
//! a point at the crank's end B. Gravity −z. The crank pivot reports its
//! motor torque (§5.2).

use std::f64::consts::PI;

use nalgebra::{UnitQuaternion, Vector3};

use super::{Assembly, rod_inertia, z_to};
use crate::{BodySpec, FingerSpec, JointKind as K, Model, ModelBuilder};

/// Crank, coupler, rocker and ground link lengths, m.
pub const CARDAN_LINKS_M: [f64; 4] = [0.03, 0.08, 0.06, 0.08];
/// The angle β between the two shafts, radians.
pub const CARDAN_BETA: f64 = PI / 6.0;
/// The crank's initial angle from +x, radians.
pub const CARDAN_CRANK0: f64 = PI / 2.0;
/// Height of the Cardan's centre above the rocker pivot, m.
pub const CARDAN_RISE_M: f64 = 0.05;

/// The rocker pivot D.
pub fn cardan_rocker_pivot() -> Vector3<f64> {
    Vector3::new(CARDAN_LINKS_M[3], 0.0, 0.0)
}

/// The coupler–rocker joint C for crank angle `theta` (radians from +x):
/// where the circles about B and D meet, on the +y side of BD (the side the
/// linkage is assembled on).
pub fn cardan_coupler_point(theta: f64) -> Vector3<f64> {
    let [a, b, c, _] = CARDAN_LINKS_M;
    let pb = Vector3::new(a * theta.cos(), a * theta.sin(), 0.0);
    let d = cardan_rocker_pivot();
    let bd = d - pb;
    let dist = bd.norm();
    let along = (b * b - c * c + dist * dist) / (2.0 * dist);
    let off = (b * b - along * along).max(0.0).sqrt();
    let u = bd / dist;
    let n = Vector3::z().cross(&u);
    pb + u * along + n * off
}

/// The four-bar driving a Cardan, assembled at q0.
pub fn four_bar_cardan() -> Model {
    four_bar_cardan_builder()
        .build()
        .expect("the four-bar and Cardan are valid by construction")
}

/// The specs of [`four_bar_cardan`] before building.
pub fn four_bar_cardan_builder() -> ModelBuilder {
    let [a, _, _, _] = CARDAN_LINKS_M;
    let pa = Vector3::zeros();
    let pb = Vector3::new(a * CARDAN_CRANK0.cos(), a * CARDAN_CRANK0.sin(), 0.0);
    let pc = cardan_coupler_point(CARDAN_CRANK0);
    let pd = cardan_rocker_pivot();
    let pu = pd + Vector3::z() * CARDAN_RISE_M;
    let s2 = Vector3::new(CARDAN_BETA.sin(), 0.0, CARDAN_BETA.cos());
    let bearing = pu + s2 * 0.06;
    let z = Vector3::z();
    let mut m = Assembly::new();
    m.body(
        BodySpec::fixed("ground"),
        Vector3::zeros(),
        UnitQuaternion::identity(),
    );
    for (name, p, q, mass) in [("crank", pa, pb, 0.04), ("coupler", pb, pc, 0.06)] {
        let len = (q - p).norm();
        m.body(
            BodySpec::new(name)
                .mass(mass)
                .inertia(rod_inertia(mass, len)),
            (p + q) / 2.0,
            z_to(&((q - p) / len)),
        );
    }
    m.body(
        BodySpec::new("shaft1")
            .mass(0.08)
            .inertia([3e-5, 3e-5, 2e-5]),
        pd + z * (CARDAN_RISE_M / 2.0),
        UnitQuaternion::identity(),
    );
    m.body(
        BodySpec::new("shaft2")
            .mass(0.06)
            .inertia(rod_inertia(0.06, 0.06)),
        pu + s2 * 0.03,
        z_to(&s2),
    );
    let cross2 = Vector3::new(CARDAN_BETA.cos(), 0.0, -CARDAN_BETA.sin());
    let cross1 = (pc - pb).normalize().cross(&z);
    let joints = [
        m.joint(K::Revolute, "ground", "crank", pa, Some([z; 2]))
            .named("crank-pivot")
            .report_torque(),
        m.joint(K::Spherical, "crank", "coupler", pb, None)
            .named("crank-coupler"),
        m.joint(K::Universal, "coupler", "shaft1", pc, Some([cross1, z]))
            .named("coupler-rocker"),
        m.joint(K::Revolute, "ground", "shaft1", pd, Some([z; 2]))
            .named("rocker-pivot"),
        m.joint(
            K::Universal,
            "shaft1",
            "shaft2",
            pu,
            Some([Vector3::y(), cross2]),
        )
        .named("cardan"),
        m.joint(K::Revolute, "ground", "shaft2", bearing, Some([s2; 2]))
            .named("output"),
    ];
    for j in joints {
        m.builder.joint(j);
    }
    let crank_end = Vector3::new(0.0, 0.0, a / 2.0);
    m.builder
        .finger(FingerSpec::point("index", "crank", crank_end.into()));
    m.builder
}
