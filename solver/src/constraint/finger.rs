//! Finger constraints: the user's finger holds a body-fixed point c of one
//! moving body at a target supplied every tick (world frame, not coordinates,
//! so moving the finger never rebuilds anything).
//!
//! - point grasp, 3 rows, metres: r + A c − p_target = 0;
//! - rigid grasp, 6 rows: the 3 point rows, then the cross-sum orientation error
//!   ½ Σ_k (A ê_k) × (T ê_k) between the body's axes and the target orientation
//!   T (radians near alignment; Jacobian ≈ −I there; smooth everywhere; see
//!   [`orientation_rows`]). T is the orientation the *body* should have: the
//!   caller composes the device rotation with the grasp offset it captured when
//!   the finger clutched.

use nalgebra::Vector3;

use super::block::{Ctx, Pair, Sink, coincidence_rows, orientation_rows};

/// A point or rigid grasp of finger `finger` on end 0 of `pair` (end 1 is the
/// world; its anchor is unused).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Finger {
    pub pair: Pair,
    /// Index into the targets slice.
    pub finger: usize,
    pub rigid: bool,
}

impl Finger {
    pub fn rows(&self) -> usize {
        if self.rigid { 6 } else { 3 }
    }

    pub fn eval<S: Sink>(&self, x: &Ctx, c: &mut [f64], sink: &mut S) {
        let target = &x.targets[self.finger];
        let mut pts = self.pair.points(x);
        pts[1].p = target.position_m;
        pts[1].lever = Vector3::zeros();
        coincidence_rows(&pts, 0, c, sink);
        if self.rigid {
            let a = x.frame(self.pair.frame[0]).rot;
            let t = target.orientation.to_rotation_matrix().into_inner();
            orientation_rows(&a, &t, 3, c, sink);
        }
    }
}
