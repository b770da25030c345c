//! Euler-parameter norm, one per moving body (Nelson & Cohen §3.2):
//! C = eᵀe − 1 = 0, 1 row, dimensionless. Its Jacobian 2eᵀ touches only the
//! body's four rotation columns.

use super::block::{Ctx, Groups, SLOTS, Sink, Slot};

/// Keeps |e| = 1 for the body whose r starts at column `col`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct QuatNorm {
    pub col: usize,
}

impl QuatNorm {
    pub const ROWS: usize = 1;

    pub fn groups(&self) -> Groups {
        let mut g: Groups = [None; SLOTS];
        g[Slot::BodyI as usize] = Some((self.col + 3, 4));
        g
    }

    pub fn eval<S: Sink>(&self, x: &Ctx, c: &mut [f64], sink: &mut S) {
        let e = &x.q[self.col + 3..self.col + 7];
        c[0] = e.iter().map(|v| v * v).sum::<f64>() - 1.0;
        for (k, v) in e.iter().enumerate() {
            sink.set(0, Slot::BodyI, k, 2.0 * v);
        }
    }
}
