//! What a satisfied constraint becomes in the fast loop: a [`SurfaceSpec`]
//! for [`Model::with_semantic`](crate::Model::with_semantic) (see
//! `constraint/surface.rs` for the rows and why they are checkMove).

use nalgebra::Vector3;

use super::area::AreaId;
use super::scene::SemanticScene;
use crate::model::{SurfaceRow, SurfaceSpec};

impl SemanticScene {
    /// The constraint's name: `<binding body>.b<k>|<offer body>.o<k>`, k the
    /// area's index among its body's bindings or offers.
    pub fn bond_name(&self, b: AreaId, a: AreaId) -> String {
        let (ab, aa) = (&self.areas[b.index()], &self.areas[a.index()]);
        let kb = self.objects[ab.body.index()]
            .bindings
            .iter()
            .position(|&x| x == b)
            .unwrap_or(0);
        let ka = self.objects[aa.body.index()]
            .offers
            .iter()
            .position(|&x| x == a)
            .unwrap_or(0);
        format!("{}.b{kb}|{}.o{ka}", self.name(ab.body), self.name(aa.body))
    }

    /// The rows of binding area `b`'s satisfied constraint (`None`: not
    /// satisfied, or both objects fixed: nothing to hold).
    pub fn surface_spec(&self, b: AreaId) -> Option<SurfaceSpec> {
        let bond = self.bond(b)?;
        let (ab, aa) = (&self.areas[b.index()], &self.areas[bond.offer.index()]);
        if self.objects[ab.body.index()].fixed && self.objects[aa.body.index()].fixed {
            return None;
        }
        let arr = |v: Vector3<f64>| [v.x, v.y, v.z];
        let plane_point = arr(aa.centroid);
        let normal = arr(aa.normal);
        let [p, q, r] = spread_triangle(&ab.polygon);
        let plane = [p, q, r].map(|v| SurfaceRow {
            point_m: arr(v),
            plane_point_m: plane_point,
            normal,
        });
        let inclusion = ab
            .polygon
            .iter()
            .flat_map(|v| {
                aa.edges.iter().map(move |(e, m)| SurfaceRow {
                    point_m: arr(*v),
                    plane_point_m: arr(*e),
                    normal: arr(*m),
                })
            })
            .collect();
        Some(SurfaceSpec {
            name: self.bond_name(b, bond.offer),
            binding: ab.body,
            offer: aa.body,
            plane,
            inclusion,
        })
    }

    /// The rows of every satisfied constraint that has some, by binding area.
    pub fn surface_specs(&self) -> Vec<SurfaceSpec> {
        self.bonds()
            .filter_map(|(b, _)| self.surface_spec(b))
            .collect()
    }
}

/// Three vertices spanning a large triangle: the farthest from the first,
/// the farthest from that one, and the farthest from the line through both
/// (well conditioned plane rows).
fn spread_triangle(poly: &[Vector3<f64>]) -> [Vector3<f64>; 3] {
    let far = |from: &Vector3<f64>| {
        poly.iter()
            .copied()
            .max_by(|a, b| (a - from).norm().total_cmp(&(b - from).norm()))
            .unwrap_or(*from)
    };
    let p = far(&poly[0]);
    let q = far(&p);
    let d = (q - p).normalize();
    let r = poly
        .iter()
        .copied()
        .max_by(|a, b| {
            let off = |x: &Vector3<f64>| ((x - p) - d * d.dot(&(x - p))).norm();
            off(a).total_cmp(&off(b))
        })
        .unwrap_or(p);
    [p, q, r]
}
