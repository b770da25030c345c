//! Convex polyhedra with the topology the witness machinery walks: vertices,
//! faces (outward unit normal, vertex loop counter-clockwise about it),
//! edges (two endpoints, two distinct faces) and the adjacency between them.
//! Body frame throughout.
//!
//! parry builds the hull (`ConvexPolyhedron::from_convex_hull`, which merges
//! coplanar triangles) and serves as the GJK support map. Its own edge list
//! also holds the diagonals of merged faces and its feature classifiers return
//! a wrong edge for 2–4 % of separated hull pairs (research notes §2), so the
//! loops, edges and the support-set classifier here are rebuilt from the
//! merged faces alone.

use nalgebra::Vector3;
use parry3d_f64::shape::ConvexPolyhedron;

use super::convert::{to_glam, to_na};

/// One face: outward unit normal and its vertex loop (counter-clockwise seen
/// from outside), with the edge between loop entries k and k + 1 at
/// `edges[k]`.
#[derive(Debug, Clone, PartialEq)]
pub struct Face {
    /// Outward unit normal, body frame.
    pub normal: Vector3<f64>,
    /// Vertex indices, counter-clockwise about `normal`.
    pub vertices: Vec<u32>,
    /// Edge indices: `edges[k]` joins `vertices[k]` and `vertices[k + 1]`.
    pub edges: Vec<u32>,
}

/// One edge: endpoints and the two faces it separates. `faces[0]` is the face
/// whose loop runs from `vertices[0]` to `vertices[1]`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Edge {
    /// Endpoint vertex indices.
    pub vertices: [u32; 2],
    /// Adjacent faces.
    pub faces: [u32; 2],
}

/// A convex polyhedron (see the module docs).
#[derive(Debug, Clone)]
pub struct Polyhedron {
    hull: ConvexPolyhedron,
    /// Vertex positions, metres, body frame.
    pub vertices: Vec<Vector3<f64>>,
    /// Faces.
    pub faces: Vec<Face>,
    /// Edges (no diagonals of merged faces).
    pub edges: Vec<Edge>,
    /// For each vertex, its edges.
    pub vertex_edges: Vec<Vec<u32>>,
    /// For each vertex, its faces.
    pub vertex_faces: Vec<Vec<u32>>,
    /// Largest vertex distance from the origin, metres.
    pub radius_m: f64,
    /// The distinct edge directions (unit, up to sign): the edge factors of
    /// the separating-axis test (a box has three).
    pub edge_directions: Vec<Vector3<f64>>,
    /// Corners of its axis-aligned bounding box, body frame.
    pub aabb: [Vector3<f64>; 2],
}

/// Why a point set has no usable hull.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum HullError {
    /// Fewer than four points, or all coplanar.
    #[error("the points span no volume (at least four points, not all in one plane, are needed)")]
    Flat,
    /// The hull's topology is not a closed two-manifold.
    #[error("the hull of the points is not a closed surface")]
    NotClosed,
}

impl Polyhedron {
    /// The convex hull of `points` (body frame). Allocates.
    pub fn hull(points: &[Vector3<f64>]) -> Result<Self, HullError> {
        if points.len() < 4 {
            return Err(HullError::Flat);
        }
        let pts: Vec<_> = points.iter().map(to_glam).collect();
        let hull = ConvexPolyhedron::from_convex_hull(&pts).ok_or(HullError::Flat)?;
        Self::from_parry(hull)
    }

    /// A box with half extents `h` centred on the origin, axis-aligned.
    pub fn cuboid(h: [f64; 3]) -> Result<Self, HullError> {
        let mut pts = Vec::with_capacity(8);
        for sx in [-1.0, 1.0] {
            for sy in [-1.0, 1.0] {
                for sz in [-1.0, 1.0] {
                    pts.push(Vector3::new(sx * h[0], sy * h[1], sz * h[2]));
                }
            }
        }
        Self::hull(&pts)
    }

    fn from_parry(hull: ConvexPolyhedron) -> Result<Self, HullError> {
        let vertices: Vec<Vector3<f64>> = hull.points().iter().map(|p| to_na(*p)).collect();
        let adj = hull.vertices_adj_to_face();
        let mut faces = Vec::with_capacity(hull.faces().len());
        for f in hull.faces() {
            let first = f.first_vertex_or_edge as usize;
            let ids = &adj[first..first + f.num_vertices_or_edges as usize];
            let normal = to_na(f.normal).normalize();
            faces.push(Face {
                vertices: ordered_loop(&vertices, ids, &normal),
                normal,
                edges: Vec::new(),
            });
        }
        if faces.len() < 4 || !normal_sane(&faces) {
            return Err(HullError::Flat);
        }
        // Edges from the loops: every directed loop edge a→b must meet its
        // reverse b→a in exactly one other face.
        let mut directed: Vec<(u32, u32, u32, usize)> = Vec::new();
        for (fi, f) in faces.iter().enumerate() {
            let n = f.vertices.len();
            for k in 0..n {
                directed.push((f.vertices[k], f.vertices[(k + 1) % n], fi as u32, k));
            }
        }
        let mut edges: Vec<Edge> = Vec::new();
        let mut slot = vec![u32::MAX; directed.len()];
        let mut index: std::collections::BTreeMap<(u32, u32), usize> = Default::default();
        for (d, &(a, b, _, _)) in directed.iter().enumerate() {
            index.insert((a, b), d);
        }
        for (d, &(a, b, f, _)) in directed.iter().enumerate() {
            if slot[d] != u32::MAX {
                continue;
            }
            let Some(&r) = index.get(&(b, a)) else {
                return Err(HullError::NotClosed);
            };
            let e = edges.len() as u32;
            edges.push(Edge {
                vertices: [a, b],
                faces: [f, directed[r].2],
            });
            slot[d] = e;
            slot[r] = e;
        }
        for (d, &(_, _, f, k)) in directed.iter().enumerate() {
            let face = &mut faces[f as usize];
            if face.edges.len() <= k {
                face.edges.resize(face.vertices.len(), u32::MAX);
            }
            face.edges[k] = slot[d];
        }
        let mut vertex_edges = vec![Vec::new(); vertices.len()];
        for (e, edge) in edges.iter().enumerate() {
            for v in edge.vertices {
                vertex_edges[v as usize].push(e as u32);
            }
        }
        let mut vertex_faces = vec![Vec::new(); vertices.len()];
        for (fi, f) in faces.iter().enumerate() {
            for &v in &f.vertices {
                vertex_faces[v as usize].push(fi as u32);
            }
        }
        let radius_m = vertices.iter().map(|v| v.norm()).fold(0.0, f64::max);
        let mut edge_directions: Vec<Vector3<f64>> = Vec::new();
        for e in &edges {
            let d = (vertices[e.vertices[1] as usize] - vertices[e.vertices[0] as usize])
                .try_normalize(1e-15)
                .unwrap_or_else(Vector3::x);
            if !edge_directions.iter().any(|u| u.cross(&d).norm() < 1e-9) {
                edge_directions.push(d);
            }
        }
        let aabb = [
            vertices
                .iter()
                .fold(Vector3::repeat(f64::INFINITY), |a, v| a.inf(v)),
            vertices
                .iter()
                .fold(Vector3::repeat(f64::NEG_INFINITY), |a, v| a.sup(v)),
        ];
        Ok(Self {
            aabb,
            edge_directions,
            hull,
            vertices,
            faces,
            edges,
            vertex_edges,
            vertex_faces,
            radius_m,
        })
    }

    /// parry's hull (the GJK support map).
    pub fn parry(&self) -> &ConvexPolyhedron {
        &self.hull
    }

    /// True when the box from `lo` to `hi` (body frame) comes within `d`
    /// metres of the bounding box.
    pub fn near_box(&self, lo: &Vector3<f64>, hi: &Vector3<f64>, d: f64) -> bool {
        (0..3).all(|k| lo[k] <= self.aabb[1][k] + d && hi[k] >= self.aabb[0][k] - d)
    }

    /// The other endpoint of `edge` than `v`.
    pub fn other_end(&self, edge: u32, v: u32) -> u32 {
        let e = &self.edges[edge as usize];
        if e.vertices[0] == v {
            e.vertices[1]
        } else {
            e.vertices[0]
        }
    }

    /// Unit direction of an edge, from `vertices[0]` to `vertices[1]`.
    pub fn edge_dir(&self, edge: u32) -> Vector3<f64> {
        let e = &self.edges[edge as usize];
        (self.vertices[e.vertices[1] as usize] - self.vertices[e.vertices[0] as usize]).normalize()
    }

    /// The separating-plane normal of an edge (Choi & Cremer §3.1.2): the
    /// normalised mean of its two face normals. It lies strictly between the
    /// faces' normals, so its dot products with both Voronoi bounding planes
    /// of the edge are positive: the plane through the edge with this normal
    /// is a valid separating plane.
    pub fn edge_normal(&self, edge: u32) -> Vector3<f64> {
        let e = &self.edges[edge as usize];
        let n = self.faces[e.faces[0] as usize].normal + self.faces[e.faces[1] as usize].normal;
        n.try_normalize(1e-12)
            .unwrap_or(self.faces[e.faces[0] as usize].normal)
    }

    /// The separating-plane normal of a vertex (§3.1.3): the normalised mean of
    /// its faces' normals, which points into the vertex's Voronoi cone.
    pub fn vertex_normal(&self, v: u32) -> Vector3<f64> {
        let faces = &self.vertex_faces[v as usize];
        let n: Vector3<f64> = faces.iter().map(|&f| self.faces[f as usize].normal).sum();
        n.try_normalize(1e-12)
            .unwrap_or_else(|| self.vertices[v as usize].normalize())
    }

    /// A point of face `f` (its first vertex).
    pub fn face_point(&self, f: u32) -> Vector3<f64> {
        self.vertices[self.faces[f as usize].vertices[0] as usize]
    }

    /// True when `p` (body frame) projects into face `f`: on the inner side of
    /// every boundary edge, within `eps` metres.
    pub fn in_face_region(&self, f: u32, p: &Vector3<f64>, eps: f64) -> bool {
        self.face_violation(f, p).0 <= eps
    }

    /// How far `p`'s projection lies outside face `f` (metres, ≤ 0 inside) and
    /// the loop position of the boundary edge it is farthest beyond.
    pub fn face_violation(&self, f: u32, p: &Vector3<f64>) -> (f64, usize) {
        let face = &self.faces[f as usize];
        let n = face.vertices.len();
        let mut worst = (f64::NEG_INFINITY, 0);
        for k in 0..n {
            let a = self.vertices[face.vertices[k] as usize];
            let b = self.vertices[face.vertices[(k + 1) % n] as usize];
            let inward = face.normal.cross(&(b - a)).normalize();
            let out = -(p - a).dot(&inward);
            if out > worst.0 {
                worst = (out, k);
            }
        }
        worst
    }

    /// Clips the segment p0→p1 (body frame, near the face's plane) to face
    /// `f`'s prism (Cyrus–Beck on the in-plane half-planes of its boundary
    /// edges): the parameter range [enter, exit] inside, and the loop
    /// position of the boundary edge that bounds each end (`None` where the
    /// endpoint itself is inside). `None` when the segment misses the face.
    pub fn clip_to_face(&self, f: u32, p0: &Vector3<f64>, p1: &Vector3<f64>) -> Option<Clip> {
        let face = &self.faces[f as usize];
        let n = face.vertices.len();
        let d = p1 - p0;
        let mut clip = Clip {
            enter: 0.0,
            enter_edge: None,
            exit: 1.0,
            exit_edge: None,
        };
        for k in 0..n {
            let a = self.vertices[face.vertices[k] as usize];
            let b = self.vertices[face.vertices[(k + 1) % n] as usize];
            let inward = face.normal.cross(&(b - a)).normalize();
            let (h0, dh) = ((p0 - a).dot(&inward), d.dot(&inward));
            if dh.abs() < 1e-15 {
                if h0 < 0.0 {
                    return None;
                }
                continue;
            }
            let s = -h0 / dh;
            if dh > 0.0 {
                if s > clip.enter {
                    clip.enter = s;
                    clip.enter_edge = Some(k);
                }
            } else if s < clip.exit {
                clip.exit = s;
                clip.exit_edge = Some(k);
            }
        }
        (clip.enter <= clip.exit).then_some(clip)
    }

    /// The support-set classifier (research notes §2): the vertices within
    /// `eps` metres of the farthest one along `dir` (body frame). One is a
    /// vertex, two joined by an edge are that edge, more (or two across a
    /// face) are the face whose normal is closest to `dir`.
    pub fn support_feature(&self, dir: &Vector3<f64>, eps: f64) -> Feature {
        let best = self
            .vertices
            .iter()
            .map(|v| v.dot(dir))
            .fold(f64::NEG_INFINITY, f64::max);
        let mut set = [u32::MAX; 2];
        let mut count = 0;
        for (i, v) in self.vertices.iter().enumerate() {
            if v.dot(dir) >= best - eps {
                if count < 2 {
                    set[count] = i as u32;
                }
                count += 1;
            }
        }
        match count {
            1 => Feature::Vertex(set[0]),
            2 => match self.edge_between(set[0], set[1]) {
                Some(e) => Feature::Edge(e),
                None => Feature::Face(self.face_toward(dir)),
            },
            _ => Feature::Face(self.face_toward(dir)),
        }
    }

    /// The edge joining vertices `a` and `b`, if any.
    pub fn edge_between(&self, a: u32, b: u32) -> Option<u32> {
        self.vertex_edges[a as usize]
            .iter()
            .copied()
            .find(|&e| self.other_end(e, a) == b)
    }

    /// The face whose normal has the largest dot product with `dir`.
    pub fn face_toward(&self, dir: &Vector3<f64>) -> u32 {
        let mut best = (f64::NEG_INFINITY, 0);
        for (i, f) in self.faces.iter().enumerate() {
            let d = f.normal.dot(dir);
            if d > best.0 {
                best = (d, i as u32);
            }
        }
        best.1
    }
}

/// The part of a segment inside a face's prism (see
/// [`Polyhedron::clip_to_face`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Clip {
    /// Segment parameter where it enters, in [0, 1].
    pub enter: f64,
    /// Loop position of the boundary edge it enters through (`None`: p0 inside).
    pub enter_edge: Option<usize>,
    /// Segment parameter where it leaves, in [0, 1].
    pub exit: f64,
    /// Loop position of the boundary edge it leaves through (`None`: p1 inside).
    pub exit_edge: Option<usize>,
}

/// A feature of a convex core: an index into its vertices, edges or faces.
/// A point core has `Vertex(0)`; a segment has `Vertex(0)`, `Vertex(1)` and
/// `Edge(0)`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Feature {
    /// A vertex.
    Vertex(u32),
    /// An edge.
    Edge(u32),
    /// A face.
    Face(u32),
}

impl Feature {
    /// 0, 1 or 2.
    pub fn dimension(self) -> u8 {
        match self {
            Feature::Vertex(_) => 0,
            Feature::Edge(_) => 1,
            Feature::Face(_) => 2,
        }
    }
}

/// `ids` ordered counter-clockwise about `normal` (a convex face's vertices
/// sorted by angle about their centroid).
fn ordered_loop(vertices: &[Vector3<f64>], ids: &[u32], normal: &Vector3<f64>) -> Vec<u32> {
    let mut unique: Vec<u32> = ids.to_vec();
    unique.sort_unstable();
    unique.dedup();
    let c: Vector3<f64> = unique
        .iter()
        .map(|&i| vertices[i as usize])
        .sum::<Vector3<f64>>()
        / unique.len() as f64;
    let u = (vertices[unique[0] as usize] - c)
        .try_normalize(1e-15)
        .unwrap_or_else(|| normal.cross(&Vector3::x()).normalize());
    let w = normal.cross(&u);
    let mut keyed: Vec<(f64, u32)> = unique
        .iter()
        .map(|&i| {
            let d = vertices[i as usize] - c;
            (d.dot(&w).atan2(d.dot(&u)), i)
        })
        .collect();
    keyed.sort_by(|a, b| a.0.total_cmp(&b.0));
    keyed.into_iter().map(|(_, i)| i).collect()
}

fn normal_sane(faces: &[Face]) -> bool {
    faces
        .iter()
        .all(|f| f.normal.iter().all(|x| x.is_finite()) && f.vertices.len() >= 3)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_cube_has_eight_vertices_twelve_edges_six_faces() {
        let c = Polyhedron::cuboid([0.1, 0.2, 0.3]).unwrap();
        assert_eq!((c.vertices.len(), c.edges.len(), c.faces.len()), (8, 12, 6));
        for e in &c.edges {
            assert_ne!(e.faces[0], e.faces[1], "a diagonal survived");
            let len =
                (c.vertices[e.vertices[0] as usize] - c.vertices[e.vertices[1] as usize]).norm();
            assert!(
                [0.2, 0.4, 0.6].iter().any(|l| (len - l).abs() < 1e-12),
                "{len}"
            );
        }
        for f in &c.faces {
            assert_eq!(f.vertices.len(), 4);
            // Counter-clockwise about the outward normal.
            let (a, b, cc) = (
                c.vertices[f.vertices[0] as usize],
                c.vertices[f.vertices[1] as usize],
                c.vertices[f.vertices[2] as usize],
            );
            assert!((b - a).cross(&(cc - b)).dot(&f.normal) > 0.0);
            assert!(f.edges.iter().all(|&e| e != u32::MAX));
        }
        for v in 0..8 {
            assert_eq!(c.vertex_edges[v].len(), 3);
            assert_eq!(c.vertex_faces[v].len(), 3);
        }
    }

    #[test]
    fn support_sets_classify_vertex_edge_and_face() {
        let c = Polyhedron::cuboid([1.0, 1.0, 1.0]).unwrap();
        let f = c.support_feature(&Vector3::new(0.0, 0.0, 1.0), 1e-9);
        assert!(matches!(f, Feature::Face(i) if c.faces[i as usize].normal.z > 0.99));
        let e = c.support_feature(&Vector3::new(1.0, 0.0, 1.0).normalize(), 1e-9);
        let Feature::Edge(e) = e else { panic!("{e:?}") };
        let mid = (c.vertices[c.edges[e as usize].vertices[0] as usize]
            + c.vertices[c.edges[e as usize].vertices[1] as usize])
            / 2.0;
        assert!((mid - Vector3::new(1.0, 0.0, 1.0)).norm() < 1e-12);
        let v = c.support_feature(&Vector3::new(1.0, 2.0, 3.0).normalize(), 1e-9);
        let Feature::Vertex(v) = v else {
            panic!("{v:?}")
        };
        assert!((c.vertices[v as usize] - Vector3::new(1.0, 1.0, 1.0)).norm() < 1e-12);
    }

    #[test]
    fn face_regions_and_separating_normals() {
        let c = Polyhedron::cuboid([1.0, 1.0, 1.0]).unwrap();
        let top = c.face_toward(&Vector3::z());
        assert!(c.in_face_region(top, &Vector3::new(0.9, -0.9, 5.0), 0.0));
        assert!(!c.in_face_region(top, &Vector3::new(1.1, 0.0, 5.0), 0.0));
        let (out, _) = c.face_violation(top, &Vector3::new(1.25, 0.0, 2.0));
        assert!((out - 0.25).abs() < 1e-12);
        for e in 0..c.edges.len() as u32 {
            let n = c.edge_normal(e);
            let edge = c.edges[e as usize];
            for f in edge.faces {
                assert!(n.dot(&c.faces[f as usize].normal) > 0.7);
            }
        }
        for v in 0..8 {
            let n = c.vertex_normal(v);
            assert!((n - c.vertices[v as usize].normalize()).norm() < 1e-12);
        }
    }

    #[test]
    fn flat_point_sets_are_refused() {
        let flat = [
            Vector3::new(0.0, 0.0, 0.0),
            Vector3::new(1.0, 0.0, 0.0),
            Vector3::new(0.0, 1.0, 0.0),
            Vector3::new(1.0, 1.0, 0.0),
        ];
        assert!(Polyhedron::hull(&flat).is_err());
        assert!(Polyhedron::hull(&flat[..3]).is_err());
    }
}
