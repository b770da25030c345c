//! What a model says about its flexible bodies at a configuration.

use crate::{BodyId, Model};

impl Model {
    /// Whether `body` is flexible.
    pub fn is_flexible(&self, body: BodyId) -> bool {
        self.flexible.iter().any(|f| f.body == body)
    }

    /// The deformation columns of flexible body `body` (y modes, then z
    /// modes; metres), or `None` for a rigid or unknown body.
    pub fn deformation_range(&self, body: BodyId) -> Option<std::ops::Range<usize>> {
        let f = self.flexible.iter().find(|f| f.body == body)?;
        Some(f.col..f.col + f.width())
    }

    /// The deflection (v, w) (metres, along the body's y and z axes) and
    /// slope (v′, w′) of flexible body `body`'s neutral axis at body x, at
    /// `q`; `None` for a rigid or unknown body or a q of the wrong length.
    pub fn deflection(&self, q: &[f64], body: BodyId, x: f64) -> Option<([f64; 2], [f64; 2])> {
        if q.len() != self.n_coords() {
            return None;
        }
        let f = self.flexible.iter().find(|f| f.body == body)?;
        Some(f.deflection(q, x))
    }

    /// The strain energy Σ ½ q_fᵀ K_f q_f of every flexible body at `q`,
    /// joules (0 for a rigid model; NaN for a q of the wrong length).
    pub fn strain_energy_j(&self, q: &[f64]) -> f64 {
        if q.len() != self.n_coords() {
            return f64::NAN;
        }
        self.flexible.iter().map(|f| f.strain_energy(q)).sum()
    }

    /// The world position of body point `k` (body frame, undeformed) of
    /// `body` at `q`, deformed when the body is flexible. `None` for an
    /// unknown body, a wrong-length q or a degenerate quaternion.
    pub fn body_point(
        &self,
        q: &[f64],
        body: BodyId,
        k: nalgebra::Vector3<f64>,
    ) -> Option<nalgebra::Vector3<f64>> {
        let frame = self.body_frame(q, body)?;
        let Some(f) = self.flexible.iter().find(|f| f.body == body) else {
            return Some(frame.point(&k));
        };
        let a = super::anchor::FlexAnchor {
            k,
            col: f.col,
            modes: f.beam.modes(),
            shape: f.beam.shape(k.x),
        };
        Some(frame.point(&a.point(q)))
    }
}
