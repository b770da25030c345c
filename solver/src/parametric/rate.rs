//! Eq. 16: the rate of the parametric contact coordinates, u̇ = D q̇
//! (Nelson & Cohen App. E; the closed form of Nelson's "Differential
//! surface kinematics" for a point on a surface). A point p kept on the
//! surface P(u, v) of a fixed body moves with ṗ = [P_u P_v] u̇, so
//!
//! ```text
//! u̇ = D_p ṗ,   D_p = G⁻¹ [P_u P_v]ᵀ,   G = [P_u P_v]ᵀ [P_u P_v]
//! ```
//!
//! (world tangents; G the first fundamental form of P), and D = D_p ∂p/∂q.
//! For a ball of radius ρ, P is the surface offset by ρ: its tangents carry
//! the curvature, P_u = S_u + ρ n_u (`surface`), so the same centre speed
//! turns (u, v) faster in a bowl than on a dome. It is also the derivative
//! of the nearest-point parameters of P at a point on it, which a test
//! checks by finite differences.

use nalgebra::{Matrix2, Matrix2x3, Vector3};

use crate::constraint::Geometry;
use crate::{ConstraintId, Model};

impl Model {
    /// D_p of surface contact `joint` at `q`: (u̇, v̇) = D_p ṗ for the held
    /// point's world velocity ṗ relative to the surface's body. `None` for
    /// a joint that is not a surface contact, a wrong-length q or a
    /// degenerate pose.
    pub fn contact_rate(&self, q: &[f64], joint: ConstraintId) -> Option<Matrix2x3<f64>> {
        if q.len() != self.n_coords() {
            return None;
        }
        let Geometry::OnSurface(g) = self.geometry.get(joint.index())? else {
            return None;
        };
        let sc = self.surfaces.get(g.index as usize)?;
        let sp = sc
            .surface
            .offset(q[sc.uv_col], q[sc.uv_col + 1], sc.radius_m);
        let rot = self.body_rotation(q, crate::BodyId(g.pair.frame[1] as u32))?;
        let (pu, pv): (Vector3<f64>, Vector3<f64>) = (rot * sp.pu, rot * sp.pv);
        let g = Matrix2::new(pu.dot(&pu), pu.dot(&pv), pu.dot(&pv), pv.dot(&pv));
        let t = Matrix2x3::from_rows(&[pu.transpose(), pv.transpose()]);
        Some(g.try_inverse()? * t)
    }

    /// The (u, v) columns of surface contact `joint`, or `None`.
    pub fn contact_parameters(&self, joint: ConstraintId) -> Option<std::ops::Range<usize>> {
        let Geometry::OnSurface(g) = self.geometry.get(joint.index())? else {
            return None;
        };
        let c = self.surfaces.get(g.index as usize)?.uv_col;
        Some(c..c + 2)
    }
}
