//! Semantic surface constraints as rows (Gösele & Stuerzlinger §3.1.1,
//! DESIGN §4.7): a satisfied constraint between a binding area b (end 0,
//! the bound body) and an offer area a (end 1, the offering body) is
//!
//! ```text
//!  plane:     n_a·(P_k − P_a) − m_k = 0   for three points P_k of b      (SurfacePlane, 3 rows)
//!  inclusion: e_j·(V_i − E_j) − m_ij ≥ 0  for each vertex V_i of b and
//!                                          each edge j of a (inward e_j)  (SurfaceInclusion)
//! ```
//!
//! Three non-collinear points on a's plane make the areas coplanar with
//! their orientation vectors anti-parallel (the other solution, the binding
//! flipped through the plane, is half a turn away); the translation along
//! the plane and the rotation about its normal stay free, which is exactly
//! the motion Algorithm 2 (checkMove) allows a body bound by one constraint.
//! The inclusion rows keep b inside a (a convex offer polygon: a vertex
//! inside every edge's half-plane is inside the polygon, and a polygon whose
//! vertices are inside is inside).
//!
//! Every row is a vertex–face primitive ([`PlaneWitness`](super::witness::PlaneWitness):
//! value, analytic Jacobian, body frames), so it shares the contact rows'
//! algebra; its parameters live at the **tail** of the evaluation's witness
//! table, after the contact slots, `from_end` entries before its end (a
//! contact active set that grows the table's head never moves them). The
//! margin m is the row's **snap offset**: the fast loop ramps it from the
//! misalignment the constraint was satisfied with down to zero at a bounded
//! speed (`program/semantic.rs`), so a snap is a short pull, never a jump.

use super::block::{Ctx, Pair, Sink};
use super::witness::{Witness, row};

/// Rows reading consecutive entries of the witness table's tail.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct SurfaceRows {
    /// End 0: the binding area's body (the points); end 1: the offer's.
    pub pair: Pair,
    /// The first row's entry is `table.len() − from_end`.
    pub from_end: u32,
    /// Number of rows.
    pub rows: u32,
}

impl SurfaceRows {
    pub fn eval<S: Sink>(&self, x: &Ctx, c: &mut [f64], sink: &mut S) {
        let first = x.witnesses.len().saturating_sub(self.from_end as usize);
        for (r, cr) in c.iter_mut().enumerate().take(self.rows as usize) {
            // A table without the entry (never built so) reads as an unused
            // slot: a large value, no gradient, never a panic.
            let w = x.witnesses.get(first + r).copied().unwrap_or(Witness::Off);
            let (v, g) = row(&w, &self.pair, x);
            *cr = v;
            sink.row(r, &g);
        }
    }
}
