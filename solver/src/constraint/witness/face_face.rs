//! Face–face (Choi & Cremer §3.1.5): two faces lying (nearly) parallel on
//! each other are reduced to primitives: every vertex of either face inside
//! the other face's Voronoi region (prism) gives a vertex–face primitive
//! (with the plane on the other body), and every crossing of the two
//! boundary loops, seen in B's face plane, gives an edge–edge primitive. A
//! box resting on a larger table gets its four corners; a face sliding off
//! an edge swaps corners for edge–edge crossings as they leave (§3.2).

use nalgebra::Vector3;

use super::edge_edge::EdgeWitness;
use super::{PlaneWitness, Witness, WitnessType};
use crate::geometry::pair::{PairView, pack};
use crate::geometry::polyhedron::{Feature, Polyhedron};

/// Vertices this far (metres) outside a prism still count as inside: a
/// corner exactly on the boundary is held rather than dropped.
const REGION_EPS_M: f64 = 1e-9;

/// Face `fa` of A's polyhedron against face `fb` of B's. Pushes every
/// primitive found (the caller keeps at most its slot budget).
pub(crate) fn reduce(
    view: &PairView,
    pa: &Polyhedron,
    fa: u32,
    pb: &Polyhedron,
    fb: u32,
    out: &mut Vec<Witness>,
) {
    let m = view.margin();
    let (face_a, face_b) = (&pa.faces[fa as usize], &pb.faces[fb as usize]);
    let (ka, kb) = (pack(Feature::Face(fa)), pack(Feature::Face(fb)));
    for &v in &face_a.vertices {
        let p = pa.vertices[v as usize];
        if pb.in_face_region(fb, &view.a_in_b(&p), REGION_EPS_M) {
            out.push(Witness::Plane(PlaneWitness {
                origin: WitnessType::FaceFace,
                ..PlaneWitness::vertex_face(0, p, pb.face_point(fb), face_b.normal, m, [v, kb])
            }));
        }
    }
    for &w in &face_b.vertices {
        let p = pb.vertices[w as usize];
        if pa.in_face_region(fa, &view.b_in_a(&p), REGION_EPS_M) {
            out.push(Witness::Plane(PlaneWitness {
                origin: WitnessType::FaceFace,
                ..PlaneWitness::vertex_face(1, p, pa.face_point(fa), face_a.normal, m, [ka, w])
            }));
        }
    }
    // Loop crossings in B's face plane.
    let n = face_b.normal;
    let u = (pb.vertices[face_b.vertices[1] as usize] - pb.vertices[face_b.vertices[0] as usize])
        .normalize();
    let w = n.cross(&u);
    let flat = |p: &Vector3<f64>| (p.dot(&u), p.dot(&w));
    let a_to_b = view.a_to_b();
    for &ea in &face_a.edges {
        let e = pa.edges[ea as usize];
        let a = [
            pa.vertices[e.vertices[0] as usize],
            pa.vertices[e.vertices[1] as usize],
        ];
        let (a0, a1) = (flat(&view.a_in_b(&a[0])), flat(&view.a_in_b(&a[1])));
        for &eb in &face_b.edges {
            let f = pb.edges[eb as usize];
            let b = [
                pb.vertices[f.vertices[0] as usize],
                pb.vertices[f.vertices[1] as usize],
            ];
            if !crosses(a0, a1, flat(&b[0]), flat(&b[1])) {
                continue;
            }
            let faces = [
                pb.faces[f.faces[0] as usize].normal,
                pb.faces[f.faces[1] as usize].normal,
            ];
            let key = [pack(Feature::Edge(ea)), pack(Feature::Edge(eb))];
            if let Some(wit) =
                EdgeWitness::build(0, a, b, faces, pb.edge_normal(eb), &a_to_b, m, key)
            {
                out.push(Witness::EdgeEdge(EdgeWitness {
                    origin: WitnessType::FaceFace,
                    ..wit
                }));
            }
        }
    }
}

/// True when segments p0p1 and q0q1 (2-D) cross at interior points of both.
fn crosses(p0: (f64, f64), p1: (f64, f64), q0: (f64, f64), q1: (f64, f64)) -> bool {
    let cross = |a: (f64, f64), b: (f64, f64)| a.0 * b.1 - a.1 * b.0;
    let sub = |a: (f64, f64), b: (f64, f64)| (a.0 - b.0, a.1 - b.1);
    let (r, s) = (sub(p1, p0), sub(q1, q0));
    let denom = cross(r, s);
    if denom.abs() < 1e-18 {
        return false;
    }
    let qp = sub(q0, p0);
    let t = cross(qp, s) / denom;
    let v = cross(qp, r) / denom;
    (1e-9..1.0 - 1e-9).contains(&t) && (1e-9..1.0 - 1e-9).contains(&v)
}
