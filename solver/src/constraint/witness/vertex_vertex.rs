//! Vertex–vertex (Choi & Cremer §3.1.3).
//!
//! Polyhedra: a separating plane through the other body's witness vertex
//! whose normal is the mean of that vertex's face normals, so the ray from
//! the vertex along it lies inside the vertex's Voronoi region; the row is a
//! [`PlaneWitness`].
//!
//! Curved shapes (a sphere against a vertex or another sphere): the exact
//! distance between the two points minus the margin,
//!
//! ```text
//! C = |P − Q| − m,    δC = n̂·(δP − δQ),   n̂ = (P − Q)/|P − Q|
//! ```
//!
//! with the construction's direction standing in for n̂ when the points
//! coincide (no NaN).

use nalgebra::Vector3;

use super::{FeatureKey, PlaneWitness, WitnessType};
use crate::constraint::block::{Ctx, Pair, RowGrad};

/// The separating plane of a polyhedral vertex–vertex witness.
pub fn separating_plane(
    point_end: u8,
    vertex: Vector3<f64>,
    other_vertex: Vector3<f64>,
    vertex_normal: Vector3<f64>,
    margin: f64,
    features: FeatureKey,
) -> PlaneWitness {
    PlaneWitness {
        origin: WitnessType::VertexVertex,
        ..PlaneWitness::vertex_face(
            point_end,
            vertex,
            other_vertex,
            vertex_normal,
            margin,
            features,
        )
    }
}

/// Two points kept `margin` apart (curved vertex–vertex).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BallWitness {
    /// Which witness case produced it.
    pub origin: WitnessType,
    /// The features it was built from.
    pub features: FeatureKey,
    /// The point on end 0, its body's frame.
    pub point_a: Vector3<f64>,
    /// The point on end 1, its body's frame.
    pub point_b: Vector3<f64>,
    /// Fallback unit direction from B's point to A's, end 1's frame.
    pub fallback: Vector3<f64>,
    /// Metres.
    pub margin: f64,
}

impl BallWitness {
    /// Value and gradient.
    #[inline(always)]
    pub(crate) fn row(&self, pair: &Pair, x: &Ctx) -> (f64, RowGrad) {
        let (fa, fb) = (x.frame(pair.frame[0]), x.frame(pair.frame[1]));
        let (la, lb) = (fa.rot * self.point_a, fb.rot * self.point_b);
        let d = (fa.r + la) - (fb.r + lb);
        let len = d.norm();
        let n = if len > 1e-12 {
            d / len
        } else {
            fb.rot * self.fallback
        };
        let mut g = RowGrad::default();
        g.point(0, &la, &n).point(1, &lb, &-n);
        (len - self.margin, g)
    }
}
