//! Prismatic joint (slider) along h_i: five rows.
//! - f_i·d = 0, g_i·d = 0 with d = p_j − p_i (anchor j relative to anchor i),
//!   metres: anchor j stays on the line through anchor i along A_i h_i;
//! - f_i·h_j = 0, g_i·h_j = 0, dimensionless: the axes stay parallel;
//! - g_i·m_j = 0, dimensionless: no twist about the axis.
//!
//! Joint coordinate (for limits): the displacement s = (A_i h_i)·(p_j − p_i),
//! metres, zero when the anchors coincide.
//! Free design variables: `anchor_i`, `anchor_j`.

use super::axes::JointAxes;
use super::block::{Ctx, Pair, RowGrad, Sink, dot_row, separation_row};

/// Slider along h_i between anchors k_i, k_j.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Prismatic {
    pub pair: Pair,
    pub axes: JointAxes,
}

impl Prismatic {
    pub const ROWS: usize = 5;

    pub fn eval<S: Sink>(&self, x: &Ctx, c: &mut [f64], sink: &mut S) {
        let pts = self.pair.points(x);
        let f_i = self.pair.dir(x, 0, &self.axes.f_i);
        let g_i = self.pair.dir(x, 0, &self.axes.g_i);
        let [a0, a1] = self.axes.alignment_rows(&self.pair, x);
        let rows = [
            separation_row(0, &f_i, &pts),
            separation_row(0, &g_i, &pts),
            a0,
            a1,
            dot_row(&g_i, &self.pair.dir(x, 1, &self.axes.m_j)),
        ];
        for (k, (v, g)) in rows.iter().enumerate() {
            c[k] = *v;
            sink.row(k, g);
        }
    }

    /// The slider displacement along A_i h_i, metres.
    #[inline]
    pub fn coordinate(&self, x: &Ctx) -> (f64, RowGrad) {
        let h_i = self.pair.dir(x, 0, &self.axes.h_i);
        separation_row(0, &h_i, &self.pair.points(x))
    }
}
