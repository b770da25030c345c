//! Collision shapes: what a scene declares ([`Shape`]), their mass
//! properties, and their compiled form for queries ([`Collider`]).
//!
//! Every collider is a convex **core** swept by a ball of radius `margin`
//! (Choi & Cremer's curved shapes with their exact support point): a sphere
//! is a point core with its radius as margin, a capsule a segment core, a
//! box or convex hull a polyhedron core with margin 0. Distances are core
//! distances minus the margins, so GJK works on exact polytopes and the
//! witness constraints on a curved shape carry its radius as an offset.
//! Body frame throughout.

use nalgebra::{Matrix3, Vector3};
use parry3d_f64::shape::{Ball, Capsule, Cuboid, Segment, SharedShape, SupportMap};

use super::convert::{to_glam, to_na};
use super::polyhedron::{HullError, Polyhedron};

/// Density a shaped body gets when it gives neither `mass` nor `density`:
/// 1000 kg/m³ (water; a 10 cm box weighs 1 kg, the scale of objects held in a
/// PHANToM workspace).
pub const DEFAULT_DENSITY_KG_M3: f64 = 1000.0;

/// A collision shape in its body's frame, as a scene declares it.
#[derive(Debug, Clone, PartialEq)]
pub enum Shape {
    /// An axis-aligned box centred on the origin.
    Box {
        /// Half extents, metres.
        half_extents_m: [f64; 3],
    },
    /// A ball centred on the origin.
    Sphere {
        /// Radius, metres.
        radius_m: f64,
    },
    /// A capsule along the body's z axis, centred on the origin.
    Capsule {
        /// Half the length of the cylindrical part, metres.
        half_height_m: f64,
        /// Radius, metres.
        radius_m: f64,
    },
    /// The convex hull of these points (body frame, metres).
    Convex {
        /// The points.
        points_m: Vec<[f64; 3]>,
    },
}

/// Why a shape cannot be used.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ShapeError {
    /// A size is not finite or not positive.
    #[error("`{field}` must be finite and > 0 (got {value})")]
    Size {
        /// Which size.
        field: &'static str,
        /// Its value.
        value: f64,
    },
    /// The hull points are unusable.
    #[error("convex shape: {0}")]
    Hull(#[from] HullError),
    /// Mass from density needs the centre of mass at the body origin.
    #[error(
        "the convex shape's centre of mass is at [{:.4}, {:.4}, {:.4}] m, not at the body origin; \
         shift its points so the origin is the centre of mass, or give `mass` and `inertia`",
        .0[0], .0[1], .0[2]
    )]
    OffCentre([f64; 3]),
    /// Mass from density needs principal axes along the body axes.
    #[error(
        "the convex shape's inertia is not diagonal in the body frame (off-diagonal {0:.2} % of the \
         largest moment); align its principal axes with the body axes, or give `mass` and `inertia`"
    )]
    NotPrincipal(f64),
}

/// Mass and principal moments of a shape of uniform density, about the body
/// origin (which must be the centre of mass).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MassProps {
    /// Kilograms.
    pub mass_kg: f64,
    /// Principal moments about the body axes, kg·m².
    pub inertia_kg_m2: [f64; 3],
}

impl Shape {
    /// Checks sizes and builds the collider. Allocates.
    pub fn collider(&self) -> Result<Collider, ShapeError> {
        let pos = |field: &'static str, value: f64| {
            if value.is_finite() && value > 0.0 {
                Ok(value)
            } else {
                Err(ShapeError::Size { field, value })
            }
        };
        let (core, margin, full) = match self {
            Shape::Box { half_extents_m: h } => {
                for (k, f) in ["box[0]", "box[1]", "box[2]"].into_iter().enumerate() {
                    pos(f, h[k])?;
                }
                let full = SharedShape::new(Cuboid::new(to_glam(&Vector3::from(*h))));
                (
                    Core::Polyhedron(Box::new(Polyhedron::cuboid(*h)?)),
                    0.0,
                    full,
                )
            }
            Shape::Sphere { radius_m } => {
                let r = pos("sphere", *radius_m)?;
                (Core::Point, r, SharedShape::new(Ball::new(r)))
            }
            Shape::Capsule {
                half_height_m,
                radius_m,
            } => {
                let r = pos("radius", *radius_m)?;
                let h = *half_height_m;
                if !(h.is_finite() && h >= 0.0) {
                    return Err(ShapeError::Size {
                        field: "half_height",
                        value: h,
                    });
                }
                if h == 0.0 {
                    (Core::Point, r, SharedShape::new(Ball::new(r)))
                } else {
                    let (a, b) = (Vector3::new(0.0, 0.0, -h), Vector3::new(0.0, 0.0, h));
                    let full = SharedShape::new(Capsule::new(to_glam(&a), to_glam(&b), r));
                    (Core::Segment { a, b }, r, full)
                }
            }
            Shape::Convex { points_m } => {
                let pts: Vec<Vector3<f64>> = points_m.iter().map(|p| Vector3::from(*p)).collect();
                let poly = Polyhedron::hull(&pts)?;
                let full = SharedShape::new(poly.parry().clone());
                (Core::Polyhedron(Box::new(poly)), 0.0, full)
            }
        };
        let core_radius = match &core {
            Core::Point => 0.0,
            Core::Segment { a, b } => a.norm().max(b.norm()),
            Core::Polyhedron(p) => p.radius_m,
        };
        Ok(Collider {
            core,
            margin_m: margin,
            radius_m: core_radius + margin,
            full,
            point: Ball::new(0.0),
        })
    }

    /// The whole shape as parry sees it and its bounding radius, m, without
    /// the witness topology of [`collider`](Self::collider); a convex shape
    /// of more than [`MAX_HULL_VERTICES`](super::MAX_HULL_VERTICES) points
    /// is its simplified hull (`simplify.rs`: parry's hull of many points
    /// costs far more than linear time). Allocates.
    pub fn parry_shape(&self) -> Result<(SharedShape, f64), ShapeError> {
        match self {
            Shape::Convex { points_m } => {
                let cut = super::simplify::simplify_hull(points_m, super::MAX_HULL_VERTICES)?;
                let kept = cut
                    .as_ref()
                    .map_or(points_m.as_slice(), |c| c.points_m.as_slice());
                let pts: Vec<_> = kept.iter().map(|p| to_glam(&Vector3::from(*p))).collect();
                let hull = parry3d_f64::shape::ConvexPolyhedron::from_convex_hull(&pts)
                    .ok_or(HullError::Flat)?;
                let r = kept
                    .iter()
                    .map(|p| Vector3::from(*p).norm())
                    .fold(0.0, f64::max);
                Ok((SharedShape::new(hull), r))
            }
            _ => {
                let c = self.collider()?;
                Ok((c.full, c.radius_m))
            }
        }
    }

    /// Mass and principal inertia at `density` (kg/m³).
    pub fn mass_properties(&self, density_kg_m3: f64) -> Result<MassProps, ShapeError> {
        self.mass_properties_within(density_kg_m3, 0.0)
    }

    /// [`mass_properties`](Self::mass_properties), the centre of mass
    /// allowed `com_slack_m` farther from the origin than round-off (a
    /// simplified hull's moves by up to the distance it was cut by).
    pub fn mass_properties_within(
        &self,
        density_kg_m3: f64,
        com_slack_m: f64,
    ) -> Result<MassProps, ShapeError> {
        let (full, radius_m) = self.parry_shape()?;
        let mp = full.mass_properties(density_kg_m3);
        let com = to_na(mp.local_com);
        let size = radius_m.max(1e-12);
        if com.norm() > 1e-3 * size + com_slack_m {
            return Err(ShapeError::OffCentre(com.into()));
        }
        let i = mp.reconstruct_inertia_matrix();
        let m = Matrix3::new(
            i.x_axis.x, i.y_axis.x, i.z_axis.x, i.x_axis.y, i.y_axis.y, i.z_axis.y, i.x_axis.z,
            i.y_axis.z, i.z_axis.z,
        );
        let largest = m.diagonal().max();
        let off = m.m12.abs().max(m.m13.abs()).max(m.m23.abs());
        if off > 1e-3 * largest {
            return Err(ShapeError::NotPrincipal(100.0 * off / largest));
        }
        Ok(MassProps {
            mass_kg: mp.mass(),
            inertia_kg_m2: [m.m11, m.m22, m.m33],
        })
    }
}

/// The convex core of a collider.
#[derive(Debug, Clone)]
pub enum Core {
    /// The body origin (a sphere's centre).
    Point,
    /// A segment from `a` to `b` (a capsule's axis), body frame.
    Segment {
        /// First end.
        a: Vector3<f64>,
        /// Second end.
        b: Vector3<f64>,
    },
    /// A convex polyhedron (box, hull).
    Polyhedron(Box<Polyhedron>),
}

/// A shape compiled for queries (see the module docs).
#[derive(Debug, Clone)]
pub struct Collider {
    /// The convex core.
    pub core: Core,
    /// Radius swept around the core, metres (0 for polyhedra).
    pub margin_m: f64,
    /// Bounding radius about the body origin, metres.
    pub radius_m: f64,
    /// The whole shape as parry sees it (penetration depth, time of impact,
    /// mass properties).
    pub full: SharedShape,
    point: Ball,
}

impl Collider {
    /// The core as a GJK support map.
    pub fn core_support(&self) -> &dyn SupportMap {
        match &self.core {
            Core::Point => &self.point,
            Core::Segment { .. } => self
                .full
                .as_capsule()
                .map(|c| &c.segment as &dyn SupportMap)
                .unwrap_or(&self.point),
            Core::Polyhedron(p) => p.parry(),
        }
    }

    /// The polyhedron core, if that is what it is.
    pub fn polyhedron(&self) -> Option<&Polyhedron> {
        match &self.core {
            Core::Polyhedron(p) => Some(p),
            _ => None,
        }
    }

    /// A vertex of the core, body frame (`Vertex(0)` of a point is the origin;
    /// of a segment, its ends).
    pub fn vertex(&self, v: u32) -> Vector3<f64> {
        match &self.core {
            Core::Point => Vector3::zeros(),
            Core::Segment { a, b } => {
                if v == 0 {
                    *a
                } else {
                    *b
                }
            }
            Core::Polyhedron(p) => p.vertices[v as usize],
        }
    }

    /// The endpoints of edge `e` of the core, body frame.
    pub fn edge(&self, e: u32) -> [Vector3<f64>; 2] {
        match &self.core {
            Core::Point => [Vector3::zeros(); 2],
            Core::Segment { a, b } => [*a, *b],
            Core::Polyhedron(p) => {
                let ed = p.edges[e as usize];
                [
                    p.vertices[ed.vertices[0] as usize],
                    p.vertices[ed.vertices[1] as usize],
                ]
            }
        }
    }
}

/// A segment core as parry's `Segment` (for callers that need the type).
pub fn segment(a: &Vector3<f64>, b: &Vector3<f64>) -> Segment {
    Segment::new(to_glam(a), to_glam(b))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mass_properties_match_closed_forms() {
        let rho = 1000.0;
        let b = Shape::Box {
            half_extents_m: [0.05, 0.03, 0.02],
        }
        .mass_properties(rho)
        .unwrap();
        let m = rho * 0.1 * 0.06 * 0.04;
        assert!((b.mass_kg - m).abs() < 1e-12 * m);
        let ix = m / 12.0 * (0.06f64.powi(2) + 0.04f64.powi(2));
        assert!((b.inertia_kg_m2[0] - ix).abs() < 1e-9 * ix, "{:?}", b);
        let s = Shape::Sphere { radius_m: 0.02 }
            .mass_properties(rho)
            .unwrap();
        let ms = rho * 4.0 / 3.0 * std::f64::consts::PI * 0.02f64.powi(3);
        assert!((s.mass_kg - ms).abs() < 1e-12 * ms);
        assert!((s.inertia_kg_m2[2] - 0.4 * ms * 0.0004).abs() < 1e-9 * ms);
        // A hull of a box's corners weighs what the box weighs.
        let mut pts = Vec::new();
        for x in [-0.05, 0.05] {
            for y in [-0.03, 0.03] {
                for z in [-0.02, 0.02] {
                    pts.push([x, y, z]);
                }
            }
        }
        let h = Shape::Convex { points_m: pts }
            .mass_properties(rho)
            .unwrap();
        assert!((h.mass_kg - m).abs() < 1e-9 * m);
        assert!((h.inertia_kg_m2[0] - ix).abs() < 1e-6 * ix);
    }

    #[test]
    fn off_centre_hulls_and_bad_sizes_are_refused() {
        let pts = vec![
            [0.0, 0.0, 0.0],
            [0.1, 0.0, 0.0],
            [0.0, 0.1, 0.0],
            [0.0, 0.0, 0.1],
        ];
        assert!(matches!(
            Shape::Convex { points_m: pts }.mass_properties(1000.0),
            Err(ShapeError::OffCentre(_))
        ));
        assert!(matches!(
            Shape::Sphere { radius_m: -1.0 }.collider(),
            Err(ShapeError::Size { .. })
        ));
        assert!(matches!(
            Shape::Box {
                half_extents_m: [0.1, f64::NAN, 0.1]
            }
            .collider(),
            Err(ShapeError::Size { .. })
        ));
    }
}
