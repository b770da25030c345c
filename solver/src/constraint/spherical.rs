//! Spherical joint (ball joint), Nelson & Cohen Eq. 9:
//! C = (r_i + A_i k_i) − (r_j + A_j k_j) = 0, 3 rows, metres.
//! Free design variables: `anchor_i`, `anchor_j`.

use super::block::{Ctx, Pair, Sink, coincidence_rows};

/// Anchors k_i, k_j coincide.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Spherical {
    pub pair: Pair,
}

impl Spherical {
    pub const ROWS: usize = 3;

    // Always inlined into the fused AL pass: left to the heuristics, it
    // stopped being inlined there when the crate's codegen units were
    // repartitioned (+2.9 % instructions per gradient iteration on the sphere
    // toy, callgrind; with this, the same count as before).
    #[inline(always)]
    pub fn eval<S: Sink>(&self, x: &Ctx, c: &mut [f64], sink: &mut S) {
        coincidence_rows(&self.pair.points(x), 0, c, sink);
    }
}
