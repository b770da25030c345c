//! Vertex–edge (Choi & Cremer §3.1.2).
//!
//! Polyhedra: a separating plane that contains the witness edge, with normal
//! the mean of the edge's two face normals. It is valid (its normal has a
//! positive dot product with the normals of both Voronoi bounding planes of
//! the edge), and it does not over-constrain: before the vertex could reach
//! the plane away from the edge, the nearest features change and the slow
//! loop replaces the witness. The row is a [`PlaneWitness`].
//!
//! Curved shapes (a sphere's centre or a capsule's end against an edge, or
//! anything against a capsule's axis): the exact distance from the point to
//! the edge's line, minus the margin,
//!
//! ```text
//! C = |w| − m,  w = d − (d·U)U,  d = P − Q,  U = R_s u
//! δC = ŵ·δP − ŵ·δQ − (d·U) ŵ·δU          (ŵ = w/|w|; ŵ ⊥ U)
//! ```
//!
//! so a ball rolls round an edge smoothly between witness updates. At |w| → 0
//! (the point on the line, only reachable deep in penetration) the direction
//! kept from the witness's construction stands in for ŵ: no NaN.

use nalgebra::Vector3;

use super::{FeatureKey, PlaneWitness, WitnessType, ends};
use crate::constraint::block::{Ctx, Pair, RowGrad};

/// Below this |w|, metres, the stored direction replaces ŵ.
const DEGENERATE_M: f64 = 1e-12;

/// The separating plane of a polyhedral vertex–edge witness: vertex `vertex`
/// of end `point_end`; the edge of the other end through `edge_point` with
/// separating normal `edge_normal` (the mean of its faces' normals).
pub fn separating_plane(
    point_end: u8,
    vertex: Vector3<f64>,
    edge_point: Vector3<f64>,
    edge_normal: Vector3<f64>,
    margin: f64,
    features: FeatureKey,
) -> PlaneWitness {
    PlaneWitness {
        origin: WitnessType::VertexEdge,
        ..PlaneWitness::vertex_face(point_end, vertex, edge_point, edge_normal, margin, features)
    }
}

/// A point kept `margin` away from a line (curved vertex–edge).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LineWitness {
    /// Which witness case produced it.
    pub origin: WitnessType,
    /// The features it was built from.
    pub features: FeatureKey,
    /// End carrying the point (0 or 1).
    pub point_end: u8,
    /// The point, its body's frame.
    pub point: Vector3<f64>,
    /// A point of the line, the other body's frame.
    pub line_point: Vector3<f64>,
    /// Unit direction of the line, the other body's frame.
    pub line_dir: Vector3<f64>,
    /// Fallback direction from the line to the point, the line body's frame.
    pub fallback: Vector3<f64>,
    /// Metres.
    pub margin: f64,
}

impl LineWitness {
    /// Value and gradient.
    #[inline(always)]
    pub(crate) fn row(&self, pair: &Pair, x: &Ctx) -> (f64, RowGrad) {
        let (p, s) = ends(self.point_end);
        let (fp, fs) = (x.frame(pair.frame[p]), x.frame(pair.frame[s]));
        let lever_p = fp.rot * self.point;
        let lever_s = fs.rot * self.line_point;
        let d = (fp.r + lever_p) - (fs.r + lever_s);
        let u = fs.rot * self.line_dir;
        let du = d.dot(&u);
        let w = d - u * du;
        let len = w.norm();
        let what = if len > DEGENERATE_M {
            w / len
        } else {
            fs.rot * self.fallback
        };
        let mut g = RowGrad::default();
        g.point(p, &lever_p, &what)
            .point(s, &lever_s, &-what)
            .direction(s, &u, &(what * -du));
        (len - self.margin, g)
    }
}
