//! Rack and pinion (Nelson & Cohen Fig. 12's gearing, revolute to
//! prismatic): the rack's slide s follows the pinion's angle θ,
//! s − s₀ = r θ, one row in metres of rack.
//!
//! θ is the revolute's coordinate ([`super::axes::JointAxes::angle`], zero at
//! the initial configuration, in (−π, π]); s the prismatic's displacement
//! (A_i h_i)·(p_j − p_i), s₀ its initial value; r (m/rad, signed: the pinion's
//! pitch radius, negative when the rack runs against the axes' sense) is the
//! rack's travel per radian. A whole turn of the pinion moves the rack 2π r
//! and returns θ to itself, so
//!
//! ```text
//! C = r · wrap((s − s₀)/r − θ),    ∂C = ∂s − r ∂θ
//! ```
//!
//! is smooth through any number of turns and equals s − s₀ − r θ near
//! assembly. Removes 1 degree of freedom.
//!
//! The two joints' moving bodies (at most two) are the row's ends, as for
//! [`super::gear`]; the model builder refuses a prismatic joint whose anchors
//! or fixed body's position are design variables (the row's ends carry no
//! design columns).

use super::block::{Ctx, Pair, RowGrad, Sink};
use super::gear::{Ends, wrap};
use super::prismatic::Prismatic;
use super::revolute::Revolute;

/// A pinion (revolute) driving a rack (prismatic) at `ratio_m` per radian.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct RackPinion {
    /// The coupling's two ends (anchors unused).
    pub pair: Pair,
    /// Joint 0 of [`Ends`].
    pub pinion: Revolute,
    /// Joint 1 of [`Ends`].
    pub rack: Prismatic,
    pub ends: Ends,
    /// r, metres of rack per radian of pinion (≠ 0).
    pub ratio_m: f64,
    /// s₀, the rack's initial displacement, m.
    pub s0_m: f64,
}

impl RackPinion {
    pub const ROWS: usize = 1;

    pub fn eval<S: Sink>(&self, x: &Ctx, c: &mut [f64], sink: &mut S) {
        let (theta, gt) = self.pinion.coordinate(x);
        let (s, gs) = self.rack.coordinate(x);
        let r = self.ratio_m;
        c[0] = r * wrap((s - self.s0_m) / r - theta);
        let mut g = RowGrad::default();
        self.ends.add(1, &gs, 1.0, &mut g);
        self.ends.add(0, &gt, -r, &mut g);
        sink.row(0, &g);
    }
}
