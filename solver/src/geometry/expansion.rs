//! Subsequent penetration of other features (Choi & Cremer §3.2.1).
//!
//! A pyramid standing on its apex on a table has one vertex–face witness,
//! the apex on the table top. Tilting it keeps that contact while a base
//! corner next to the apex goes through the table: the witness of the
//! initial contact cannot see it, because up to the penetration the nearest
//! features were the contact itself. When a tracked pair overlaps, the
//! monitor looks at the vertices next to every vertex held on a face (the
//! search "limited to checking adjacent vertices"); those below the face's
//! plane join the held ones, and the witness becomes the higher-dimensional
//! feature that covers both the old contact and the new penetration:
//!
//! ```text
//!  held on face F      violators below F        new witness
//!  {apex}            + {corner}            ─►   edge apex–corner on F (edge–face)
//!  {apex, corner}    + {next corner}       ─►   face apex–corner–next on F (face–face)
//!  {apex}            + {corner, next}      ─►   face on F (face–face at once)
//! ```
//!
//! The new feature pair is reduced to primitives as any edge–face or
//! face–face witness is (§3.1.5). The active set keeps those primitives
//! (the *expanded* ones) while they stay within the pair's window, so the
//! backup that follows a penetration (revert, add, retry, §3.2) retries
//! with them in place.

use super::pair::PairView;
use super::polyhedron::Feature;
use super::primitives::flipped;
use super::primitives::value_at;
use crate::constraint::witness::{PlaneWitness, Witness, edge_face, face_face};

/// A vertex key packed by [`super::pair::pack`] (dimension 0).
const DIM_SHIFT: u32 = 30;
const INDEX_MASK: u32 = (1 << DIM_SHIFT) - 1;

/// The vertices of one polyhedron held on one face of the other by the
/// last cycle's vertex–face primitives.
struct Held {
    /// End of the pair carrying the vertices (0 = A).
    point_end: u8,
    /// The face (of the other end) they are held on.
    face: u32,
    /// The held vertices.
    vertices: Vec<u32>,
}

/// Groups the vertex–face primitives of `prev` by (end, face).
fn held(prev: &[Witness]) -> Vec<Held> {
    let mut groups: Vec<Held> = Vec::new();
    for w in prev {
        let Witness::Plane(p) = w else { continue };
        let pe = p.point_end as usize;
        let (vkey, fkey) = (p.features[pe], p.features[1 - pe]);
        if vkey >> DIM_SHIFT != 0 || fkey >> DIM_SHIFT != 2 {
            continue;
        }
        let face = fkey & INDEX_MASK;
        match groups
            .iter_mut()
            .find(|g| g.point_end == p.point_end && g.face == face)
        {
            Some(g) if !g.vertices.contains(&vkey) => g.vertices.push(vkey),
            Some(_) => {}
            None => groups.push(Held {
                point_end: p.point_end,
                face,
                vertices: vec![vkey],
            }),
        }
    }
    groups
}

/// For every group of vertices held on a face by `prev` (the last cycle's
/// primitives), the vertices adjacent to them that now lie below that
/// face's plane; each group with such violators is expanded to the edge
/// (one held vertex and one violator) or the face (three or more, on one
/// face of their polyhedron) that covers them all, and that feature's
/// primitives are appended to `out`. Returns the number of expansions.
pub(super) fn expand_on_penetration(
    view: &PairView,
    prev: &[Witness],
    out: &mut Vec<Witness>,
) -> u32 {
    let mut made = 0;
    for g in held(prev) {
        let v = if g.point_end == 0 {
            *view
        } else {
            view.swapped()
        };
        let (Some(pp), Some(ps)) = (v.a.polyhedron(), v.b.polyhedron()) else {
            continue;
        };
        if g.face as usize >= ps.faces.len()
            || g.vertices.iter().any(|&h| h as usize >= pp.vertices.len())
        {
            continue;
        }
        let (fp, fnormal) = (ps.face_point(g.face), ps.faces[g.face as usize].normal);
        let margin = v.margin();
        let below = |i: u32| (v.a_in_b(&pp.vertices[i as usize]) - fp).dot(&fnormal) - margin < 0.0;
        let mut violators: Vec<u32> = g
            .vertices
            .iter()
            .flat_map(|&h| {
                pp.vertex_edges[h as usize]
                    .iter()
                    .map(move |&e| pp.other_end(e, h))
            })
            .filter(|nb| !g.vertices.contains(nb) && below(*nb))
            .collect();
        violators.sort_unstable();
        violators.dedup();
        if violators.is_empty() {
            continue;
        }
        let mut set = g.vertices.clone();
        set.extend(&violators);
        let start = out.len();
        if let [a, b] = set[..] {
            let Some(e) = pp.edge_between(a, b) else {
                continue;
            };
            let ends = pp.edges[e as usize].vertices;
            edge_face::reduce(
                &v,
                [pp.vertices[ends[0] as usize], pp.vertices[ends[1] as usize]],
                (
                    [Feature::Vertex(ends[0]), Feature::Vertex(ends[1])],
                    Feature::Edge(e),
                ),
                ps,
                g.face,
                out,
            );
        } else {
            let shared = pp.vertex_faces[set[0] as usize].iter().copied().find(|&f| {
                set.iter()
                    .all(|x| pp.vertex_faces[*x as usize].contains(&f))
            });
            let Some(f) = shared else {
                continue;
            };
            face_face::reduce(&v, pp, f, ps, g.face, out);
        }
        if g.point_end == 1 {
            let a_to_b = view.a_to_b();
            for w in &mut out[start..] {
                *w = flipped(*w, &a_to_b);
            }
        }
        made += 1;
    }
    made
}

/// Appends the primitives of `extra` that `out` does not hold yet (by
/// features).
pub(super) fn merge(out: &mut Vec<Witness>, extra: &[Witness]) {
    for w in extra {
        if !out.iter().any(|o| o.same_features(w)) {
            out.push(*w);
        }
    }
}

/// With the guards on (`ContactSettings::guards`): the expansion as it ran
/// before the guards could be switched off, kept exactly, since the guarded
/// scenes' figures were measured with it. Subsequent penetration (§3.2.1): the cores overlap, so there are no
/// nearest features. For each vertex–face primitive of the last cycle, find
/// the vertices next to its vertex that now lie below its plane; with one,
/// the edge from the contact vertex to it becomes the witness (edge–face),
/// with more, their common face (face–face). Returns the expansions made.
pub(super) fn expand_overlap(view: &PairView, prev: &[Witness], out: &mut Vec<Witness>) -> u32 {
    let mut made = 0;
    for w in prev {
        let Witness::Plane(p) = w else { continue };
        let pe = p.point_end as usize;
        let (vkey, fkey) = (p.features[pe], p.features[1 - pe]);
        if vkey >= 1 << 30 || fkey >> 30 != 2 {
            continue;
        }
        let face = fkey & ((1 << 30) - 1);
        let v = if pe == 0 { *view } else { view.swapped() };
        let (Some(pp), Some(ps)) = (v.a.polyhedron(), v.b.polyhedron()) else {
            continue;
        };
        let start = out.len();
        let violators: Vec<u32> = pp.vertex_edges[vkey as usize]
            .iter()
            .map(|&e| pp.other_end(e, vkey))
            .filter(|&nb| {
                let (val, _) = value_at(
                    &Witness::Plane(PlaneWitness {
                        point: pp.vertices[nb as usize],
                        point_end: 0,
                        ..*p
                    }),
                    &v.pa,
                    &v.pb,
                );
                val < 0.0
            })
            .collect();
        match violators.as_slice() {
            [] => continue,
            [nb] => {
                let Some(e) = pp.edge_between(vkey, *nb) else {
                    continue;
                };
                let ends = pp.edges[e as usize].vertices;
                edge_face::reduce(
                    &v,
                    [pp.vertices[ends[0] as usize], pp.vertices[ends[1] as usize]],
                    (
                        [Feature::Vertex(ends[0]), Feature::Vertex(ends[1])],
                        Feature::Edge(e),
                    ),
                    ps,
                    face,
                    out,
                );
            }
            many => {
                let shared = pp.vertex_faces[vkey as usize].iter().copied().find(|&f| {
                    many.iter()
                        .all(|nb| pp.vertex_faces[*nb as usize].contains(&f))
                });
                match shared {
                    Some(f) => face_face::reduce(&v, pp, f, ps, face, out),
                    None => continue,
                }
            }
        }
        if pe == 1 {
            let a_to_b = view.a_to_b();
            for w in &mut out[start..] {
                *w = flipped(*w, &a_to_b);
            }
        }
        made += 1;
    }
    made
}
