//! Mass matrix and the right-hand side of Eq. 7 in augmented coordinates, for
//! the rational rotation R(e) = A_h(e)/|e|² of [`crate::rotation`].
//!
//! Kinetic energy of a body (origin at its centre of mass, principal inertia J′
//! about its body axes, J_w = R J′ Rᵀ): with ω = Ω(e) ė (exact for any e ≠ 0),
//!
//! ```text
//! T = ½ m |ṙ|² + ½ ωᵀ J_w ω = ½ ṙᵀ (m I) ṙ + ½ ėᵀ (Ωᵀ J_w Ω) ė,     M_e = Ωᵀ J_w Ω
//! ```
//!
//! (for unit e, Ω = 2G and M_e = 4 Gᵀ J G, the usual form). M_e is singular
//! along e (a pure change of |e| moves nothing); only the quaternion-norm row
//! 2eᵀ acts in that direction, so any positive mass there changes only that
//! row's multiplier. We use M̃_e = M_e + c′ (4/|e|⁴) e eᵀ with c′ the body's
//! mean principal moment, whose inverse is closed-form because
//! U = [(|e|/2) Ω; eᵀ/|e|] is orthogonal:
//!
//! ```text
//! M̃_e⁻¹ = (s/4) [ (s/4) Ωᵀ J_w⁻¹ Ω + e eᵀ / (s c′) ],   s = |e|²
//! ```
//!
//! Right-hand side of Eq. 7, b = Q_e + Q_v − M q̈: gravity acts at the centre
//! of mass (Q_e = [m g; 0]); differentiating ω = Ω ė gives α = Ω ë + Ω̇ ė with
//! Ω̇ ė = −(2 eᵀė / |e|²) ω (the E(ė) ė term of Ω̇ vanishes), and the
//! rotational Newton–Euler equation J_w α + ω × J_w ω = τ projected by Ωᵀ is
//! the e-row of Eq. 6 with Q_v = −Ωᵀ (J_w Ω̇ ė + ω × J_w ω). So per body
//!
//! ```text
//! b_r = m (g − r̈),    b_e = −Ωᵀ (J_w α + ω × J_w ω)
//! ```
//!
//! which the fast loop evaluates from world-frame a, ω, α estimated by
//! differences of q, and the reference from q̇ and q̈ directly.

use nalgebra::{Matrix3, Matrix4, Vector3, Vector4};

use crate::rotation::BodyFrame;
use crate::{Body, Model};

/// Mass data of one moving body, and its column offset in q.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct BodyMass {
    /// Column of r; e follows at `offset + 3`.
    pub offset: usize,
    /// Kilograms.
    pub mass: f64,
    /// Principal inverse moments about the body axes, 1/(kg·m²).
    pub inv_inertia: Vector3<f64>,
    /// Principal moments, kg·m².
    pub inertia: Vector3<f64>,
    /// c′ (mean principal moment, kg·m²): the mass given to the |e| direction.
    pub norm_mass: f64,
    /// False for a contact finger's fingertip, which the user's hand carries:
    /// gravity does not act on it.
    pub weighs: bool,
}

impl BodyMass {
    /// Mass data of every moving body of `model`, in layout order. Allocates.
    pub fn of_model(model: &Model) -> Vec<Self> {
        model
            .layout()
            .moving_bodies()
            .map(|(id, offset)| Self::new(&model.bodies()[id.index()], offset))
            .collect()
    }

    fn new(b: &Body, offset: usize) -> Self {
        let j = b.inertia_kg_m2;
        Self {
            offset,
            mass: b.mass_kg,
            inv_inertia: j.map(|v| 1.0 / v),
            inertia: j,
            norm_mass: j.sum() / 3.0,
            weighs: !b.fingertip,
        }
    }

    /// J_w = R J′ Rᵀ (world frame), kg·m².
    #[inline]
    pub fn world_inertia(&self, f: &BodyFrame) -> Matrix3<f64> {
        f.rot * Matrix3::from_diagonal(&self.inertia) * f.rot.transpose()
    }

    /// M_e = Ωᵀ J_w Ω (4 × 4, singular along e).
    #[inline]
    pub fn rotational_mass(&self, f: &BodyFrame) -> Matrix4<f64> {
        f.omega.transpose() * self.world_inertia(f) * f.omega
    }

    /// M̃_e⁻¹ (4 × 4) at Euler parameters `e` (module docs).
    #[inline]
    pub fn inv_rotational_mass(&self, f: &BodyFrame, e: &Vector4<f64>) -> Matrix4<f64> {
        let s = e.norm_squared();
        let j_inv = f.rot * Matrix3::from_diagonal(&self.inv_inertia) * f.rot.transpose();
        (f.omega.transpose() * j_inv * f.omega * (s / 4.0)
            + e * e.transpose() / (s * self.norm_mass))
            * (s / 4.0)
    }

    /// b = Q_e + Q_v − M q̈ of this body (7 values: r then e) from world-frame
    /// linear acceleration `a`, angular velocity `w` and angular acceleration
    /// `alpha` of its centre of mass, with gravity `g`.
    #[inline(always)]
    pub fn generalized_force(
        &self,
        f: &BodyFrame,
        g: &Vector3<f64>,
        a: &Vector3<f64>,
        w: &Vector3<f64>,
        alpha: &Vector3<f64>,
        out: &mut [f64],
    ) {
        let jw = self.world_inertia(f);
        let tau = -(jw * alpha + w.cross(&(jw * w)));
        let g = if self.weighs { *g } else { Vector3::zeros() };
        let force = (g - a) * self.mass;
        out[..3].copy_from_slice(force.as_slice());
        out[3..7].copy_from_slice((f.omega.transpose() * tau).as_slice());
    }
}

/// The e-part of q̇ and q̈ of one body turned into world ω and α (module docs):
/// ω = Ω ė, α = Ω ë − (2 eᵀė / |e|²) ω.
#[inline]
pub(crate) fn angular_motion(
    f: &BodyFrame,
    e: &Vector4<f64>,
    e_dot: &Vector4<f64>,
    e_ddot: &Vector4<f64>,
) -> (Vector3<f64>, Vector3<f64>) {
    let w = f.omega * e_dot;
    let alpha = f.omega * e_ddot - w * (2.0 * e.dot(e_dot) / e.norm_squared());
    (w, alpha)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn body() -> (BodyMass, BodyFrame, Vector4<f64>) {
        let m = BodyMass {
            offset: 0,
            mass: 0.3,
            inv_inertia: Vector3::new(1.0 / 2e-3, 1.0 / 3e-3, 1.0 / 4e-3),
            inertia: Vector3::new(2e-3, 3e-3, 4e-3),
            norm_mass: 3e-3,
            weighs: true,
        };
        let e = Vector4::new(0.9, -0.3, 0.5, 0.2) * 1.3;
        let f = BodyFrame::new(Vector3::new(0.1, 0.2, 0.3), [e[0], e[1], e[2], e[3]]).unwrap();
        (m, f, e)
    }

    #[test]
    fn kinetic_energy_of_m_e_matches_body_rotation() {
        let (m, f, _) = body();
        let e_dot = Vector4::new(0.3, -1.1, 0.4, 0.8);
        let w = f.omega * e_dot;
        let t_world = 0.5 * w.dot(&(m.world_inertia(&f) * w));
        let t_aug = 0.5 * e_dot.dot(&(m.rotational_mass(&f) * e_dot));
        assert!((t_world - t_aug).abs() < 1e-14 * t_world.abs().max(1.0));
        // Body-frame check of J_w: ωᵀ J_w ω = ω_bᵀ J′ ω_b.
        let wb = f.rot.transpose() * w;
        let t_body = 0.5 * wb.component_mul(&m.inertia).dot(&wb);
        assert!((t_world - t_body).abs() < 1e-15);
    }

    #[test]
    fn augmented_inverse_inverts_m_e_off_the_norm_direction() {
        let (m, f, e) = body();
        let s = e.norm_squared();
        let m_tilde = m.rotational_mass(&f) + e * e.transpose() * (4.0 * m.norm_mass / (s * s));
        let prod = m_tilde * m.inv_rotational_mass(&f, &e);
        assert!((prod - Matrix4::identity()).abs().max() < 1e-10, "{prod}");
    }

    #[test]
    fn angular_acceleration_matches_finite_differences() {
        // e(t) = |e(t)| · unit quaternion spinning about a fixed axis, with a
        // changing norm, so both terms of α = Ω ë + Ω̇ ė matter.
        let axis = Vector3::new(0.3, -0.5, 0.8).normalize();
        let e_of = |t: f64| {
            let th = 0.7 * t + 0.4 * t * t;
            let (c, sn) = ((th / 2.0).cos(), (th / 2.0).sin());
            Vector4::new(c, sn * axis.x, sn * axis.y, sn * axis.z) * (1.0 + 0.2 * t)
        };
        let (t, d) = (0.3, 1e-4);
        let e = e_of(t);
        let e_dot = (e_of(t + d) - e_of(t - d)) / (2.0 * d);
        let e_ddot = (e_of(t + d) - 2.0 * e + e_of(t - d)) / (d * d);
        let f = BodyFrame::new(Vector3::zeros(), [e[0], e[1], e[2], e[3]]).unwrap();
        let (w, alpha) = angular_motion(&f, &e, &e_dot, &e_ddot);
        // Exact: ω = θ̇ axis, α = θ̈ axis.
        assert!((w - axis * (0.7 + 0.8 * t)).norm() < 1e-7, "{w}");
        assert!((alpha - axis * 0.8).norm() < 1e-5, "{alpha}");
    }
}
