//! `joint_limit_distance` (Nelson & Cohen App. D, "maximization of a
//! configuration for joint limit distance"): every listed joint's coordinate
//! s (hinge angle, slider displacement or strut length; see
//! `constraint::limit`) kept near the middle m of its limits [lo, hi],
//!
//! ```text
//! F = L² · ½ Σ_j ((s_j − m_j) / h_j)²,   m = (lo + hi)/2,  h = (hi − lo)/2     (m²)
//! ```
//!
//! with L the model's length scale (so F is in m² like the other terms):
//! each joint's distance to its nearer limit is h (1 − |s − m|/h), and
//! minimising F pushes every joint away from both limits at once, smoothly
//! (a max-of-distances form would have no gradient where two joints tie).
//! Reported value: the RMS over the joints of |s_j − m_j| / h_j (0: every
//! joint at its middle; 1: every joint at a limit), √(2F / (L² n)).

use super::grad::BodyGrad;
use crate::constraint::block::{Ctx, RowGrad};
use crate::constraint::limit::Limit;

/// The limited joints to keep centred: their compiled limit geometry.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Centred {
    pub limits: Vec<Limit>,
    /// L², m².
    pub scale_m2: f64,
}

impl Centred {
    /// (s − m)/h, h and the coordinate's gradient of joint k at `q` and the
    /// frames of `g`.
    #[inline]
    fn offset(&self, q: &[f64], g: &BodyGrad, k: usize) -> (f64, f64, RowGrad) {
        let x = Ctx {
            q,
            frames: &g.frames,
            targets: &[],
            witnesses: &[],
            flex: &g.flex,
            surfaces: &[],
            rolling: &[],
        };
        let l = &self.limits[k];
        let (s, rg) = l.coordinate(&x);
        let half = 0.5 * (l.hi - l.lo);
        ((s - 0.5 * (l.hi + l.lo)) / half, half, rg)
    }

    /// F at `q` (frames in `g`).
    pub fn value(&self, q: &[f64], g: &BodyGrad) -> f64 {
        (0..self.limits.len())
            .map(|k| 0.5 * self.offset(q, g, k).0.powi(2))
            .sum::<f64>()
            * self.scale_m2
    }

    /// RMS_j |s_j − m_j| / h_j.
    pub fn report(&self, q: &[f64], g: &BodyGrad) -> f64 {
        let n = self.limits.len().max(1) as f64;
        ((0..self.limits.len())
            .map(|k| self.offset(q, g, k).0.powi(2))
            .sum::<f64>()
            / n)
            .sqrt()
    }

    /// F, and `w` × ∂F into `g` (free anchors straight into `out`).
    pub fn gradient(&self, q: &[f64], g: &mut BodyGrad, w: f64, out: &mut [f64]) -> f64 {
        let mut f = 0.0;
        for k in 0..self.limits.len() {
            let (t, half, rg) = self.offset(q, g, k);
            f += 0.5 * t * t;
            g.row(
                self.limits[k].pair(),
                &rg,
                w * self.scale_m2 * t / half,
                out,
            );
        }
        f * self.scale_m2
    }
}
