//! Point–plane distance N·(P − P₀), 1 row, metres, shared by two constraint
//! kinds that differ only in sense:
//! - the `point_on_plane` joint (equality, surface attachment
//!   n₂·((r₁ + A₁c₁) − p₂) = 0): body i carries the point k_i, body j carries
//!   the plane through k_j with unit normal h_j;
//! - the point–plane **inequality** N·P ≥ 0 of a contact witness (Choi &
//!   Cremer §3): the point on one body stays on the positive side of a plane
//!   attached to another body or to the world.
//!
//! Free design variables (joint only): `anchor_i` (the point), `anchor_j` (a
//! point of the plane).

use nalgebra::Vector3;

use super::block::{Ctx, Pair, Sink, separation_row};

/// Point anchor k_i on end 0; plane through anchor k_j with unit body-frame
/// normal `normal` on end 1 (a fixed body or the world for a static plane).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct PointPlane {
    pub pair: Pair,
    pub normal: Vector3<f64>,
}

impl PointPlane {
    pub const ROWS: usize = 1;

    pub fn eval<S: Sink>(&self, x: &Ctx, c: &mut [f64], sink: &mut S) {
        let n = self.pair.dir(x, 1, &self.normal);
        let (v, g) = separation_row(1, &n, &self.pair.points(x));
        c[0] = v;
        sink.row(0, &g);
    }
}
