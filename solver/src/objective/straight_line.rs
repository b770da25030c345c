//! `straight_line` (Nelson & Cohen Fig. 10, the Peaucellier objective): a
//! body point x kept on a world line through a with unit direction u,
//!
//! ```text
//! F = ½ |P (x − a)|²,   P = I − u uᵀ,   ∂F/∂x = P (x − a)        (m²)
//! ```
//!
//! Reported value: the point's distance from the line, metres.

use nalgebra::Vector3;

use super::grad::BodyGrad;
use crate::BodyId;

/// A body point kept on a line.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct StraightLine {
    pub body: BodyId,
    /// The point, body frame, metres.
    pub point: Vector3<f64>,
    /// A point of the line, world frame, metres.
    pub line_point: Vector3<f64>,
    /// Unit direction of the line, world frame.
    pub direction: Vector3<f64>,
}

impl StraightLine {
    /// The component of x − a off the line, and the lever arm R·point.
    #[inline]
    fn offset(&self, g: &BodyGrad) -> (Vector3<f64>, Vector3<f64>) {
        let f = &g.frames[self.body.index()];
        let lever = g.lever(self.body, &self.point);
        let d = f.r + lever - self.line_point;
        (d - self.direction * self.direction.dot(&d), lever)
    }

    /// F at the frames of `g`.
    pub fn value(&self, g: &BodyGrad) -> f64 {
        0.5 * self.offset(g).0.norm_squared()
    }

    /// Distance from the line, metres.
    pub fn report(&self, g: &BodyGrad) -> f64 {
        self.offset(g).0.norm()
    }

    /// F, and `w` × ∂F into `g`'s accumulators.
    pub fn gradient(&self, g: &mut BodyGrad, w: f64) -> f64 {
        let (off, lever) = self.offset(g);
        g.point_at(self.body, &self.point, &lever, &(off * w));
        0.5 * off.norm_squared()
    }
}
