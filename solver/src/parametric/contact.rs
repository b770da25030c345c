//! A point of one body held on a parametric surface of another, with the
//! contact's surface parameters (u, v) as coordinates (Nelson & Cohen
//! App. E): 3 rows, metres,
//!
//! ```text
//! C = p_i − (r_j + R_j P(u, v)) = 0,     P = S + ρ n   (ρ = 0: S itself)
//! ```
//!
//! p_i the point (body i, any anchor), P the surface of body j offset by ρ:
//! with ρ > 0 the point is the centre of a ball of radius ρ touching S, and
//! the contact point is P − ρ n. ∂C/∂(u, v) = −R_j [P_u P_v]; the body
//! columns are a coincidence's. Frictionless: the rows' force is normal to
//! the surface once Eq. 7 balances the (u, v) columns, which carry no load
//! (their metric is small and their generalized force zero: `model::auxiliary`).

use super::surface::Surface;
use crate::constraint::block::{Ctx, Pair, Point, Sink, Slot, coincidence_rows};

/// One surface contact of a model (the table `Ctx::surfaces` indexes).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfaceContact {
    /// The surface, in body j's frame.
    pub surface: Surface,
    /// ρ, metres: the point is a ball's centre of this radius (0: the
    /// point itself).
    pub radius_m: f64,
    /// Column of u (v follows).
    pub uv_col: usize,
}

/// The rows of a surface contact: end 0 holds the point, end 1 the surface
/// (its anchor is unused); `index` into the model's surface contacts.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct OnSurface {
    pub pair: Pair,
    pub index: u32,
}

impl OnSurface {
    pub const ROWS: usize = 3;

    pub fn eval<S: Sink>(&self, x: &Ctx, c: &mut [f64], sink: &mut S) {
        let Some(sc) = x.surfaces.get(self.index as usize) else {
            c[..3].fill(0.0);
            return;
        };
        let (u, v) = (x.q[sc.uv_col], x.q[sc.uv_col + 1]);
        let sp = sc.surface.offset(u, v, sc.radius_m);
        let f1 = x.frame(self.pair.frame[1]);
        let mut pts = self.pair.points(x);
        let lever = f1.rot * sp.p;
        pts[1] = Point {
            p: f1.r + lever,
            lever,
        };
        coincidence_rows(&pts, 0, c, sink);
        let (wu, wv) = (f1.rot * sp.pu, f1.rot * sp.pv);
        for k in 0..3 {
            sink.set(k, Slot::Length, 0, -wu[k]);
            sink.set(k, Slot::Length, 1, -wv[k]);
        }
    }
}
