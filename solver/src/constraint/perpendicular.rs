//! Perpendicular condition, Nelson & Cohen Eq. 10:
//! C = (A_i h_i)ᵀ (A_j h_j) = 0, 1 row, dimensionless (≈ the angle error from
//! 90° in radians). Anchors are not used; no design variables.

use nalgebra::Vector3;

use super::block::{Ctx, Pair, Sink, dot_row};

/// Body-frame axes h_i, h_j (unit) stay at 90°.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Perpendicular {
    pub pair: Pair,
    pub axes: [Vector3<f64>; 2],
}

impl Perpendicular {
    pub const ROWS: usize = 1;

    pub fn eval<S: Sink>(&self, x: &Ctx, c: &mut [f64], sink: &mut S) {
        perpendicular_row(&self.pair, &self.axes, x, 0, c, sink);
    }
}

/// Writes (A_i h_i)·(A_j h_j) at local row `row` (shared with the universal joint).
/// Always inlined: out of line it cost 9 % of a sphere-toy AL iteration.
#[inline(always)]
pub(crate) fn perpendicular_row<S: Sink>(
    pair: &Pair,
    axes: &[Vector3<f64>; 2],
    x: &Ctx,
    row: usize,
    c: &mut [f64],
    sink: &mut S,
) {
    let (v, g) = dot_row(&pair.dir(x, 0, &axes[0]), &pair.dir(x, 1, &axes[1]));
    c[row] = v;
    sink.row(row, &g);
}
