//! Contact witnesses as constraint rows (Choi & Cremer §3.1): each nearest-
//! feature pair of two convex bodies becomes one or more **primitive**
//! inequalities C ≥ 0 (metres), one kind per file:
//!
//! | file | witness | primitive row |
//! |---|---|---|
//! | `vertex_face.rs` | vertex–face | N·(P − P₀) − m ≥ 0, Eq. 1 (also the row form of the separating planes) |
//! | `vertex_edge.rs` | vertex–edge | separating plane through the edge, normal = mean of its faces' normals (§3.1.2); curved: exact distance to the line − m |
//! | `vertex_vertex.rs` | vertex–vertex | separating plane through the vertex, normal = mean of its faces' normals (§3.1.3); curved: exact distance − m |
//! | `edge_edge.rs` | edge–edge | the intersection point IP of A's edge line with a face plane of B's edge (Eq. 2) outside B's separating plane (Eq. 3) |
//! | `edge_face.rs` | edge–face | reduced to vertex–face and edge–edge primitives (§3.1.5) |
//! | `face_face.rs` | face–face | reduced to vertex–face and edge–edge primitives (§3.1.5) |
//! | `friction.rs` | — | a stick row at a finger contact: t·(P − P₀) = 0 while the Coulomb cone holds |
//!
//! m is the sum of the two shapes' margins (a sphere's or capsule's radius:
//! curved shapes act through their exact support point, the core point
//! offset by the radius along the normal). Every primitive keeps its
//! parameters in body frames, so the row is analytic in q between the slow
//! loop's witness updates; its Jacobian is written through the shared block
//! helpers and checked against central differences.
//!
//! A witness **slot** is a row of the model whose parameters live in the
//! [`Evaluation`](crate::Evaluation)'s witness table, not in the immutable
//! model: the slow loop changes features without changing the sparsity
//! pattern (a slot always touches its pair's two bodies). An unused slot is
//! [`Witness::Off`]: value [`OFF_VALUE_M`], zero gradient, never active.

pub(crate) mod edge_edge;
pub(crate) mod edge_face;
pub(crate) mod face_face;
pub(crate) mod friction;
pub(crate) mod vertex_edge;
pub(crate) mod vertex_face;
pub(crate) mod vertex_vertex;

pub use edge_edge::EdgeWitness;
pub use vertex_edge::LineWitness;
pub use vertex_face::PlaneWitness;
pub use vertex_vertex::BallWitness;

use super::block::{Ctx, Pair, RowGrad, Sink};

/// Value of an unused slot, metres: far from any contact, so the row is never
/// active and never counts as penetrating.
pub const OFF_VALUE_M: f64 = 1.0;

/// Which of Choi & Cremer's six nearest-feature cases a primitive came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum WitnessType {
    /// §3.1.1.
    VertexFace,
    /// §3.1.2.
    VertexEdge,
    /// §3.1.3.
    VertexVertex,
    /// §3.1.4.
    EdgeEdge,
    /// §3.1.5, reduced.
    EdgeFace,
    /// §3.1.5, reduced.
    FaceFace,
    /// A friction stick row (not a witness type of the paper).
    Friction,
    /// A semantic surface row (`constraint/surface.rs`; not a contact).
    Surface,
}

impl WitnessType {
    /// Lower-case name for reports.
    pub fn as_str(self) -> &'static str {
        match self {
            Self::VertexFace => "vertex-face",
            Self::VertexEdge => "vertex-edge",
            Self::VertexVertex => "vertex-vertex",
            Self::EdgeEdge => "edge-edge",
            Self::EdgeFace => "edge-face",
            Self::FaceFace => "face-face",
            Self::Friction => "friction",
            Self::Surface => "surface",
        }
    }
}

/// The parameters of one witness row (body frames of the pair's two ends).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum Witness {
    /// An unused slot.
    #[default]
    Off,
    /// A point kept on the positive side of a plane.
    Plane(PlaneWitness),
    /// A point kept `margin` away from a point (curved vertex–vertex).
    Ball(BallWitness),
    /// A point kept `margin` away from a line (curved vertex–edge).
    Line(LineWitness),
    /// Eq. 2–3.
    EdgeEdge(EdgeWitness),
}

impl Witness {
    /// The witness type this primitive came from (`None` when off).
    pub fn origin(&self) -> Option<WitnessType> {
        match self {
            Witness::Off => None,
            Witness::Plane(w) => Some(w.origin),
            Witness::Ball(w) => Some(w.origin),
            Witness::Line(w) => Some(w.origin),
            Witness::EdgeEdge(w) => Some(w.origin),
        }
    }

    /// True for a used slot.
    pub fn is_on(&self) -> bool {
        !matches!(self, Witness::Off)
    }

    /// Same features and kind, parameters within `tol` metres (a slow-loop
    /// refresh that only moved a contact point along its face is not a
    /// witness change).
    pub fn same_features(&self, other: &Witness) -> bool {
        match (self, other) {
            (Witness::Off, Witness::Off) => true,
            (Witness::Plane(a), Witness::Plane(b)) => a.features == b.features,
            (Witness::Ball(a), Witness::Ball(b)) => a.features == b.features,
            (Witness::Line(a), Witness::Line(b)) => a.features == b.features,
            (Witness::EdgeEdge(a), Witness::EdgeEdge(b)) => a.features == b.features,
            _ => false,
        }
    }
}

/// A feature pair identity for change detection: (kind and index on A, on B),
/// packed as `dimension << 30 | index`.
pub type FeatureKey = [u32; 2];

/// A contact constraint of the model: `rows` witness rows of one pair, row r
/// reading entry `first_slot + r` of the evaluation's witness table.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct ContactRows {
    pub pair: Pair,
    pub first_slot: u32,
    pub rows: u32,
}

impl ContactRows {
    pub fn eval<S: Sink>(&self, x: &Ctx, c: &mut [f64], sink: &mut S) {
        for (r, cr) in c.iter_mut().enumerate().take(self.rows as usize) {
            let w = x
                .witnesses
                .get(self.first_slot as usize + r)
                .copied()
                .unwrap_or_default();
            let (v, g) = row(&w, &self.pair, x);
            *cr = v;
            sink.row(r, &g);
        }
    }
}

/// Value and gradient of one witness at the context's frames. Always
/// inlined: in a value-only evaluation (`NoJacobian`, every projected step)
/// the gradient is then dead code and not computed.
#[inline(always)]
pub(crate) fn row(w: &Witness, pair: &Pair, x: &Ctx) -> (f64, RowGrad) {
    match w {
        Witness::Off => (OFF_VALUE_M, RowGrad::default()),
        Witness::Plane(p) => p.row(pair, x),
        Witness::Ball(b) => b.row(pair, x),
        Witness::Line(l) => l.row(pair, x),
        Witness::EdgeEdge(e) => e.row(pair, x),
    }
}

/// Frame indices `[point end, plane end]` for a primitive whose point is on
/// `point_end` (0 or 1).
#[inline]
pub(crate) fn ends(point_end: u8) -> (usize, usize) {
    if point_end == 0 { (0, 1) } else { (1, 0) }
}
