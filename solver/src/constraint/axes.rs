//! Body-frame reference directions of the axis-aligning joints (revolute,
//! prismatic), fixed once at build time from the initial poses.
//!
//! Body i carries a right-handed orthonormal triad (f_i, g_i, h_i) with h_i the
//! joint axis; body j carries its axis h_j and a reference m_j ⟂ h_j that equals
//! f_i (in the world) at the initial configuration. The joint angle is measured
//! from m_j against f_i, so it is zero at the initial configuration.

use nalgebra::{Matrix3, Vector3};

use super::block::{Ctx, Pair, RowGrad, dot_row};

/// Unit body-frame directions of an axis-aligning joint.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct JointAxes {
    /// f_i, g_i, h_i on body i (right-handed: f × g = h).
    pub f_i: Vector3<f64>,
    pub g_i: Vector3<f64>,
    pub h_i: Vector3<f64>,
    /// The axis on body j.
    pub h_j: Vector3<f64>,
    /// Zero-angle reference on body j, ⟂ h_j.
    pub m_j: Vector3<f64>,
}

/// A unit vector perpendicular to the unit vector `h` (deterministic: built from
/// the coordinate axis least aligned with `h`).
pub(crate) fn perpendicular_to(h: &Vector3<f64>) -> Vector3<f64> {
    let k = h.iamin();
    h.cross(&Vector3::ith(k, 1.0)).normalize()
}

impl JointAxes {
    /// Reference directions from unit body-frame axes and the initial rotations
    /// `rot_i`, `rot_j` (body → world) of the two bodies.
    pub fn new(
        h_i: Vector3<f64>,
        h_j: Vector3<f64>,
        rot_i: &Matrix3<f64>,
        rot_j: &Matrix3<f64>,
    ) -> Self {
        let f_i = perpendicular_to(&h_i);
        let g_i = h_i.cross(&f_i);
        // f_i seen from body j at the initial poses, projected off h_j.
        let f_in_j = rot_j.tr_mul(&(rot_i * f_i));
        let m = f_in_j - h_j * h_j.dot(&f_in_j);
        let m_j = if m.norm() > 1e-6 {
            m.normalize()
        } else {
            perpendicular_to(&h_j)
        };
        Self {
            f_i,
            g_i,
            h_i,
            h_j,
            m_j,
        }
    }

    /// The two rows f_i·h_j = 0, g_i·h_j = 0 that keep the axes parallel.
    #[inline]
    pub fn alignment_rows(&self, pair: &Pair, x: &Ctx) -> [(f64, RowGrad); 2] {
        let h_j = pair.dir(x, 1, &self.h_j);
        [
            dot_row(&pair.dir(x, 0, &self.f_i), &h_j),
            dot_row(&pair.dir(x, 0, &self.g_i), &h_j),
        ]
    }

    /// Rotation angle of body j relative to body i about h_i, radians in
    /// (−π, π], zero at the initial configuration, positive right-handed about
    /// A_i h_i: θ = atan2(m_j·g_i, m_j·f_i) (world-frame directions).
    #[inline]
    pub fn angle(&self, pair: &Pair, x: &Ctx) -> (f64, RowGrad) {
        let m = pair.dir(x, 1, &self.m_j);
        let (c, gc) = dot_row(&pair.dir(x, 0, &self.f_i), &m);
        let (s, gs) = dot_row(&pair.dir(x, 0, &self.g_i), &m);
        let r2 = s * s + c * c;
        if r2 < 1e-24 {
            // m_j ∥ h_i: the angle is undefined; report 0 with a zero gradient.
            return (0.0, RowGrad::default());
        }
        let mut g = gs.scaled(c / r2);
        g.add_scaled(-s / r2, &gc);
        (s.atan2(c), g)
    }
}
