//! Fixed joint (weld): a spherical joint at k_i/k_j (3 rows, metres) plus the
//! cross-sum orientation error between body i's axes and body j's axes mapped
//! through the relative orientation captured at build time (3 rows, radians
//! near alignment; see [`orientation_rows`]). Removes 6 degrees of freedom.
//! Free design variables: `anchor_i`, `anchor_j`.

use nalgebra::Matrix3;

use super::block::{Ctx, Pair, Sink, coincidence_rows, orientation_rows};

/// Bodies i and j keep the relative pose they had at the initial configuration
/// (orientation) and keep k_i ≡ k_j (position).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Weld {
    pub pair: Pair,
    /// B̄ = R_j0ᵀ R_i0: body i's axes expressed in body j's frame at assembly.
    pub relative: Matrix3<f64>,
}

impl Weld {
    pub const ROWS: usize = 6;

    pub fn eval<S: Sink>(&self, x: &Ctx, c: &mut [f64], sink: &mut S) {
        coincidence_rows(&self.pair.points(x), 0, c, sink);
        let a = x.frame(self.pair.frame[0]).rot;
        let b = x.frame(self.pair.frame[1]).rot * self.relative;
        orientation_rows(&a, &b, 3, c, sink);
    }
}
