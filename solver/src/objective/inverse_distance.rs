//! `inverse_distance`: Nelson & Cohen's Eq. 15 as written,
//! f = min_{p,o} 1/‖p − o‖, for body points p_k and an obstacle point o.
//!
//! The paper's subscript reads as "over the pair (p, o) nearest each
//! other" (Fig. 13's creature dodging a bullet; read literally, the
//! smallest 1/d is the farthest pair, which avoids nothing): f = 1/d_min.
//! In m² like every term, with L the model's length scale:
//!
//! ```text
//! F = L³ / d_min,   d_min = min_k |p_k − o|
//! ∂F = −L³ / d_min² · u_k*ᵀ ∂p_k*      (k* the nearest point, u its unit direction)
//! ```
//!
//! How it differs from `obstacle` (the smooth barrier the scenes use): it
//! has no activation distance, so it pulls at every distance (1/d² falls off
//! but never reaches zero); it follows only the nearest point, so its
//! gradient jumps where two points tie for nearest (the barrier's 4-norm
//! blends them); and it grows without bound as d → 0 where the barrier's
//! floor keeps a bounded pull. Guard (needed for any finite output): a
//! distance below [`super::MIN_DISTANCE_FRACTION`] × L counts as that
//! distance (F constant, zero gradient there). The obstacle is an input, as
//! in `obstacle`: its own body's columns get nothing. Reported value: d_min,
//! metres.

use nalgebra::Vector3;

use super::MIN_DISTANCE_FRACTION;
use super::grad::BodyGrad;
use super::obstacle::Obstacle;
use crate::BodyId;

/// Body points kept away from an obstacle by Eq. 15.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct InverseDistance {
    /// (body, point in its frame).
    pub points: Vec<(BodyId, Vector3<f64>)>,
    pub obstacle: Obstacle,
    /// L, metres.
    pub scale_m: f64,
}

impl InverseDistance {
    fn obstacle_at(&self, g: &BodyGrad) -> Vector3<f64> {
        match self.obstacle {
            Obstacle::World(o) => o,
            Obstacle::Body(b, p) => g.frames[b.index()].point(&p),
        }
    }

    /// The nearest point: (index, distance, p − o, lever arm). Ties go to
    /// the first.
    fn nearest(&self, g: &BodyGrad) -> (usize, f64, Vector3<f64>, Vector3<f64>) {
        let o = self.obstacle_at(g);
        let mut best = (0, f64::INFINITY, Vector3::zeros(), Vector3::zeros());
        for (k, (b, p)) in self.points.iter().enumerate() {
            let f = &g.frames[b.index()];
            let lever = f.rot * p;
            let v = f.r + lever - o;
            let d = v.norm();
            if d < best.1 {
                best = (k, d, v, lever);
            }
        }
        best
    }

    fn floor(&self) -> f64 {
        MIN_DISTANCE_FRACTION * self.scale_m
    }

    /// F at the frames of `g`.
    pub fn value(&self, g: &BodyGrad) -> f64 {
        let (_, d, ..) = self.nearest(g);
        self.scale_m.powi(3) / d.max(self.floor())
    }

    /// d_min, metres.
    pub fn report(&self, g: &BodyGrad) -> f64 {
        self.nearest(g).1
    }

    /// F, and `w` × ∂F (the nearest point's body only) into `g`.
    pub fn gradient(&self, g: &mut BodyGrad, w: f64) -> f64 {
        let (k, d, v, lever) = self.nearest(g);
        let l3 = self.scale_m.powi(3);
        if d <= self.floor() {
            return l3 / self.floor();
        }
        let u = v / d;
        g.point(self.points[k].0, &lever, &(u * (-w * l3 / (d * d))));
        l3 / d
    }
}
