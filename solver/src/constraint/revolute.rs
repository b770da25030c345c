//! Revolute joint (hinge): a spherical joint at k_i/k_j (3 rows, metres) plus
//! two perpendicular rows f_i·h_j = 0, g_i·h_j = 0 (dimensionless) that keep the
//! axis A_j h_j parallel to A_i h_i. Removes 5 degrees of freedom.
//! Joint coordinate (for limits): the angle of [`JointAxes::angle`], radians.
//! Free design variables: `anchor_i`, `anchor_j`.

use super::axes::JointAxes;
use super::block::{Ctx, Pair, RowGrad, Sink, coincidence_rows};

/// Hinge about h_i (body i) ≡ h_j (body j) through k_i ≡ k_j.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Revolute {
    pub pair: Pair,
    pub axes: JointAxes,
}

impl Revolute {
    pub const ROWS: usize = 5;

    // Always inlined into the fused AL pass: left to the heuristics, it
    // stopped being inlined there when the crate's codegen units were
    // repartitioned (+2.9 % instructions per gradient iteration on the sphere
    // toy, callgrind; with this, the same count as before).
    #[inline(always)]
    pub fn eval<S: Sink>(&self, x: &Ctx, c: &mut [f64], sink: &mut S) {
        coincidence_rows(&self.pair.points(x), 0, c, sink);
        for (k, (v, g)) in self.axes.alignment_rows(&self.pair, x).iter().enumerate() {
            c[3 + k] = *v;
            sink.row(3 + k, g);
        }
    }

    /// The hinge angle, radians (see [`JointAxes::angle`]).
    #[inline]
    pub fn coordinate(&self, x: &Ctx) -> (f64, RowGrad) {
        self.axes.angle(&self.pair, x)
    }
}
