//! `[[joint]]` tables: the kind, design variables, limits and a joint's surface.

use super::{Arr, Quat, Vec3};
use serde::Deserialize;
use toml::Spanned;

/// `kind = "…"` of a joint.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum JointKindSpec {
    /// 3 rows.
    Spherical,
    /// 5 rows.
    Revolute,
    /// 4 rows.
    Universal,
    /// 5 rows.
    Prismatic,
    /// 6 rows.
    Fixed,
    /// 1 row.
    Distance,
    /// 1 row.
    Perpendicular,
    /// 1 row.
    PointOnPlane,
    /// 3 rows + (u, v).
    OnSurface,
    /// 3 + 2 rows + (u, v).
    Rolling,
}

/// A name in `free = [...]`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FreeSpec {
    /// The distance joint's length.
    Length,
    /// The anchor on body i.
    AnchorI,
    /// The anchor on body j.
    AnchorJ,
    /// A fixed body's position (`[[body]]` only).
    Position,
}

/// `bounds = [lo, hi]` or `bounds = [[lo_x, lo_y, lo_z], [hi_x, hi_y, hi_z]]`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum BoundsSpec {
    /// The same range for every component.
    Scalar([f64; 2]),
    /// A range per component.
    Vector([[f64; 3]; 2]),
}

impl<'de> Deserialize<'de> for BoundsSpec {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        #[derive(Deserialize)]
        #[serde(untagged)]
        enum Raw {
            Scalar(Vec<f64>),
            Vector(Vec<Vec<f64>>),
        }
        let shape = || {
            serde::de::Error::custom(
                "expected `bounds = [lo, hi]` or `bounds = [[lo_x, lo_y, lo_z], [hi_x, hi_y, hi_z]]`",
            )
        };
        match Raw::deserialize(d).map_err(|_| shape())? {
            Raw::Scalar(v) => <[f64; 2]>::try_from(v)
                .map(BoundsSpec::Scalar)
                .map_err(|_| shape()),
            Raw::Vector(v) => {
                let rows: Vec<[f64; 3]> = v
                    .into_iter()
                    .map(|r| <[f64; 3]>::try_from(r).map_err(|_| shape()))
                    .collect::<Result<_, _>>()?;
                <[[f64; 3]; 2]>::try_from(rows)
                    .map(BoundsSpec::Vector)
                    .map_err(|_| shape())
            }
        }
    }
}

/// `[[joint]]`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct JointSection {
    /// Optional, unique if given.
    #[serde(default)]
    pub name: Option<Spanned<String>>,
    /// The joint kind.
    pub kind: Spanned<JointKindSpec>,
    /// Body i, body j.
    pub bodies: Spanned<Arr<Spanned<String>, 2>>,
    /// Body-local anchor points k_i, k_j, m.
    #[serde(default)]
    pub anchors: Option<Spanned<Arr<Vec3, 2>>>,
    /// Body-local axes h_i, h_j.
    #[serde(default)]
    pub axes: Option<Spanned<Arr<Vec3, 2>>>,
    /// Distance joints: strut length, m.
    #[serde(default)]
    pub length: Option<Spanned<f64>>,
    /// Inequality on the joint coordinate.
    #[serde(default)]
    pub limits: Option<Spanned<Arr<f64, 2>>>,
    /// Design variables.
    #[serde(default)]
    pub free: Vec<Spanned<FreeSpec>>,
    /// Bounds on the design variables.
    #[serde(default)]
    pub bounds: Option<Spanned<BoundsSpec>>,
    /// The two bodies' shapes collide with each other (default false).
    #[serde(default)]
    pub collide: Option<Spanned<bool>>,
    /// Report the torque a motor on this joint's axis would need (§5.2).
    #[serde(default)]
    pub report_torque: Option<Spanned<bool>>,
    /// `on_surface` and `rolling`: body j's surface.
    #[serde(default)]
    pub surface: Option<Spanned<SurfaceSection>>,
    /// `on_surface` and `rolling`: the ball's radius, m.
    #[serde(default)]
    pub radius: Option<Spanned<f64>>,
}

/// `surface = { type, radius, origin, orientation }` of a joint.
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SurfaceSection {
    /// The surface's shape.
    #[serde(rename = "type")]
    pub kind: SurfaceTypeSpec,
    /// Sphere or cylinder radius, m.
    #[serde(default)]
    pub radius: Option<f64>,
    /// Origin of its local frame, m, body j's frame.
    #[serde(default)]
    pub origin: Option<Vec3>,
    /// Its local frame, `[w, x, y, z]`, local → body.
    #[serde(default)]
    pub orientation: Option<Quat>,
}

/// `type = "…"` of a surface.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SurfaceTypeSpec {
    /// The local xy plane.
    Plane,
    /// A sphere seen from inside.
    Bowl,
    /// A sphere seen from outside.
    Dome,
    /// A cylinder along local x seen from inside.
    Trough,
    /// A cylinder along local x seen from outside.
    Ridge,
}
