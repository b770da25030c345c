//! The per-row rules of one augmented-Lagrangian iteration (Nelson & Cohen
//! Eq. 1–3), the q step, and the violation statistics of an evaluated C.
//!
//! Per row i, from the newest C_i (so the multiplier step and the q step see
//! the same violation; this ordering is the stable one, see [`super::scaling`]):
//!
//! ```text
//! equality:    λ_i ← λ_i + k₂_i C_i                 w_i = λ_i + K_i C_i
//! finger:      (no multiplier)                      w_i = K_i C_i · min(1, d / |ℓ C|_group)
//! inequality:  ν_i ← max(0, ν_i − k₂_i C_i)         w_i = −max(0, ν_i − K_i C_i)
//! redundant:   λ_i ← 0                              w_i = 0
//! then         q ← q − h [ (q − q₀) + W⁻¹ C_qᵀ w ]
//! ```
//!
//! The inequality form is the projected (Rockafellar) augmented Lagrangian of
//! C ≥ 0: ν ≥ 0 is the magnitude of the row's reaction, stored as-is in the
//! multiplier vector; a row with C_i > ν_i / K_i contributes nothing.
//!
//! Finger rows come in groups of three (the point, and for a rigid grasp the
//! orientation); a group whose scaled error |ℓ C| exceeds the pull limit d
//! ([`SolverSettings::finger_pull_limit_m`](crate::SolverSettings::finger_pull_limit_m))
//! pulls as if it were d away, in the same direction: a target far outside
//! the mechanism's reach drags it toward the closest reachable configuration
//! without loading the joints with K·ℓ²·(the whole distance), and a
//! linearised (projected) step cannot overshoot by more than d.

use super::scaling::{Role, Scaling};
use crate::{Model, RowUnit, Sense};

/// w_i of row `i` at value `c`, updating its multiplier.
#[inline(always)]
pub(crate) fn row_weight(s: &Scaling, i: usize, c: f64, lambda: &mut f64) -> f64 {
    match s.role[i] {
        Role::Equality | Role::DesignPin => {
            *lambda += s.integral[i] * c;
            *lambda + s.penalty[i] * c
        }
        Role::Finger | Role::Coupling => s.penalty[i] * c,
        Role::Inequality | Role::Contact | Role::DesignBound => {
            *lambda = (*lambda - s.integral[i] * c).max(0.0);
            -(*lambda - s.penalty[i] * c).max(0.0)
        }
        Role::Redundant | Role::Friction => {
            *lambda = 0.0;
            0.0
        }
    }
}

/// Applies the pull limit to the weights `w` of one finger constraint whose
/// first row is `r0` and values are `c`.
#[inline]
pub(crate) fn clamp_finger_pull(s: &Scaling, r0: usize, c: &[f64], w: &mut [f64]) {
    for (g, (cg, wg)) in c.chunks(3).zip(w.chunks_mut(3)).enumerate() {
        let base = r0 + 3 * g;
        let norm = cg
            .iter()
            .enumerate()
            .map(|(k, v)| (s.ell[base + k] * v).powi(2))
            .sum::<f64>()
            .sqrt();
        if norm > s.finger_limit_m {
            let f = s.finger_limit_m / norm;
            for v in wg {
                *v *= f;
            }
        }
    }
}

/// q ← q − h [(q − q₀) + W⁻¹ g] with g = C_qᵀ w.
///
/// # Real-time
/// No allocation; O(coordinates).
#[inline]
pub(crate) fn step(s: &Scaling, h: f64, q: &mut [f64], q_ref: &[f64], g: &[f64]) {
    for (((qc, rc), gc), wc) in q.iter_mut().zip(q_ref).zip(g).zip(&s.inv_metric) {
        *qc -= h * ((*qc - *rc) + wc * gc);
    }
}

/// Constraint violation of one evaluated C, finger rows excluded (their
/// residual is the tracking error, reported per finger), contact rows
/// reported as penetration apart, friction stick rows not at all (their
/// value is a tangential slip, not an error). Equalities count
/// |C_i|, inequalities max(0, −C_i); redundant (masked) rows count by their
/// sense like the others: masking changes how a row is solved, not whether
/// its violation is reported.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(crate) struct Violation {
    /// Largest, over length rows, metres.
    pub max_m: f64,
    /// Largest, over angle rows, radians.
    pub max_rad: f64,
    /// Largest |eᵀe − 1|, dimensionless.
    pub max_norm: f64,
    /// Root mean square over length rows, metres.
    pub rms_m: f64,
    /// Largest ℓ_i |C_i| over all counted rows (angle and norm rows times L), metres.
    pub max_scaled_m: f64,
    /// Deepest penetration of a contact witness row, max(0, −C), metres
    /// (not part of the other figures).
    pub max_penetration_m: f64,
}

impl Violation {
    /// Statistics of `c` (one entry per row of `model`).
    ///
    /// # Real-time
    /// No allocation; O(rows).
    pub fn of(model: &Model, s: &Scaling, c: &[f64]) -> Self {
        let mut v = Self::default();
        let (mut sum, mut count) = (0.0, 0usize);
        for (i, (&ci, row)) in c.iter().zip(model.rows()).enumerate() {
            let e = match (s.role[i], row.sense) {
                (Role::Finger | Role::Coupling | Role::Friction, _)
                | (Role::Redundant, Sense::Friction) => continue,
                (Role::Contact, _) => {
                    v.max_penetration_m = v.max_penetration_m.max(-ci);
                    continue;
                }
                (Role::Equality | Role::DesignPin, _) | (Role::Redundant, Sense::Equality) => {
                    ci.abs()
                }
                (Role::Inequality | Role::DesignBound, _)
                | (Role::Redundant, Sense::Inequality) => (-ci).max(0.0),
            };
            match row.unit {
                RowUnit::Length => {
                    v.max_m = v.max_m.max(e);
                    sum += e * e;
                    count += 1;
                }
                RowUnit::Angle => v.max_rad = v.max_rad.max(e),
                RowUnit::Dimensionless => v.max_norm = v.max_norm.max(e),
            }
            v.max_scaled_m = v.max_scaled_m.max(s.ell[i] * e);
        }
        if count > 0 {
            v.rms_m = (sum / count as f64).sqrt();
        }
        v
    }
}
