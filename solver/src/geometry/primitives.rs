//! From a nearest-feature pair to witness primitives (Choi & Cremer §3.1),
//! the pre-emptive expansion to nearby features (§3.2, §3.2.1) and the
//! choice of which primitives fill a pair's row slots.
//!
//! Polyhedron against polyhedron follows the paper: separating planes for
//! vertex–edge and vertex–vertex, Eq. 2–3 for edge–edge, reductions for
//! edge–face and face–face. Where a curved core (a sphere's point, a
//! capsule's segment) takes part, the exact distances replace the
//! separating planes (the curved shape's exact support point).

use nalgebra::{Matrix3, Vector3};

use super::convert::Pose3;
use super::narrow::PairQuery;
use super::pair::{PairView, pack};
use super::polyhedron::Feature;
use super::shape::Core;
use crate::constraint::block::{Ctx, Pair, Param3};
use crate::constraint::witness::edge_edge::EdgeWitness;
use crate::constraint::witness::{
    BallWitness, LineWitness, PlaneWitness, Witness, WitnessType, edge_face, face_face,
    vertex_edge, vertex_vertex,
};
use crate::rotation::BodyFrame;

/// Appends the primitives of the nearest features `q.features` of the pair
/// (end 0 = A). Nothing when the query has no features (penetrating cores).
pub fn primitives(view: &PairView, q: &PairQuery, out: &mut Vec<Witness>) {
    let Some((fa, fb)) = q.features else {
        return;
    };
    let m = view.margin();
    let (poly_a, poly_b) = (view.a.polyhedron(), view.b.polyhedron());
    let flat = view.a.margin_m == 0.0 && view.b.margin_m == 0.0;
    let key = [pack(fa), pack(fb)];
    match (fa, fb) {
        (Feature::Vertex(i), Feature::Vertex(j)) => {
            let (va, vb) = (view.a.vertex(i), view.b.vertex(j));
            match poly_b {
                Some(pb) if flat && poly_a.is_some() => out.push(Witness::Plane(
                    vertex_vertex::separating_plane(0, va, vb, pb.vertex_normal(j), m, key),
                )),
                _ => out.push(ball(view, va, vb, m, key)),
            }
        }
        (Feature::Vertex(i), Feature::Edge(e)) => {
            let va = view.a.vertex(i);
            match poly_b {
                Some(pb) if flat => {
                    let [b0, _] = view.b.edge(e);
                    out.push(Witness::Plane(vertex_edge::separating_plane(
                        0,
                        va,
                        b0,
                        pb.edge_normal(e),
                        m,
                        key,
                    )));
                }
                _ => out.push(line(view, 0, va, view.b.edge(e), m, key)),
            }
        }
        (Feature::Edge(e), Feature::Vertex(j)) => {
            let vb = view.b.vertex(j);
            match poly_a {
                Some(pa) if flat => {
                    let [a0, _] = view.a.edge(e);
                    out.push(Witness::Plane(vertex_edge::separating_plane(
                        1,
                        vb,
                        a0,
                        pa.edge_normal(e),
                        m,
                        key,
                    )));
                }
                _ => out.push(line(view, 1, vb, view.a.edge(e), m, key)),
            }
        }
        (Feature::Vertex(i), Feature::Face(f)) => {
            if let Some(pb) = poly_b {
                out.push(Witness::Plane(PlaneWitness::vertex_face(
                    0,
                    view.a.vertex(i),
                    pb.face_point(f),
                    pb.faces[f as usize].normal,
                    m,
                    key,
                )));
            }
        }
        (Feature::Face(f), Feature::Vertex(j)) => {
            if let Some(pa) = poly_a {
                out.push(Witness::Plane(PlaneWitness::vertex_face(
                    1,
                    view.b.vertex(j),
                    pa.face_point(f),
                    pa.faces[f as usize].normal,
                    m,
                    key,
                )));
            }
        }
        (Feature::Edge(ea), Feature::Edge(eb)) => edge_edge(view, q, ea, eb, out),
        (Feature::Edge(e), Feature::Face(f)) => {
            if let Some(pb) = poly_b {
                edge_face::reduce(view, view.a.edge(e), edge_ids(&view.a.core, e), pb, f, out);
            }
        }
        (Feature::Face(f), Feature::Edge(e)) => {
            if let Some(pa) = poly_a {
                let sw = view.swapped();
                let start = out.len();
                edge_face::reduce(&sw, view.b.edge(e), edge_ids(&view.b.core, e), pa, f, out);
                flip_from(out, start, &view.a_to_b());
            }
        }
        (Feature::Face(fa), Feature::Face(fb)) => {
            if let (Some(pa), Some(pb)) = (poly_a, poly_b) {
                face_face::reduce(view, pa, fa, pb, fb, out);
            }
        }
    }
}

fn edge_edge(view: &PairView, q: &PairQuery, ea: u32, eb: u32, out: &mut Vec<Witness>) {
    let m = view.margin();
    let key = [pack(Feature::Edge(ea)), pack(Feature::Edge(eb))];
    let (a, b) = (view.a.edge(ea), view.b.edge(eb));
    if let Some(pb) = view.b.polyhedron() {
        let e = pb.edges[eb as usize];
        let faces = [e.faces[0], e.faces[1]].map(|f| pb.faces[f as usize].normal);
        if let Some(w) =
            EdgeWitness::build(0, a, b, faces, pb.edge_normal(eb), &view.a_to_b(), m, key)
        {
            out.push(Witness::EdgeEdge(w));
            return;
        }
        // Parallel edges: each end of A's edge (clipped to B's edge) against
        // B's edge.
        for p in clipped_ends(view, a, b) {
            if view.a.margin_m == 0.0 {
                out.push(Witness::Plane(vertex_edge::separating_plane(
                    0,
                    p,
                    b[0],
                    pb.edge_normal(eb),
                    m,
                    key,
                )));
            } else {
                out.push(line(view, 0, p, b, m, key));
            }
        }
        return;
    }
    if let Some(pa) = view.a.polyhedron() {
        // B is a capsule's axis: it plays E_A, A's edge carries the faces.
        let e = pa.edges[ea as usize];
        let faces = [e.faces[0], e.faces[1]].map(|f| pa.faces[f as usize].normal);
        let b_to_a = view.a_to_b().transpose();
        if let Some(w) = EdgeWitness::build(1, b, a, faces, pa.edge_normal(ea), &b_to_a, m, key) {
            out.push(Witness::EdgeEdge(w));
            return;
        }
    }
    // Two capsule axes (or parallel): the closest point of A's axis against
    // B's axis line.
    let pa_local = view.pa.local_point(&q.core_point_a);
    out.push(line(view, 0, pa_local, b, m, key));
}

/// The ends of the overlap of A's edge `a` (A's frame) with B's parallel
/// edge `b` (B's frame) along B's edge, as points of A's edge (A's frame).
fn clipped_ends(view: &PairView, a: [Vector3<f64>; 2], b: [Vector3<f64>; 2]) -> [Vector3<f64>; 2] {
    let (a0, a1) = (view.a_in_b(&a[0]), view.a_in_b(&a[1]));
    let axis = b[1] - b[0];
    let len2 = axis.norm_squared().max(1e-30);
    let (ta0, ta1) = ((a0 - b[0]).dot(&axis) / len2, (a1 - b[0]).dot(&axis) / len2);
    if (ta1 - ta0).abs() < 1e-12 {
        return a;
    }
    // Parameters along A's edge where it meets B's edge's ends.
    let to_s = |t: f64| ((t - ta0) / (ta1 - ta0)).clamp(0.0, 1.0);
    let (s0, s1) = (to_s(0.0), to_s(1.0));
    let (lo, hi) = (s0.min(s1), s0.max(s1));
    [a[0] + (a[1] - a[0]) * lo, a[0] + (a[1] - a[0]) * hi]
}

fn edge_ids(core: &Core, e: u32) -> ([Feature; 2], Feature) {
    match core {
        Core::Polyhedron(p) => {
            let v = p.edges[e as usize].vertices;
            (
                [Feature::Vertex(v[0]), Feature::Vertex(v[1])],
                Feature::Edge(e),
            )
        }
        _ => ([Feature::Vertex(0), Feature::Vertex(1)], Feature::Edge(0)),
    }
}

fn ball(view: &PairView, va: Vector3<f64>, vb: Vector3<f64>, m: f64, key: [u32; 2]) -> Witness {
    let d = view.a_in_b(&va) - vb;
    Witness::Ball(BallWitness {
        origin: WitnessType::VertexVertex,
        features: key,
        point_a: va,
        point_b: vb,
        fallback: d.try_normalize(1e-15).unwrap_or_else(Vector3::z),
        margin: m,
    })
}

/// A point on end `point_end` against the line through `seg` on the other.
fn line(
    view: &PairView,
    point_end: u8,
    point: Vector3<f64>,
    seg: [Vector3<f64>; 2],
    m: f64,
    key: [u32; 2],
) -> Witness {
    let dir = (seg[1] - seg[0])
        .try_normalize(1e-15)
        .unwrap_or_else(Vector3::z);
    let p_other = if point_end == 0 {
        view.a_in_b(&point)
    } else {
        view.b_in_a(&point)
    };
    let d = p_other - seg[0];
    let w = d - dir * d.dot(&dir);
    let fallback = w.try_normalize(1e-15).unwrap_or_else(|| {
        dir.cross(&Vector3::x())
            .try_normalize(1e-9)
            .unwrap_or(Vector3::y())
    });
    Witness::Line(LineWitness {
        origin: WitnessType::VertexEdge,
        features: key,
        point_end,
        point,
        line_point: seg[0],
        line_dir: dir,
        fallback,
        margin: m,
    })
}

/// Flips the primitives `out[start..]`, built with the ends exchanged, back
/// into the pair's orientation. `a_to_b` rotates the pair's A frame into B's.
fn flip_from(out: &mut [Witness], start: usize, a_to_b: &Matrix3<f64>) {
    for w in &mut out[start..] {
        *w = flipped(*w, a_to_b);
    }
}

/// `w`, written with the ends exchanged, in the pair's orientation.
pub fn flipped(w: Witness, a_to_b: &Matrix3<f64>) -> Witness {
    match w {
        Witness::Off => Witness::Off,
        Witness::Plane(mut p) => {
            p.point_end ^= 1;
            p.features.swap(0, 1);
            Witness::Plane(p)
        }
        Witness::Line(mut l) => {
            l.point_end ^= 1;
            l.features.swap(0, 1);
            Witness::Line(l)
        }
        Witness::EdgeEdge(mut e) => {
            e.edge_end ^= 1;
            e.features.swap(0, 1);
            Witness::EdgeEdge(e)
        }
        Witness::Ball(b) => Witness::Ball(BallWitness {
            point_a: b.point_b,
            point_b: b.point_a,
            // The old fallback points from old B to old A in old A's… frame
            // of the old end 1 (= new A); the new one points from new B to
            // new A in new B's frame (= old A's frame).
            fallback: -(a_to_b.transpose() * b.fallback),
            features: [b.features[1], b.features[0]],
            ..b
        }),
    }
}

/// The value of primitive `w` at the poses of A and B (metres) and the world
/// point it holds (the point end's point; for edge–edge the edge point).
pub fn value_at(w: &Witness, pa: &Pose3, pb: &Pose3) -> (f64, Vector3<f64>) {
    let frames = [frame(pa), frame(pb)];
    let x = Ctx {
        q: &[],
        frames: &frames,
        targets: &[],
        witnesses: std::slice::from_ref(w),
        flex: &[],
        surfaces: &[],
        rolling: &[],
    };
    let pair = Pair {
        frame: [0, 1],
        col: [None, None],
        anchor: [Param3::Const(Vector3::zeros()); 2],
    };
    let c = [crate::constraint::witness::row(w, &pair, &x).0];
    let point = match w {
        Witness::Off => pa.r,
        Witness::Plane(p) => [pa, pb][p.point_end as usize].point(&p.point),
        Witness::Line(l) => [pa, pb][l.point_end as usize].point(&l.point),
        Witness::Ball(b) => pa.point(&b.point_a),
        Witness::EdgeEdge(e) => [pa, pb][e.edge_end as usize].point(&e.edge_point),
    };
    (c[0], point)
}

fn frame(p: &Pose3) -> BodyFrame {
    BodyFrame {
        r: p.r,
        rot: p.rot,
        omega: nalgebra::Matrix3x4::zeros(),
    }
}

/// Pre-emptive expansion (§3.2, §3.2.1 without waiting for penetration):
/// every vertex of either polyhedron within `reach` metres of a face of the
/// other, over that face, gets a vertex–face primitive against it (for a
/// convex body, being outside any one face's plane is being outside the
/// body). That covers the tilting pyramid's base corners before they
/// touch the table, a tilting cube's diagonal corner two edges from the
/// contact, and the end vertices of an edge–edge witness that a rotation
/// about the crossing would swing into a face — all before the next cycle.
/// Duplicates of primitives already in `out` are skipped; `select` keeps
/// the most critical within the slot budget. `depth_m` is how deep the two
/// bodies overlap now (0 when apart); `cones`: the edge guards' normal-cone
/// test ([`super::ContactSettings::edge_cones`]).
pub fn expand(view: &PairView, reach: f64, depth_m: f64, cones: bool, out: &mut Vec<Witness>) {
    let (Some(pa), Some(pb)) = (view.a.polyhedron(), view.b.polyhedron()) else {
        return;
    };
    let m = view.margin();
    for point_end in [0u8, 1u8] {
        let (pp, ps, pose_p, pose_s) = if point_end == 0 {
            (pa, pb, view.pa, view.pb)
        } else {
            (pb, pa, view.pb, view.pa)
        };
        for (v, vertex) in pp.vertices.iter().enumerate() {
            let local = pose_s.local_point(&pose_p.point(vertex));
            if !ps.near_box(&local, &local, reach + m) {
                continue;
            }
            // Among the faces whose prism holds the vertex (a face it could
            // land on), the one it is farthest outside; a vertex over no face
            // (beyond an edge) is left to the edge guards. Two equal boxes
            // stacked corner on corner sit on three planes at once: only the
            // face under the corner is the right one to hold it against.
            // Strictly over the face (by a millionth of the body's size): a
            // corner exactly on a face's boundary, as where two equal boxes
            // stand corner on corner, lies over two faces at once, and which
            // one should hold it is the reduction's business, not a guard's.
            let inside = -1e-6 * ps.radius_m;
            let (mut best, mut face) = (f64::NEG_INFINITY, u32::MAX);
            for (f, fc) in ps.faces.iter().enumerate() {
                let d = (local - ps.face_point(f as u32)).dot(&fc.normal);
                if d > best && ps.in_face_region(f as u32, &local, inside) {
                    (best, face) = (d, f as u32);
                }
            }
            if face == u32::MAX {
                continue;
            }
            if best - m >= reach {
                continue;
            }
            let fkey = pack(Feature::Face(face));
            let features = if point_end == 0 {
                [v as u32, fkey]
            } else {
                [fkey, v as u32]
            };
            let dup = out.iter().any(|w| match w {
                Witness::Plane(q) => q.features == features && q.point_end == point_end,
                _ => false,
            });
            if !dup {
                out.push(Witness::Plane(PlaneWitness::vertex_face(
                    point_end,
                    *vertex,
                    ps.face_point(face),
                    ps.faces[face as usize].normal,
                    m,
                    features,
                )));
            }
        }
    }
    super::guards::edge_guards(view, pa, pb, reach, depth_m, cones, out);
}

/// Keeps at most `slots` of `out`: the one nearest to violation first, then
/// repeatedly the one whose held point is farthest from those kept (a
/// spread support, e.g. a box face's four corners).
pub fn select(view: &PairView, slots: usize, out: &mut Vec<Witness>) {
    if out.len() <= slots {
        return;
    }
    let vals: Vec<(f64, Vector3<f64>)> = out
        .iter()
        .map(|w| value_at(w, &view.pa, &view.pb))
        .collect();
    let first = (0..out.len())
        .min_by(|&i, &j| vals[i].0.total_cmp(&vals[j].0))
        .unwrap_or(0);
    let mut keep = vec![first];
    while keep.len() < slots {
        let next = (0..out.len())
            .filter(|i| !keep.contains(i))
            .max_by(|&i, &j| {
                let d = |k: usize| {
                    keep.iter()
                        .map(|&s| (vals[k].1 - vals[s].1).norm())
                        .fold(f64::INFINITY, f64::min)
                };
                d(i).total_cmp(&d(j))
            });
        match next {
            Some(n) => keep.push(n),
            None => break,
        }
    }
    keep.sort_unstable();
    let kept: Vec<Witness> = keep.iter().map(|&i| out[i]).collect();
    *out = kept;
}
