//! Gear pair (Nelson & Cohen Fig. 12): two revolute joints turning at a fixed
//! ratio, θ_j = ρ θ_i, one row in radians of joint j.
//!
//! θ_i, θ_j are the joints' own coordinates ([`super::axes::JointAxes::angle`]: zero at
//! the initial configuration, right-handed about each joint's axis on its
//! body i), each in (−π, π]. Gears turn many times, so the row cannot be
//! θ_j − ρ θ_i of those wrapped angles: it would jump by 2πρ whenever gear i
//! passes half a turn. A real gear ratio is a ratio of tooth counts,
//! ρ = p/q in lowest terms (q > 0), and q θ_j − p θ_i is defined modulo 2π
//! (a whole turn of either gear adds a multiple of 2π), so
//!
//! ```text
//! C = wrap(q θ_j − p θ_i) / q,    wrap(x) = x − 2π round(x / 2π)
//! ∂C = ∂θ_j − ρ ∂θ_i
//! ```
//!
//! is smooth through any number of turns and equals θ_j − ρ θ_i near
//! assembly (its other zeros are the other meshings, a tooth or more apart:
//! a local solver never reaches them). Removes 1 degree of freedom.
//!
//! **Bodies.** The two joints may touch up to four bodies; the row has two
//! ends ([`Pair`]), the two distinct moving bodies among them (gears on a
//! fixed frame, or a gear riding on its mate's carrier). Each joint's
//! gradient is mapped onto those ends by [`Ends`]; a fixed body's part is
//! dropped (its pose is constant, and an angle does not depend on its
//! position). The model builder refuses three or more moving bodies.

use super::block::{Ctx, Pair, RowGrad, Sink};
use super::revolute::Revolute;

/// Where the ends of the two coupled joints land in the coupling's own
/// [`Pair`]: `map[k][e]` is joint k's end e as end 0 or 1 of the coupling,
/// or `None` for a fixed body (or the world).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Ends {
    pub map: [[Option<u8>; 2]; 2],
}

impl Ends {
    /// Adds `k` × joint `joint`'s gradient `g` (over its own ends) into
    /// `out` (over the coupling's ends).
    #[inline]
    pub fn add(&self, joint: usize, g: &RowGrad, k: f64, out: &mut RowGrad) {
        for end in 0..2 {
            if let Some(to) = self.map[joint][end] {
                let to = to as usize;
                out.lin[to] += g.lin[end] * k;
                out.ang[to] += g.ang[end] * k;
            }
        }
    }
}

/// x wrapped into [−π, π].
#[inline]
pub(crate) fn wrap(x: f64) -> f64 {
    use std::f64::consts::TAU;
    x - TAU * (x / TAU).round()
}

/// Two revolutes geared at ρ = `num` / `den`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Gear {
    /// The coupling's two ends (the moving bodies of the joints; anchors
    /// unused).
    pub pair: Pair,
    /// Joint i (the driver) and joint j (the driven one).
    pub joints: [Revolute; 2],
    pub ends: Ends,
    /// ρ = num / den in lowest terms, den > 0 (whole numbers as f64).
    pub num: f64,
    pub den: f64,
}

impl Gear {
    pub const ROWS: usize = 1;

    pub fn eval<S: Sink>(&self, x: &Ctx, c: &mut [f64], sink: &mut S) {
        let (ti, gi) = self.joints[0].coordinate(x);
        let (tj, gj) = self.joints[1].coordinate(x);
        c[0] = wrap(self.den * tj - self.num * ti) / self.den;
        let mut g = RowGrad::default();
        self.ends.add(1, &gj, 1.0, &mut g);
        self.ends.add(0, &gi, -self.num / self.den, &mut g);
        sink.row(0, &g);
    }
}

#[cfg(test)]
mod tests {
    use super::wrap;
    use std::f64::consts::PI;

    #[test]
    fn wrap_keeps_small_angles_and_folds_whole_turns() {
        assert_eq!(wrap(0.3), 0.3);
        assert!((wrap(0.3 + 6.0 * PI) - 0.3).abs() < 1e-14);
        assert!((wrap(-0.3 - 4.0 * PI) + 0.3).abs() < 1e-14);
        assert!(wrap(3.0 * PI).abs() <= PI + 1e-15);
    }
}
