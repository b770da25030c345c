//! Bounds on one design-variable component x (a length, an anchor or a free
//! position coordinate, metres): two `≥ 0` rows x − lo ≥ 0 and hi − x ≥ 0
//! ([`ConstraintKind::DesignBound`](super::ConstraintKind::DesignBound)), or,
//! when lo = hi, one equality row x − lo = 0
//! ([`ConstraintKind::DesignPin`](super::ConstraintKind::DesignPin)). The rows
//! touch one design column and no body, so Eq. 7 never sees them and the
//! projected update enforces them as a box on the design step (see
//! `al::design`); the gradient rule and the placement treat them like any
//! other row.

use super::block::{Ctx, Groups, SLOTS, Sink, Slot};

/// lo ≤ q[col] ≤ hi.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct DesignBound {
    pub col: usize,
    pub lo: f64,
    pub hi: f64,
}

impl DesignBound {
    /// 1 row when pinned (lo = hi), else 2.
    pub fn rows(&self) -> usize {
        if self.lo == self.hi { 1 } else { 2 }
    }

    pub fn groups(&self) -> Groups {
        let mut g: Groups = [None; SLOTS];
        g[Slot::Length as usize] = Some((self.col, 1));
        g
    }

    pub fn eval<S: Sink>(&self, x: &Ctx, c: &mut [f64], sink: &mut S) {
        let v = x.q[self.col];
        c[0] = v - self.lo;
        sink.set(0, Slot::Length, 0, 1.0);
        if self.lo != self.hi {
            c[1] = self.hi - v;
            sink.set(1, Slot::Length, 0, -1.0);
        }
    }
}
