//! Universal (Hooke) joint, Nelson & Cohen Eq. 11: a spherical joint (3 rows,
//! metres) plus the perpendicular condition on the two cross axes (1 row,
//! dimensionless). Removes 4 degrees of freedom.
//! Free design variables: `anchor_i`, `anchor_j`.

use nalgebra::Vector3;

use super::block::{Ctx, Pair, Sink, coincidence_rows};
use super::perpendicular::perpendicular_row;

/// Spherical at k_i/k_j plus h_i ⟂ h_j.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Universal {
    pub pair: Pair,
    pub axes: [Vector3<f64>; 2],
}

impl Universal {
    pub const ROWS: usize = 4;

    // Always inlined into the fused AL pass: left to the heuristics, it
    // stopped being inlined there when the crate's codegen units were
    // repartitioned (+2.9 % instructions per gradient iteration on the sphere
    // toy, callgrind; with this, the same count as before).
    #[inline(always)]
    pub fn eval<S: Sink>(&self, x: &Ctx, c: &mut [f64], sink: &mut S) {
        coincidence_rows(&self.pair.points(x), 0, c, sink);
        perpendicular_row(&self.pair, &self.axes, x, 3, c, sink);
    }
}
