//! A point of a flexible body that a joint, a finger or an objective uses:
//! its undeformed body-frame position k and the shape functions there, so
//! that its deformed body-frame position is linear in the deformation
//! coordinates q_f,
//!
//! ```text
//! k(q_f) = k + Φ(k) q_f,   Φ(k) = [ −y φ′ᵀ  −z φ′ᵀ ]     (3 × 2n: y modes, z modes)
//!                                  [   φᵀ      0    ]
//!                                  [   0       φᵀ   ]
//! ```
//!
//! (φ, φ′ at k's x; see `beam`). A row that depends on the world point
//! p = r + R k(q_f) with gradient n (world) gets ∂/∂q_f = Φᵀ Rᵀ n: the
//! body-frame gradient d = Rᵀ n of a free anchor, pushed through Φᵀ.

use nalgebra::Vector3;

use super::beam::{MAX_MODES, Shape};

/// A deforming point of a flexible body (`Param3::Flex` indexes a table of
/// these held by the model).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct FlexAnchor {
    /// Undeformed position, metres, body frame.
    pub k: Vector3<f64>,
    /// First deformation column (y modes, then z modes).
    pub col: usize,
    /// Modes per direction.
    pub modes: usize,
    /// φ_j and φ_j′ at k.x.
    pub shape: Shape,
}

impl FlexAnchor {
    /// Number of deformation columns, 2n.
    #[inline]
    pub fn width(&self) -> usize {
        2 * self.modes
    }

    /// The deformed body-frame position k + Φ q_f at `q`.
    #[inline]
    pub fn point(&self, q: &[f64]) -> Vector3<f64> {
        let n = self.modes;
        let (qy, qz) = (
            &q[self.col..self.col + n],
            &q[self.col + n..self.col + 2 * n],
        );
        let (mut v, mut w, mut dv, mut dw) = (0.0, 0.0, 0.0, 0.0);
        for j in 0..n {
            v += self.shape.phi[j] * qy[j];
            w += self.shape.phi[j] * qz[j];
            dv += self.shape.slope[j] * qy[j];
            dw += self.shape.slope[j] * qz[j];
        }
        self.k + Vector3::new(-self.k.y * dv - self.k.z * dw, v, w)
    }

    /// Φᵀ d for a body-frame gradient `d` of the point: the 2n values of
    /// ∂/∂q_f, written to `out`.
    #[inline]
    pub fn gradient(&self, d: &Vector3<f64>, out: &mut [f64]) {
        let n = self.modes;
        for j in 0..n {
            let s = self.shape.slope[j];
            out[j] = self.shape.phi[j] * d.y - self.k.y * s * d.x;
            out[n + j] = self.shape.phi[j] * d.z - self.k.z * s * d.x;
        }
    }

    /// True when the point does not move with the deformation (the clamp,
    /// x = x_c: φ = φ′ = 0 there).
    pub fn is_rigid(&self) -> bool {
        self.shape.phi[..self.modes]
            .iter()
            .chain(&self.shape.slope[..self.modes])
            .all(|v| *v == 0.0)
    }
}

/// Φ as a dense 3 × 2n matrix (tests and the dense reference).
#[allow(dead_code)]
pub(crate) fn dense_phi(a: &FlexAnchor) -> nalgebra::DMatrix<f64> {
    let mut m = nalgebra::DMatrix::zeros(3, a.width());
    let mut out = [0.0; 2 * MAX_MODES];
    for r in 0..3 {
        let d = Vector3::ith(r, 1.0);
        a.gradient(&d, &mut out);
        for c in 0..a.width() {
            m[(r, c)] = out[c];
        }
    }
    m
}

#[cfg(test)]
mod tests {
    use super::super::beam::{Beam, BeamSpec};
    use super::*;

    /// The deformed point is linear in q_f with the matrix `gradient`
    /// writes: k(q) − k = Φ q exactly.
    #[test]
    fn point_is_linear_with_gradient_as_its_matrix() {
        let beam = Beam::new(BeamSpec::new([-0.1, 0.2], 1.0, 3), 0.2);
        let k = Vector3::new(0.13, 0.01, -0.02);
        let a = FlexAnchor {
            k,
            col: 2,
            modes: 3,
            shape: beam.shape(k.x),
        };
        let q = [9.0, 9.0, 0.01, -0.02, 0.005, 0.03, 0.002, -0.01];
        let phi = dense_phi(&a);
        let qf = nalgebra::DVector::from_column_slice(&q[2..8]);
        let want = k + Vector3::from_column_slice((phi * qf).as_slice());
        assert!((a.point(&q) - want).norm() < 1e-16);
        assert!(!a.is_rigid());
    }
}
