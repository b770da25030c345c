//! `obstacle` (Nelson & Cohen Eq. 15, "dodging bullets"): body points p_k
//! kept away from an obstacle point o. Eq. 15 minimises
//! max_k 1/|p_k − o| (the nearest pair), which has no gradient where two
//! pairs tie and pulls at every distance. Here each point within the
//! activation distance D gets a barrier, and the barriers are combined by a
//! smooth maximum (a 4-norm):
//!
//! ```text
//! b_k = ½ (D/d_k − 1)²  for d_k < D, else 0        d_k = |p_k − o|
//! F   = D² (Σ_k b_k⁴)^¼                              (m²)
//! ∂F  = D² Σ_k (b_k / ‖b‖₄)³ ∂b_k,   ∂b_k = −(D/d_k − 1)(D/d_k²) u_kᵀ ∂p_k
//! ```
//!
//! b is C¹ (zero value and slope at d = D), so F is C¹ everywhere, zero with
//! no point in range, and max_k b_k ≤ F/D² ≤ 4^¼ max_k b_k for up to four
//! points in range: it follows the nearest pair as Eq. 15 does. Guards: a
//! distance below [`MIN_DISTANCE_FRACTION`] × D (at most
//! [`MAX_DISTANCE_FLOOR_M`]) counts as that distance (no division by zero, a
//! bounded pull), and at d = 0 the direction u is zero.
//!
//! The obstacle is an input, not a variable: when it is a point of a body
//! (moved by its own finger or joints), F's gradient leaves that body's
//! columns out (it is the partial gradient with respect to the points'
//! bodies). Reported value: the smallest distance d_k, metres.

use nalgebra::Vector3;

use super::grad::BodyGrad;
use crate::BodyId;

/// Distances below this fraction of the activation distance count as it…
pub const MIN_DISTANCE_FRACTION: f64 = 1e-3;

/// … but never more than this, metres: with the floor at a fixed fraction
/// of D, an activation distance of 1 km put the floor at 1 m, every point
/// of a desk-sized scene under it, and the objective (whose barrier is flat
/// there) silently off.
pub const MAX_DISTANCE_FLOOR_M: f64 = 1e-3;

/// The obstacle point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Obstacle {
    /// Fixed in the world, metres.
    World(Vector3<f64>),
    /// A point of a body (body frame, metres).
    Body(BodyId, Vector3<f64>),
}

/// Body points kept away from an obstacle.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Avoid {
    /// (body, point in its frame).
    pub points: Vec<(BodyId, Vector3<f64>)>,
    pub obstacle: Obstacle,
    /// Activation distance D, metres (> 0).
    pub distance_m: f64,
}

impl Avoid {
    fn obstacle_at(&self, g: &BodyGrad) -> Vector3<f64> {
        match self.obstacle {
            Obstacle::World(o) => o,
            Obstacle::Body(b, p) => g.frames[b.index()].r + g.lever(b, &p),
        }
    }

    /// (d, clamped d, barrier, unit direction, lever) of point k.
    #[inline]
    fn pair(&self, g: &BodyGrad, o: &Vector3<f64>, k: usize) -> Pair {
        let (b, p) = self.points[k];
        let f = &g.frames[b.index()];
        let lever = g.lever(b, &p);
        let v = f.r + lever - o;
        let d = v.norm();
        let floor = (MIN_DISTANCE_FRACTION * self.distance_m).min(MAX_DISTANCE_FLOOR_M);
        let dd = d.max(floor);
        let u = if d > 0.0 { v / d } else { Vector3::zeros() };
        let ratio = self.distance_m / dd;
        let b_k = if dd < self.distance_m {
            0.5 * (ratio - 1.0) * (ratio - 1.0)
        } else {
            0.0
        };
        Pair {
            d,
            clamped: d < dd,
            barrier: b_k,
            slope: -(ratio - 1.0) * ratio / dd,
            u,
            lever,
        }
    }

    /// ‖b‖₄ over the points.
    fn norm4(&self, g: &BodyGrad, o: &Vector3<f64>) -> f64 {
        (0..self.points.len())
            .map(|k| self.pair(g, o, k).barrier.powi(4))
            .sum::<f64>()
            .powf(0.25)
    }

    /// F at the frames of `g`.
    pub fn value(&self, g: &BodyGrad) -> f64 {
        let o = self.obstacle_at(g);
        self.distance_m * self.distance_m * self.norm4(g, &o)
    }

    /// The smallest distance, metres.
    pub fn report(&self, g: &BodyGrad) -> f64 {
        let o = self.obstacle_at(g);
        (0..self.points.len())
            .map(|k| self.pair(g, &o, k).d)
            .fold(f64::INFINITY, f64::min)
    }

    /// F, and `w` × ∂F (points' bodies only) into `g`'s accumulators.
    pub fn gradient(&self, g: &mut BodyGrad, w: f64) -> f64 {
        let o = self.obstacle_at(g);
        let norm = self.norm4(g, &o);
        let scale = self.distance_m * self.distance_m;
        if norm == 0.0 {
            return 0.0;
        }
        for k in 0..self.points.len() {
            let p = self.pair(g, &o, k);
            if p.barrier == 0.0 || p.clamped {
                // Out of range, or inside the floor where the barrier is
                // constant (its slope is zero there).
                continue;
            }
            let c = w * scale * (p.barrier / norm).powi(3) * p.slope;
            let (body, k_body) = self.points[k];
            g.point_at(body, &k_body, &p.lever, &(p.u * c));
        }
        scale * norm
    }
}

/// One point's distance terms.
struct Pair {
    d: f64,
    clamped: bool,
    barrier: f64,
    /// ∂b/∂d.
    slope: f64,
    u: Vector3<f64>,
    lever: Vector3<f64>,
}
