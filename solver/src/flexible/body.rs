//! A compiled flexible body: where its deformation columns are, its beam,
//! and its part of Eq. 7's right-hand side b = Q − M q̈ on those columns.

use nalgebra::{DMatrix, Matrix3, Vector3};

use super::beam::{Beam, MAX_MODES};
use crate::BodyId;

/// One flexible body of a model.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct FlexBody {
    /// The body (moving).
    pub body: BodyId,
    /// First deformation column (y modes, then z modes).
    pub col: usize,
    pub beam: Beam,
    /// K_f, 2n × 2n row-major, N/m.
    pub stiffness: Vec<f64>,
    /// M_f, 2n × 2n row-major, kg.
    pub mass: Vec<f64>,
}

impl FlexBody {
    /// The body's columns at `col` (assigned later by the builder).
    pub fn new(body: BodyId, beam: Beam) -> Self {
        let row_major = |m: DMatrix<f64>| m.transpose().as_slice().to_vec();
        Self {
            body,
            col: 0,
            stiffness: row_major(beam.stiffness()),
            mass: row_major(beam.modal_mass()),
            beam,
        }
    }

    /// Number of deformation columns, 2n.
    #[inline]
    pub fn width(&self) -> usize {
        2 * self.beam.modes()
    }

    /// U = ½ q_fᵀ K_f q_f at `q`, joules.
    pub fn strain_energy(&self, q: &[f64]) -> f64 {
        let w = self.width();
        let qf = &q[self.col..self.col + w];
        let mut u = 0.0;
        for i in 0..w {
            for j in 0..w {
                u += qf[i] * self.stiffness[i * w + j] * qf[j];
            }
        }
        0.5 * u
    }

    /// b_f = −K_f q_f − M_f q̈_f + g_f into `out` (2n values): the elastic
    /// force, the elastic inertia and the modal gravity load, with the
    /// body's rotation `rot` (body → world), gravity `g` (world) and the
    /// deformation accelerations `qdd` (2n).
    ///
    /// # Real-time
    /// No allocation; O((2n)²).
    pub fn generalized_force(
        &self,
        q: &[f64],
        rot: &Matrix3<f64>,
        g: &Vector3<f64>,
        qdd: &[f64],
        out: &mut [f64],
    ) {
        let (w, n) = (self.width(), self.beam.modes());
        let qf = &q[self.col..self.col + w];
        let g_body = rot.tr_mul(g);
        for (i, o) in out.iter_mut().enumerate().take(w) {
            let (k, m) = (
                &self.stiffness[i * w..(i + 1) * w],
                &self.mass[i * w..(i + 1) * w],
            );
            let f: f64 = (0..w).map(|j| -(k[j] * qf[j] + m[j] * qdd[j])).sum();
            let (dir, j) = if i < n {
                (g_body.y, i)
            } else {
                (g_body.z, i - n)
            };
            *o = f + self.beam.load[j.min(MAX_MODES - 1)] * dir;
        }
    }

    /// The tip (or any x) deflection (v, w) and slope (v′, w′) at body x.
    pub fn deflection(&self, q: &[f64], x: f64) -> ([f64; 2], [f64; 2]) {
        let n = self.beam.modes();
        let s = self.beam.shape(x);
        let (mut d, mut t) = ([0.0; 2], [0.0; 2]);
        for dir in 0..2 {
            for j in 0..n {
                let v = q[self.col + dir * n + j];
                d[dir] += s.phi[j] * v;
                t[dir] += s.slope[j] * v;
            }
        }
        (d, t)
    }
}
