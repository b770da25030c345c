//! Edge–edge guards (§3.2's pre-emptive rows, extended to edges): every
//! pair of edges of two polyhedra that could cross before the next cycle
//! gets the Eq. 2–3 primitive of that edge pair. Called by
//! [`super::primitives::expand`] after the vertex guards.

use nalgebra::{Matrix3, Vector3};

use super::pair::{PairView, pack};
use super::polyhedron::{Feature, Polyhedron};
use super::primitives::value_at;
use crate::constraint::witness::Witness;
use crate::constraint::witness::edge_edge::EdgeWitness;

/// Edge–edge guards: every edge of A whose closest approach to an edge of B
/// is within `reach` and falls inside both edges (two edges that could cross
/// before the next cycle; within 5 % of an end whose vertex has a
/// vertex–face row, that row holds instead), and with `cones` only if it
/// can meet it edge on edge ([`edges_can_meet`]), gets the Eq. 2–3
/// primitive of that edge pair. A rotation of up to the speed limit
/// between two cycles can sweep an edge across an edge without any vertex
/// coming near a face.
pub(super) fn edge_guards(
    view: &PairView,
    pa: &Polyhedron,
    pb: &Polyhedron,
    reach: f64,
    depth_m: f64,
    cones: bool,
    out: &mut Vec<Witness>,
) {
    let m = view.margin();
    let near_b = edges_near(view, pa, pb, reach + m);
    if near_b.is_empty() {
        return;
    }
    let g = Guards {
        view,
        pa,
        pb,
        reach,
        depth_m,
        cones,
        m,
        a_to_b: view.a_to_b(),
        held_a: held_vertices(out, 0, pa.vertices.len()),
        held_b: held_vertices(out, 1, pb.vertices.len()),
    };
    for ea in 0..pa.edges.len() {
        let Some(a) = g.edge_of_a(ea) else {
            continue;
        };
        for &eb in &near_b {
            if let Some(w) = g.guard(&a, eb, out) {
                out.push(w);
            }
        }
    }
}

/// B's edges near A's bounding box (within `within` m): only those can come
/// within reach (a hull of 20 vertices has ~50 edges: all pairs cost 30 µs).
fn edges_near(view: &PairView, pa: &Polyhedron, pb: &Polyhedron, within: f64) -> Vec<usize> {
    (0..pb.edges.len())
        .filter(|&eb| {
            let f = pb.edges[eb];
            let (b0, b1) = (
                view.b_in_a(&pb.vertices[f.vertices[0] as usize]),
                view.b_in_a(&pb.vertices[f.vertices[1] as usize]),
            );
            pa.near_box(&b0.inf(&b1), &b0.sup(&b1), within)
        })
        .collect()
}

/// One pair's guard search: the pair, its reach and overlap, and which
/// vertices already have a vertex–face row.
struct Guards<'a> {
    view: &'a PairView<'a>,
    pa: &'a Polyhedron,
    pb: &'a Polyhedron,
    reach: f64,
    depth_m: f64,
    cones: bool,
    m: f64,
    a_to_b: Matrix3<f64>,
    held_a: Vec<bool>,
    held_b: Vec<bool>,
}

/// An edge of A: its index, its ends in A's frame and in B's.
struct EdgeOfA {
    index: usize,
    local: [Vector3<f64>; 2],
    in_b: [Vector3<f64>; 2],
}

impl Guards<'_> {
    /// A's edge `ea` if it is near B's bounding box.
    fn edge_of_a(&self, ea: usize) -> Option<EdgeOfA> {
        let e = self.pa.edges[ea];
        let local = [
            self.pa.vertices[e.vertices[0] as usize],
            self.pa.vertices[e.vertices[1] as usize],
        ];
        let in_b = [self.view.a_in_b(&local[0]), self.view.a_in_b(&local[1])];
        let (a0, a1) = (in_b[0], in_b[1]);
        self.pb
            .near_box(&a0.inf(&a1), &a0.sup(&a1), self.reach + self.m)
            .then_some(EdgeOfA {
                index: ea,
                local,
                in_b,
            })
    }

    /// The guard of A's edge `a` and B's edge `eb`, if they could cross
    /// before the next cycle and no row in `out` holds them already.
    fn guard(&self, a: &EdgeOfA, eb: usize, out: &[Witness]) -> Option<Witness> {
        let (pa, pb, m) = (self.pa, self.pb, self.m);
        let (e, f) = (pa.edges[a.index], pb.edges[eb]);
        let b = [
            pb.vertices[f.vertices[0] as usize],
            pb.vertices[f.vertices[1] as usize],
        ];
        let [a0, a1] = a.in_b;
        let (s, t, d) = segment_closest(a0, a1, b[0], b[1])?;
        // The closest approach must fall inside both edges (beyond an
        // end the lines meet where the edges do not). Near an end, that
        // end's vertex guard holds the pair if it has one; a vertex over
        // no face of the other body (a stacked box's corner beyond the
        // edge of the box below) has none, and only this edge pair can
        // hold it (BENCHMARKS.md, issue 23, "edge guards at the corners").
        let inside = |u: f64| u > 0.0 && u < 1.0;
        let end_held = |u: f64, ends: [u32; 2], held: &[bool]| {
            (u < 0.05 && held[ends[0] as usize]) || (u > 0.95 && held[ends[1] as usize])
        };
        if d - m >= self.reach
            || !inside(s)
            || !inside(t)
            || end_held(s, e.vertices, &self.held_a)
            || end_held(t, f.vertices, &self.held_b)
        {
            return None;
        }
        let key = [
            pack(Feature::Edge(a.index as u32)),
            pack(Feature::Edge(eb as u32)),
        ];
        if out.iter().any(|w| match w {
            Witness::EdgeEdge(x) => x.features == key,
            _ => false,
        }) {
            return None;
        }
        let faces = [
            pb.faces[f.faces[0] as usize].normal,
            pb.faces[f.faces[1] as usize].normal,
        ];
        let faces_a = [
            self.a_to_b * pa.faces[e.faces[0] as usize].normal,
            self.a_to_b * pa.faces[e.faces[1] as usize].normal,
        ];
        if self.cones && !edges_can_meet(a1 - a0, faces_a, b[1] - b[0], faces) {
            return None;
        }
        let sep = pb.edge_normal(eb as u32);
        let w = EdgeWitness::build(0, a.local, b, faces, sep, &self.a_to_b, m, key)?;
        // Eq. 3 holds only where this pair of edges is the one that would
        // collide: a guard whose row reads deeper than the bodies overlap
        // (`depth_m`, 0 when they are apart) sees the crossing from the
        // wrong side of the separating plane and would push the bodies
        // for nothing.
        let w = Witness::EdgeEdge(w);
        let (value, _) = value_at(&w, &self.view.pa, &self.view.pb);
        (value >= -self.depth_m - 1e-9 && value - m < self.reach).then_some(w)
    }
}

/// How far outside an edge's normal cone (the arc between its two faces'
/// normals) the normal of an edge–edge contact may lie, rad: a box tilted
/// on the edge of another meets it with the normal that far off one cone
/// (0.01 rad in `solver/tests/contact/corners.rs`).
const CONE_SLACK_RAD: f64 = std::f64::consts::FRAC_PI_6;

/// Two edges (directions `da`, `db`, their faces' outward normals, all in
/// B's frame) can touch edge on edge: the normal of the plane they span,
/// n = ±da × db, lies in B's normal cone and −n in A's, within
/// [`CONE_SLACK_RAD`] (the Gauss-map test of a Minkowski-difference face).
/// Otherwise the bodies cannot meet along that edge pair, and Eq. 3's
/// separating plane through B's edge is no plane between them: a side edge
/// of a stacked box standing on the top edge of the box below, their
/// corners within microns, gives a vertical plane at 45° that reads the
/// column's sideways offset as a penetration and pushes the boxes apart
/// sideways (BENCHMARKS.md, issue 23, "the throws").
fn edges_can_meet(
    da: Vector3<f64>,
    faces_a: [Vector3<f64>; 2],
    db: Vector3<f64>,
    faces_b: [Vector3<f64>; 2],
) -> bool {
    let Some(n) = da.cross(&db).try_normalize(1e-12) else {
        return false;
    };
    let n = if n.dot(&(faces_b[0] + faces_b[1])) >= 0.0 {
        n
    } else {
        -n
    };
    within_cone(&n, faces_b) && within_cone(&-n, faces_a)
}

/// `n` (unit, perpendicular to the edge like its faces' normals) within
/// [`CONE_SLACK_RAD`] of the arc between the two face normals.
fn within_cone(n: &Vector3<f64>, faces: [Vector3<f64>; 2]) -> bool {
    let Some(mid) = (faces[0] + faces[1]).try_normalize(1e-12) else {
        return true;
    };
    let half = faces[0].dot(&mid).clamp(-1.0, 1.0).acos();
    n.dot(&mid).clamp(-1.0, 1.0).acos() <= half + CONE_SLACK_RAD
}

/// Per vertex of end `point_end`'s polyhedron: held against a face of the
/// other body by a vertex–face primitive in `out`.
fn held_vertices(out: &[Witness], point_end: u8, n: usize) -> Vec<bool> {
    let mut held = vec![false; n];
    for w in out {
        if let Witness::Plane(p) = w {
            let (v, other) = if point_end == 0 {
                (p.features[0], p.features[1])
            } else {
                (p.features[1], p.features[0])
            };
            if p.point_end == point_end && v >> 30 == 0 && other >> 30 == 2 && (v as usize) < n {
                held[v as usize] = true;
            }
        }
    }
    held
}

/// Closest points of segments p0p1 and q0q1: parameters (s, t) and
/// distance; `None` for (nearly) parallel segments, whose crossing is not a
/// point.
fn segment_closest(
    p0: Vector3<f64>,
    p1: Vector3<f64>,
    q0: Vector3<f64>,
    q1: Vector3<f64>,
) -> Option<(f64, f64, f64)> {
    let (d1, d2, r) = (p1 - p0, q1 - q0, p0 - q0);
    let (a, e, f) = (d1.dot(&d1), d2.dot(&d2), d2.dot(&r));
    let (b, c) = (d1.dot(&d2), d1.dot(&r));
    let denom = a * e - b * b;
    if denom <= 1e-12 * a * e {
        return None;
    }
    let s = ((b * f - c * e) / denom).clamp(0.0, 1.0);
    let t = ((b * s + f) / e).clamp(0.0, 1.0);
    let s = ((b * t - c) / a).clamp(0.0, 1.0);
    let d = ((p0 + d1 * s) - (q0 + d2 * t)).norm();
    Some((s, t, d))
}
