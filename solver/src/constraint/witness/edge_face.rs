//! Edge–face (Choi & Cremer §3.1.5): an edge of A lying (nearly) parallel on
//! a face of B is reduced to primitives. Each endpoint of the edge inside the
//! face's Voronoi region (its prism) gives a vertex–face primitive; where the
//! edge leaves the prism through a boundary edge of the face, that endpoint's
//! place is taken by an edge–edge primitive with the boundary edge ("if the
//! edge penetrates one of the Voronoi boundary planes of the face, the case
//! is reduced to one edge-edge case and one vertex-face case").
//!
//! The boundary edge is found by clipping the edge to the face prism
//! (Cyrus–Beck over the face's loop), which is the adjacency walk of §3.2:
//! a sliding edge leaves through the loop edge next to the one it entered.

use nalgebra::Vector3;

use super::edge_edge::EdgeWitness;
use super::{PlaneWitness, Witness, WitnessType, vertex_edge};
use crate::geometry::pair::{PairView, pack};
use crate::geometry::polyhedron::{Feature, Polyhedron};

/// An edge of A (its two points in A's frame and the feature ids of its
/// endpoints and itself) against face `face` of B's polyhedron `poly_b`.
/// Pushes one or two primitives (end 0 = A).
pub(crate) fn reduce(
    view: &PairView,
    edge: [Vector3<f64>; 2],
    ids: ([Feature; 2], Feature),
    poly_b: &Polyhedron,
    face: u32,
    out: &mut Vec<Witness>,
) {
    let m = view.margin();
    let f = &poly_b.faces[face as usize];
    let (fp, fnormal) = (poly_b.face_point(face), f.normal);
    let face_key = pack(Feature::Face(face));
    let (p0, p1) = (view.a_in_b(&edge[0]), view.a_in_b(&edge[1]));
    let Some(clip) = poly_b.clip_to_face(face, &p0, &p1) else {
        // The edge misses the prism (only within the parallel tolerance):
        // hold its endpoint nearer the face's plane.
        let k = if (p0 - fp).dot(&fnormal) <= (p1 - fp).dot(&fnormal) {
            0
        } else {
            1
        };
        out.push(Witness::Plane(PlaneWitness {
            origin: WitnessType::EdgeFace,
            ..PlaneWitness::vertex_face(0, edge[k], fp, fnormal, m, [pack(ids.0[k]), face_key])
        }));
        return;
    };
    let a_to_b = view.a_to_b();
    for (end, s, boundary) in [
        (0, clip.enter, clip.enter_edge),
        (1, clip.exit, clip.exit_edge),
    ] {
        match boundary {
            None => out.push(Witness::Plane(PlaneWitness {
                origin: WitnessType::EdgeFace,
                ..PlaneWitness::vertex_face(
                    0,
                    edge[end],
                    fp,
                    fnormal,
                    m,
                    [pack(ids.0[end]), face_key],
                )
            })),
            Some(k) => {
                let be = f.edges[k];
                let e = poly_b.edges[be as usize];
                let b = [
                    poly_b.vertices[e.vertices[0] as usize],
                    poly_b.vertices[e.vertices[1] as usize],
                ];
                let faces = [
                    poly_b.faces[e.faces[0] as usize].normal,
                    poly_b.faces[e.faces[1] as usize].normal,
                ];
                let sep = poly_b.edge_normal(be);
                let key = [pack(ids.1), pack(Feature::Edge(be))];
                match EdgeWitness::build(0, edge, b, faces, sep, &a_to_b, m, key) {
                    Some(w) => out.push(Witness::EdgeEdge(EdgeWitness {
                        origin: WitnessType::EdgeFace,
                        ..w
                    })),
                    None => {
                        // A's edge runs along the boundary edge: hold the point
                        // where it crosses out of the prism against the
                        // boundary edge's separating plane.
                        let point = edge[0] + (edge[1] - edge[0]) * s;
                        out.push(Witness::Plane(PlaneWitness {
                            origin: WitnessType::EdgeFace,
                            ..vertex_edge::separating_plane(0, point, b[0], sep, m, key)
                        }));
                    }
                }
            }
        }
    }
}
