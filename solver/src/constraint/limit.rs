//! Joint limits: two inequality rows on a joint coordinate x,
//! x − lo ≥ 0 and hi − x ≥ 0, whose meaning depends on the joint:
//! - revolute: the hinge angle in radians, zero at the initial configuration,
//!   right-handed about A_i h_i, in (−π, π] (limits must lie inside (−π, π));
//! - prismatic: the displacement (A_i h_i)·(p_j − p_i) in metres;
//! - distance: the measured anchor distance |p_i − p_j| in metres (not the
//!   design variable L, so it bounds the real strut even while C ≠ 0).

use super::block::{Ctx, Groups, Pair, Sink, Slot};
use super::distance::Distance;
use super::prismatic::Prismatic;
use super::revolute::Revolute;

/// The joint whose coordinate is limited.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Limited {
    Angle(Revolute),
    Displacement(Prismatic),
    Length(Distance),
}

/// lo ≤ x ≤ hi as two `≥ 0` rows.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Limit {
    pub joint: Limited,
    pub lo: f64,
    pub hi: f64,
}

impl Limit {
    pub const ROWS: usize = 2;

    pub fn pair(&self) -> &Pair {
        match &self.joint {
            Limited::Angle(j) => &j.pair,
            Limited::Displacement(j) => &j.pair,
            Limited::Length(j) => &j.pair,
        }
    }

    /// The joint's groups, without `length` (x never depends on L).
    pub fn groups(&self) -> Groups {
        let mut g = self.pair().groups();
        g[Slot::Length as usize] = None;
        g
    }

    /// The joint coordinate x and its gradient.
    #[inline]
    pub fn coordinate(&self, x: &Ctx) -> (f64, super::block::RowGrad) {
        match &self.joint {
            Limited::Angle(j) => j.coordinate(x),
            Limited::Displacement(j) => j.coordinate(x),
            Limited::Length(j) => j.coordinate(x),
        }
    }

    pub fn eval<S: Sink>(&self, x: &Ctx, c: &mut [f64], sink: &mut S) {
        let (v, g) = self.coordinate(x);
        c[0] = v - self.lo;
        c[1] = self.hi - v;
        sink.row(0, &g);
        sink.row(1, &g.scaled(-1.0));
    }
}
