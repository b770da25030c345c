//! Offer and binding areas (§3.1): an oriented planar polygon and a label,
//! body frame, with the plane quantities the algorithms need precomputed.

use nalgebra::{Vector2, Vector3};

use super::labels::Label;
use super::spec::AreaKind;
use crate::BodyId;
use crate::geometry::Pose3;

/// An area's handle: its index in the scene's area list.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct AreaId(pub u32);

impl AreaId {
    /// As an index.
    pub fn index(self) -> usize {
        self.0 as usize
    }
}

/// One area (see the module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct Area {
    /// Its body.
    pub body: BodyId,
    /// Offer or binding.
    pub kind: AreaKind,
    /// Its label.
    pub label: Label,
    /// Vertices, body frame, m.
    pub polygon: Vec<Vector3<f64>>,
    /// The unit orientation vector, body frame.
    pub normal: Vector3<f64>,
    /// Mean of the vertices, body frame, m.
    pub centroid: Vector3<f64>,
    /// Largest distance of a vertex from the centroid, m.
    pub radius_m: f64,
    /// In-plane unit vectors (u, v, normal right-handed), body frame.
    pub u: Vector3<f64>,
    /// See `u`.
    pub v: Vector3<f64>,
    /// For each edge k (vertex k → k + 1): a point and the unit in-plane
    /// normal pointing into the polygon, body frame (convex polygons; for a
    /// non-convex binding these are unused).
    pub edges: Vec<(Vector3<f64>, Vector3<f64>)>,
}

impl Area {
    /// An area from a validated polygon (≥ 3 vertices, planar, simple) and
    /// a non-zero normal.
    pub fn new(
        body: BodyId,
        kind: AreaKind,
        label: Label,
        polygon: &[[f64; 3]],
        normal: [f64; 3],
    ) -> Self {
        let polygon: Vec<Vector3<f64>> = polygon.iter().map(|p| Vector3::from(*p)).collect();
        let n = Vector3::from(normal).normalize();
        let centroid = polygon.iter().sum::<Vector3<f64>>() / polygon.len().max(1) as f64;
        let radius_m = polygon
            .iter()
            .map(|p| (p - centroid).norm())
            .fold(0.0, f64::max);
        let seed = if n.x.abs() < 0.9 {
            Vector3::x()
        } else {
            Vector3::y()
        };
        let u = (seed - n * n.dot(&seed)).normalize();
        let v = n.cross(&u);
        let k = polygon.len();
        let edges = (0..k)
            .map(|i| {
                let (a, b) = (polygon[i], polygon[(i + 1) % k]);
                let mut m = n.cross(&(b - a));
                if m.dot(&(centroid - a)) < 0.0 {
                    m = -m;
                }
                let norm = m.norm();
                (a, if norm > 0.0 { m / norm } else { m })
            })
            .collect();
        Self {
            body,
            kind,
            label,
            polygon,
            normal: n,
            centroid,
            radius_m,
            u,
            v,
            edges,
        }
    }

    /// The centroid in the world at `pose`.
    pub fn centroid_w(&self, pose: &Pose3) -> Vector3<f64> {
        pose.point(&self.centroid)
    }

    /// The orientation vector in the world at `pose`.
    pub fn normal_w(&self, pose: &Pose3) -> Vector3<f64> {
        pose.dir(&self.normal)
    }

    /// The vertices in the world at `pose`.
    pub fn vertices_w<'a>(&'a self, pose: &'a Pose3) -> impl Iterator<Item = Vector3<f64>> + 'a {
        self.polygon.iter().map(move |p| pose.point(p))
    }

    /// How far the world point `p` lies outside this (convex) polygon,
    /// measured in its plane at `pose`: the largest distance outside an
    /// edge, ≤ 0 inside (m).
    pub fn outside_m(&self, pose: &Pose3, p: &Vector3<f64>) -> f64 {
        self.edges
            .iter()
            .map(|(a, m)| -pose.dir(m).dot(&(p - pose.point(a))))
            .fold(f64::NEG_INFINITY, f64::max)
    }

    /// In-plane coordinates of the world point `p` (for plots and tests).
    pub fn plane_coords(&self, pose: &Pose3, p: &Vector3<f64>) -> Vector2<f64> {
        let d = pose.local_point(p) - self.centroid;
        Vector2::new(d.dot(&self.u), d.dot(&self.v))
    }
}

/// How a binding area lies against an offer area at the given poses.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Relation {
    /// Signed distance of the binding's centroid above the offer's plane
    /// (along the offer's orientation vector), m.
    pub distance_m: f64,
    /// Largest distance of a binding vertex from the offer's plane, m.
    pub off_plane_m: f64,
    /// Angle between the binding's orientation vector and the reverse of
    /// the offer's, rad (0: anti-parallel, as aligned areas are).
    pub angle_rad: f64,
    /// Largest distance of a binding vertex's projection outside the offer
    /// polygon, m (≤ 0: the projection is included).
    pub outside_m: f64,
}

/// The relation of binding `b` at `pb` to offer `a` at `pa`.
pub fn relation(b: &Area, pb: &Pose3, a: &Area, pa: &Pose3) -> Relation {
    let na = a.normal_w(pa);
    let pa0 = a.centroid_w(pa);
    let nb = b.normal_w(pb);
    let mut off_plane: f64 = 0.0;
    let mut outside = f64::NEG_INFINITY;
    for v in b.vertices_w(pb) {
        let h = na.dot(&(v - pa0));
        off_plane = off_plane.max(h.abs());
        // The edge test is in-plane: the normal component does not count.
        outside = outside.max(a.outside_m(pa, &(v - na * h)));
    }
    Relation {
        distance_m: na.dot(&(b.centroid_w(pb) - pa0)),
        off_plane_m: off_plane,
        // atan2 of |sin| and cos: accurate near 0, where acos loses half
        // the digits (acos(1 − ε) ≈ √(2ε)).
        angle_rad: nb.cross(&-na).norm().atan2(-nb.dot(&na)),
        outside_m: outside,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Matrix3;

    fn square(h: f64, n: f64) -> Area {
        Area::new(
            BodyId(0),
            AreaKind::Offer,
            Label(0),
            &[[-h, -h, 0.0], [h, -h, 0.0], [h, h, 0.0], [-h, h, 0.0]],
            [0.0, 0.0, n],
        )
    }

    #[test]
    fn edges_point_inward_whatever_the_winding() {
        for a in [square(0.5, 1.0), square(0.5, -1.0)] {
            let at = |x: f64, y: f64| a.outside_m(&Pose3::IDENTITY, &Vector3::new(x, y, 0.0));
            assert!((at(0.0, 0.0) + 0.5).abs() < 1e-12);
            assert!((at(0.7, 0.0) - 0.2).abs() < 1e-12);
            assert!((at(0.5, 0.5)).abs() < 1e-12);
        }
    }

    #[test]
    fn relation_of_a_tilted_binding_above_an_offer() {
        let table = square(0.5, 1.0);
        let cup = Area::new(
            BodyId(1),
            AreaKind::Binding,
            Label(0),
            &[
                [-0.1, -0.1, 0.0],
                [0.1, -0.1, 0.0],
                [0.1, 0.1, 0.0],
                [-0.1, 0.1, 0.0],
            ],
            [0.0, 0.0, -1.0],
        );
        let tilt = 0.1f64;
        let rot = Matrix3::new(
            1.0,
            0.0,
            0.0,
            0.0,
            tilt.cos(),
            -tilt.sin(),
            0.0,
            tilt.sin(),
            tilt.cos(),
        );
        let pb = Pose3 {
            r: Vector3::new(0.2, 0.0, 0.03),
            rot,
        };
        let r = relation(&cup, &pb, &table, &Pose3::IDENTITY);
        assert!((r.distance_m - 0.03).abs() < 1e-12);
        assert!((r.angle_rad - tilt).abs() < 1e-12);
        assert!((r.off_plane_m - (0.03 + 0.1 * tilt.sin())).abs() < 1e-12);
        assert!((r.outside_m - (0.2 + 0.1 - 0.5)).abs() < 1e-12);
    }
}
