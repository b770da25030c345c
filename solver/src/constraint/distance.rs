//! Distance joint (strut): C = |p_i − p_j| − L = 0, 1 row, metres, where p are
//! the world anchors and L the length (a constant or the free design variable
//! `length`). Joint coordinate (for limits): the measured length |p_i − p_j|,
//! metres. Free design variables: `length`, `anchor_i`, `anchor_j`.
//!
//! If the anchors coincide (|p_i − p_j| < 1e-12 m) the direction is undefined:
//! the point columns of the row are written as zero (no NaN), the `length`
//! column stays −1.

use nalgebra::Vector3;

use super::block::{Ctx, Pair, Param1, RowGrad, Sink, Slot};

/// Strut of length L between anchors k_i, k_j.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Distance {
    pub pair: Pair,
    pub length: Param1,
}

impl Distance {
    pub const ROWS: usize = 1;

    pub fn eval<S: Sink>(&self, x: &Ctx, c: &mut [f64], sink: &mut S) {
        let (len, g) = self.coordinate(x);
        c[0] = len - x.scalar(&self.length);
        sink.row(0, &g);
        sink.set(0, Slot::Length, 0, -1.0);
    }

    /// The measured anchor distance, metres, and its gradient.
    #[inline]
    pub fn coordinate(&self, x: &Ctx) -> (f64, RowGrad) {
        let pts = self.pair.points(x);
        let d = pts[0].p - pts[1].p;
        let len = d.norm();
        let n = if len > 1e-12 {
            d / len
        } else {
            Vector3::zeros()
        };
        let mut g = RowGrad::default();
        g.point(0, &pts[0].lever, &n).point(1, &pts[1].lever, &-n);
        (len, g)
    }
}
