//! The Stewart platform of Nelson & Cohen Figs. 2 and 3: "3 revolute, 3
//! spherical, 3 universal joints, and one constraint on a ground body
//! holding it immobile" (a 3-RUS platform, 6 degrees of freedom).
//!
//! The graph of Fig. 3 exactly: the `ground` is a moving body (its own node)
//! held by a `hold` weld to the fixed `floor`. Three legs at azimuths
//! ψ_k = 90° + 120° k (radial r̂_k, tangent t_k = ẑ × r̂_k): a `crank{k}` on a
//! `hinge{k}` revolute at B_k = R_b r̂_k about t_k (limits ±0.8 rad), a
//! `rod{k}` on an `elbow{k}` universal at the crank's end C_k = (R_b + a) r̂_k
//! (cross axes t_k on the crank and t_k × rod on the rod), and a `ball{k}`
//! spherical at the platform point P_k = R_p r̂_k + h ẑ. At the initial
//! configuration the cranks are horizontal; raising the level platform to
//! height z turns every crank by the same α, with its end at height
//! a sin α where (Figs. 2/3 closed form, u = R_b − R_p)
//!
//! ```text
//! (u + a cos α)² + (z − a sin α)² = L²
//! ⇔ α = acos(K/ρ) − δ,  K = (L² − u² − a² − z²)/(2a),  ρ = √(u² + z²),  δ = atan2(z, u)
//! ```
//!
//! 8 moving bodies, 56 coordinates. Grübler: 6·8 − (6 + 3·5 + 3·4 + 3·3) = 6
//! degrees of freedom (the platform's pose; rank-tested). Finger `index`:
//! rigid grasp of the platform 1 cm above its centre. Gravity −z.

use std::f64::consts::PI;

use nalgebra::{UnitQuaternion, Vector3};

use super::{Assembly, rod_inertia, z_to};
use crate::{BodySpec, FingerSpec, JointKind as K, Model, ModelBuilder};

/// Radius of the hinges on the ground, m.
pub const RSU_BASE_M: f64 = 0.10;
/// Crank length a, m.
pub const RSU_CRANK_M: f64 = 0.05;
/// Radius of the platform's ball joints, m.
pub const RSU_PLATFORM_M: f64 = 0.05;
/// Rod length L, m.
pub const RSU_ROD_M: f64 = 0.13;

/// Azimuth of leg k, radians.
pub fn rsu_azimuth(k: usize) -> f64 {
    PI / 2.0 + 2.0 * PI / 3.0 * k as f64
}

/// The platform's initial height (cranks horizontal), m.
pub fn rsu_height_m() -> f64 {
    let u = RSU_BASE_M + RSU_CRANK_M - RSU_PLATFORM_M;
    (RSU_ROD_M * RSU_ROD_M - u * u).sqrt()
}

/// The 3-RUS platform, assembled at q0.
pub fn stewart_3rsu() -> Model {
    stewart_3rsu_builder()
        .build()
        .expect("the 3-RUS platform is valid by construction")
}

/// The specs of [`stewart_3rsu`] before building.
pub fn stewart_3rsu_builder() -> ModelBuilder {
    let h = rsu_height_m();
    let id = UnitQuaternion::identity();
    let mut m = Assembly::new();
    m.body(BodySpec::fixed("floor"), Vector3::zeros(), id);
    m.body(
        BodySpec::new("ground")
            .mass(2.0)
            .inertia([0.01, 0.01, 0.02]),
        Vector3::zeros(),
        id,
    );
    m.body(
        BodySpec::new("platform")
            .mass(0.2)
            .inertia([8e-4, 8e-4, 1.5e-3]),
        Vector3::new(0.0, 0.0, h),
        id,
    );
    let mut joints = vec![
        m.joint(K::Fixed, "floor", "ground", Vector3::zeros(), None)
            .named("hold"),
    ];
    for k in 0..3 {
        let psi = rsu_azimuth(k);
        let r = Vector3::new(psi.cos(), psi.sin(), 0.0);
        let t = Vector3::z().cross(&r);
        let b = r * RSU_BASE_M;
        let c = r * (RSU_BASE_M + RSU_CRANK_M);
        let p = r * RSU_PLATFORM_M + Vector3::z() * h;
        let rod_dir = (p - c) / RSU_ROD_M;
        let (crank, rod) = (format!("crank{k}"), format!("rod{k}"));
        m.body(
            BodySpec::new(&crank)
                .mass(0.05)
                .inertia(rod_inertia(0.05, RSU_CRANK_M)),
            (b + c) / 2.0,
            z_to(&r),
        );
        m.body(
            BodySpec::new(&rod)
                .mass(0.04)
                .inertia(rod_inertia(0.04, RSU_ROD_M)),
            (c + p) / 2.0,
            z_to(&rod_dir),
        );
        joints.push(
            m.joint(K::Revolute, "ground", &crank, b, Some([t; 2]))
                .named(format!("hinge{k}"))
                .limits(-0.8, 0.8),
        );
        let n = t.cross(&rod_dir).normalize();
        joints.push(
            m.joint(K::Universal, &crank, &rod, c, Some([t, n]))
                .named(format!("elbow{k}")),
        );
        joints.push(
            m.joint(K::Spherical, &rod, "platform", p, None)
                .named(format!("ball{k}")),
        );
    }
    for j in joints {
        m.builder.joint(j);
    }
    m.builder
        .finger(FingerSpec::rigid("index", "platform", [0.0, 0.0, 0.01]));
    m.builder
}
