//! [`PlacementOptions`]: the knobs of the Newton-KKT placement, with units and
//! the reason for each default.

use super::PlacementError;

/// Settings of one [`Placement`](super::Placement). Fixed at
/// [`Placement::analyze`](super::Placement::analyze); analyse again to change
/// them.
#[derive(Debug, Clone, PartialEq)]
pub struct PlacementOptions {
    /// Stopping tolerance on the constraint residual: the 2-norm over the
    /// equality rows and the violated part `min(C_j, 0)` of the inequality rows
    /// (mixed units: metres, radians, dimensionless quaternion-norm rows).
    /// Scene key `placement_tolerance`. Default 1e-9: a nanometre, four orders
    /// below a PHANToM's encoder resolution, so a converged placement is a
    /// reference for fast-loop errors in micrometres.
    pub tolerance: f64,
    /// Initial and smallest damping μ in (J W⁻¹ Jᵀ + μI) λ = r (units of the
    /// normal matrix: squared row units per unit weight). Scene key `damping`.
    /// Default 1e-8: a metre row of J Jᵀ has diagonal ≈ 1, so the damped step is
    /// the Newton step to 1e-8 relative, while every Cholesky pivot of a
    /// singular J Jᵀ stays ≥ 1e-8, eight orders above rounding.
    pub damping: f64,
    /// Newton iterations at most. Default 50: a good start converges in 3–8;
    /// the cap only bounds singular or conflicting problems.
    pub max_iterations: u32,
    /// Converged also needs the last Newton step (∞-norm over q and the
    /// slacks: metres and quaternion units) at most this, so the objective's
    /// stationarity and the multipliers have converged too, not only C.
    /// Default 1e-9 (a nanometre).
    pub step_tolerance: f64,
    /// Optional diagonal weight W (one positive entry per coordinate) of the
    /// objective ½‖q − q_ref‖²_W: a large weight keeps that coordinate near its
    /// reference. `None` is W = I (Choi & Cremer Eq. 4).
    pub weights: Option<Vec<f64>>,
    /// A column of C_q (one coordinate) with more than this many nonzeros is
    /// *dense*: it would fill a `count × count` block of J Jᵀ, so it is split
    /// off and handled by the modified Schur complement (Choi & Cremer §5.1).
    /// Default 32: a 32 × 32 dense block costs ≈ 5 000 flops, negligible next
    /// to the sparse factor, while the Stewart platform (25 rows on the
    /// platform) and the sphere toy (≤ 18 per bead) stay plainly sparse.
    /// `usize::MAX` disables the split.
    pub dense_column_threshold: usize,
}

impl Default for PlacementOptions {
    fn default() -> Self {
        Self {
            tolerance: 1e-9,
            damping: 1e-8,
            max_iterations: 50,
            step_tolerance: 1e-9,
            weights: None,
            dense_column_threshold: 32,
        }
    }
}

impl PlacementOptions {
    /// Defaults with the two scene keys applied where the scene set them.
    pub fn from_scene(placement_tolerance: Option<f64>, damping: Option<f64>) -> Self {
        let d = Self::default();
        Self {
            tolerance: placement_tolerance.unwrap_or(d.tolerance),
            damping: damping.unwrap_or(d.damping),
            ..d
        }
    }

    /// Checks every field against a model of `n_coords` coordinates.
    pub(crate) fn validate(&self, n_coords: usize) -> Result<(), PlacementError> {
        let bad = |field| Err(PlacementError::InvalidOption { field });
        if !(self.tolerance.is_finite() && self.tolerance > 0.0) {
            return bad("tolerance");
        }
        if !(self.damping.is_finite() && self.damping > 0.0 && self.damping < 1.0) {
            return bad("damping");
        }
        if self.max_iterations == 0 || self.max_iterations > 10_000 {
            return bad("max_iterations");
        }
        if !(self.step_tolerance.is_finite() && self.step_tolerance > 0.0) {
            return bad("step_tolerance");
        }
        if self.dense_column_threshold < 2 {
            return bad("dense_column_threshold");
        }
        if let Some(w) = &self.weights {
            if w.len() != n_coords {
                return Err(PlacementError::WeightCount {
                    expected: n_coords,
                    got: w.len(),
                });
            }
            if let Some(index) = w.iter().position(|v| !(v.is_finite() && *v > 0.0)) {
                return Err(PlacementError::NonPositiveWeight { index });
            }
        }
        Ok(())
    }
}

/// The scalar options, copied out for the duration of a solve.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Knobs {
    pub tolerance: f64,
    pub damping: f64,
    pub max_iterations: u32,
    pub step_tolerance: f64,
}

impl PlacementOptions {
    pub(crate) fn clone_scalars(&self) -> Knobs {
        Knobs {
            tolerance: self.tolerance,
            damping: self.damping,
            max_iterations: self.max_iterations,
            step_tolerance: self.step_tolerance,
        }
    }
}
