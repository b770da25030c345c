//! Vertex–face (Choi & Cremer §3.1.1, Eq. 1): N·P ≥ 0 with P = V − P_p, the
//! vertex V of one body against the plane of a face of the other (point P_p,
//! outward unit normal N), both moving with their bodies:
//!
//! ```text
//! C = N·(V − P_p) − m ≥ 0,    N = R_s n,  V = r_p + R_p v,  P_p = r_s + R_s p
//! δC = N·δV − N·δP_p + (V − P_p)·δN
//! ```
//!
//! m is the margin (radii of curved shapes). The same row, with a different
//! plane, serves the separating planes of vertex–edge and vertex–vertex
//! witnesses and the friction stick rows.

use nalgebra::Vector3;

use super::{FeatureKey, WitnessType, ends};
use crate::constraint::block::{Ctx, Pair, RowGrad};

/// A point on one end kept on the positive side of a plane on the other.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlaneWitness {
    /// Which witness case produced it.
    pub origin: WitnessType,
    /// The features it was built from (change detection).
    pub features: FeatureKey,
    /// 0: the point is on end 0 (body A) and the plane on end 1; 1: reversed.
    pub point_end: u8,
    /// The point, metres, its body's frame.
    pub point: Vector3<f64>,
    /// A point of the plane, metres, the plane body's frame.
    pub plane_point: Vector3<f64>,
    /// Unit normal of the plane, the plane body's frame.
    pub normal: Vector3<f64>,
    /// Distance the point must keep from the plane, metres.
    pub margin: f64,
}

impl PlaneWitness {
    /// Vertex `vertex` of end `point_end` against the face through
    /// `face_point` with outward normal `normal` of the other end.
    pub fn vertex_face(
        point_end: u8,
        vertex: Vector3<f64>,
        face_point: Vector3<f64>,
        normal: Vector3<f64>,
        margin: f64,
        features: FeatureKey,
    ) -> Self {
        Self {
            origin: WitnessType::VertexFace,
            features,
            point_end,
            point: vertex,
            plane_point: face_point,
            normal: normal.normalize(),
            margin,
        }
    }

    /// Value and gradient at the evaluation's frames.
    #[inline(always)]
    pub(crate) fn row(&self, pair: &Pair, x: &Ctx) -> (f64, RowGrad) {
        let (p, s) = ends(self.point_end);
        let (fp, fs) = (x.frame(pair.frame[p]), x.frame(pair.frame[s]));
        let lever_p = fp.rot * self.point;
        let lever_s = fs.rot * self.plane_point;
        let d = (fp.r + lever_p) - (fs.r + lever_s);
        let n = fs.rot * self.normal;
        let mut g = RowGrad::default();
        g.point(p, &lever_p, &n)
            .point(s, &lever_s, &-n)
            .direction(s, &n, &d);
        (n.dot(&d) - self.margin, g)
    }
}
