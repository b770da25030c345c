//! `[[body]]` tables: the body, its flexibility, shape and semantic areas.

use super::{Arr, BoundsSpec, FreeSpec, Quat, Vec3};
use serde::Deserialize;
use toml::Spanned;

/// `[[body]]`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BodySection {
    /// Required, unique.
    pub name: Spanned<String>,
    /// Fixed bodies have no coordinates.
    #[serde(default)]
    pub fixed: bool,
    /// m, scene frame; default origin.
    #[serde(default)]
    pub position: Option<Spanned<Vec3>>,
    /// `[w, x, y, z]`; default identity.
    #[serde(default)]
    pub orientation: Option<Spanned<Quat>>,
    /// kg.
    #[serde(default)]
    pub mass: Option<Spanned<f64>>,
    /// Principal moments, kg·m², body frame.
    #[serde(default)]
    pub inertia: Option<Spanned<Vec3>>,
    /// Collision shape; a body without one takes part in no contact.
    #[serde(default)]
    pub shape: Option<Spanned<ShapeSpec>>,
    /// kg/m³: mass and inertia from the shape when `mass` is absent.
    #[serde(default)]
    pub density: Option<Spanned<f64>>,
    /// Coulomb μ of the body's contacts with other bodies.
    #[serde(default)]
    pub friction: Option<Spanned<f64>>,
    /// Restitution of the body's contacts, in [0, 1].
    #[serde(default)]
    pub restitution: Option<Spanned<f64>>,
    /// Velocity damping, 1/s.
    #[serde(default)]
    pub damping: Option<Spanned<f64>>,
    /// Initial velocity, m/s, scene frame.
    #[serde(default)]
    pub velocity: Option<Spanned<Vec3>>,
    /// Initial angular velocity, rad/s, scene frame.
    #[serde(default)]
    pub angular_velocity: Option<Spanned<Vec3>>,
    /// `[[body.offer]]` semantic areas.
    #[serde(default)]
    pub offer: Vec<AreaSection>,
    /// `[[body.binding]]` semantic areas.
    #[serde(default)]
    pub binding: Vec<AreaSection>,
    /// Design variables of a fixed body: `["position"]`.
    #[serde(default)]
    pub free: Vec<Spanned<FreeSpec>>,
    /// Bounds on the freed position.
    #[serde(default)]
    pub bounds: Option<Spanned<BoundsSpec>>,
    /// A flexible body's beam (Nelson & Cohen §4).
    #[serde(default)]
    pub flexible: Option<Spanned<FlexibleSpec>>,
}

/// `flexible = { span, clamp, stiffness, stiffness_z, modes }`.
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FlexibleSpec {
    /// `[x0, x1]` along the body's x axis, m, body frame.
    pub span: Arr<f64, 2>,
    /// Where on the span the body frame is the beam's tangent frame, m
    /// (default 0).
    #[serde(default)]
    pub clamp: Option<f64>,
    /// EI for deflection along the body's y axis (and z unless
    /// `stiffness_z`), N·m².
    pub stiffness: f64,
    /// EI for deflection along z, N·m² (default: `stiffness`).
    #[serde(default)]
    pub stiffness_z: Option<f64>,
    /// Shape functions per direction (default 3).
    #[serde(default)]
    pub modes: Option<u32>,
}

/// `shape = { … }`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields, rename_all = "snake_case")]
pub enum ShapeSpec {
    /// Half extents, m.
    Box(Vec3),
    /// Radius, m.
    Sphere(f64),
    /// Along the body's z axis.
    Capsule {
        /// Half the length of the cylinder part, m.
        half_height: f64,
        /// m.
        radius: f64,
    },
    /// Convex hull of the points, body frame.
    Convex(Vec<Vec3>),
}

/// A semantic offer or binding area.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AreaSection {
    /// Label in the `[labels]` partial order.
    pub label: Spanned<String>,
    /// Planar polygon, body frame.
    pub polygon: Spanned<Vec<Vec3>>,
    /// Orientation vector, body frame.
    pub normal: Spanned<Vec3>,
}
