//! The projected update (DESIGN §4.3, "going beyond"): a Gauss–Newton / chord
//! step that reuses the factor of C_q M⁻¹ C_qᵀ the force solve computed at
//! the end of the previous tick, instead of Eq. 3's gradient step.
//!
//! Plain Eq. 3 converges linearly with the condition number of the scaled
//! Gram matrix, and the slowest mode is the one that matters: the finger
//! dragging the whole linkage along its free motion (on the four-bar that mode
//! is ~1/80 of σ_max, so a finger lags by centimetres at 6 cm/s; trade-off
//! table). Each tick here solves the linearised least-astonishment problem
//!
//! ```text
//! min_Δ  ½ (d + Δ)ᵀ M (d + Δ) + ½ K m̄ Σ_F (ℓ (C_F + J_F Δ))²
//! s.t.   C_J + J_J Δ = 0                      (joints, norms, active limits)
//! ```
//!
//! with d = q − q₀, m̄ the mean body mass (so K stays dimensionless), and J the
//! Jacobian at the tick's start q_s (chord). Its KKT conditions give
//! Δ = −d − M⁻¹ Jᵀ y with
//!
//! ```text
//! [A_JJ  A_JF            ] [y_J]   [C_J − J_J d]
//! [A_FJ  A_FF + 1/(K m̄) ] [y_F] = [C_F − J_F d],     A = J M⁻¹ Jᵀ (scaled by ℓ)
//! ```
//!
//! which is the force solve's matrix plus a diagonal on the finger block: one
//! sparse solve with the existing factor and an m_f × m_f Cholesky of its
//! Schur complement per iteration, no new factorisation. The least-astonishment
//! metric becomes the mass matrix (Gauss's least constraint); design variables,
//! which have no inertia, stay fixed (only the gradient update moves them).
//! Inequalities follow the force solve's active set (a released row is free
//! from the next tick on). The y are the step's multipliers: stored as λ
//! (equalities) and ν = max(0, −y) (inequalities).
//!
//! **Redundant rows** (found by `Program::new`, see `force::redundancy`)
//! take no part: the factor holds them as decoupled unit rows with a zero
//! right-hand side, so their y is exactly 0. Without that, A_JJ is singular
//! and off the manifold the right-hand side has parts in C_q's left null
//! space that the round-off pivots turn into enormous y.
//!
//! **Chord divergence.** The factor is the previous tick's. Near a singular
//! pose (the Peaucellier linkage's dead point, where its rhombus goes flat)
//! the kept rows lose rank, the linearisation holds only over tiny steps,
//! and the chord iteration diverges: each step 50–9000× the one before
//! (measured: 8 mm, 0.4 m, 3 km, 6000 km within one tick). A converging chord iteration
//! contracts (ratios 0.1–0.7), so `Program::tick` refuses a step more than
//! twice as large as the tick's previous one (the step is sized before it
//! is applied) and ends the tick's iterations there; the next tick starts
//! from a fresh factor. Through the dead point
//! that costs a few ticks of up to 0.7 mm violation, and the linkage folds
//! into its other branch instead of flying apart.

use super::scaling::{Role, Scaling};
use crate::force::feedback::Feedback;
use crate::{EvalError, Evaluation, FingerTarget, Model};

/// A predicted violation below this (metres) makes an inactive inequality
/// row active within the tick (10 nm: round-off of a step that slides along
/// a resting contact never triggers it).
pub(crate) const ACTIVATE_TOLERANCE_M: f64 = 1e-8;

/// What one projected step did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Step {
    /// Applied; its largest scaled coordinate change, metres.
    Taken(f64),
    /// Refused: larger than allowed (a diverging chord iteration).
    Refused,
    /// Not applied: it would violate inactive inequality rows, now marked in
    /// the force solve's `forced` set; refactor and take it again.
    Activate,
}

/// Why a projected step failed (the program turns it into its tick outcome).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum StepError {
    /// C could not be evaluated at q (a non-finite q or target).
    Eval(EvalError),
    /// A product produced a NaN or infinity.
    NonFinite,
    /// The solve with the force factor failed.
    Solve,
}

/// Buffers of the projected step.
#[derive(Debug, Clone)]
pub(crate) struct Projected {
    d: Vec<f64>,
    /// C_q d with the chord C_q, kept up to date across the steps of one
    /// sequence (see [`Projected::begin`]).
    jd: Vec<f64>,
    /// `jd` holds C_q (q − q_ref) for the current q.
    jd_current: bool,
    jm: Vec<f64>,
    r: Vec<f64>,
    y: Vec<f64>,
    g: Vec<f64>,
    mg: Vec<f64>,
    /// 1 / (K w m̄) per finger row, F order.
    k_inv: Vec<f64>,
    /// First row and row count of each finger constraint.
    fingers: Vec<(usize, usize)>,
}

impl Projected {
    /// Buffers for `model`. Allocates.
    pub fn new(model: &Model, gain: f64, finger_weight: f64, mean_mass_kg: f64) -> Self {
        let fingers: Vec<(usize, usize)> = model
            .fingers()
            .iter()
            .map(|f| {
                let rows = &model.constraints()[f.constraint.index()].rows;
                (rows.start, rows.len())
            })
            .collect();
        let m_f = fingers.iter().map(|f| f.1).sum();
        let (n, m) = (model.n_coords(), model.n_rows());
        Self {
            d: vec![0.0; n],
            jd: vec![0.0; m],
            jm: vec![0.0; m],
            r: vec![0.0; m],
            y: vec![0.0; m],
            g: vec![0.0; n],
            mg: vec![0.0; n],
            k_inv: vec![1.0 / (gain * finger_weight * mean_mass_kg); m_f],
            fingers,
            jd_current: false,
        }
    }

    /// Starts a sequence of steps with one chord Jacobian and one q_ref:
    /// the next step forms C_q (q − q_ref) afresh; the later ones update it
    /// (a taken step moves q by −s (d + M̃⁻¹ g), so C_q d moves by
    /// −s (C_q d + C_q M̃⁻¹ g), and C_q M̃⁻¹ g is formed anyway for the
    /// inequality rows' prediction): one product per step saved.
    pub fn begin(&mut self) {
        self.jd_current = false;
    }

    /// One projected step of size `step` (1 = the full Gauss–Newton step) from
    /// `q` toward `targets`, with q₀ = `q_ref`, the Jacobian stored in `ev` and
    /// the factor held by `fb` (both at the tick's start). Returns the step's
    /// size, its largest scaled coordinate change (r in metres, e times L),
    /// or `None`, leaving q and `lambda` untouched, when that size exceeds
    /// `max_size_m` (a diverging chord iteration, see the module docs).
    ///
    /// # Real-time
    /// No allocation; a value-only evaluation, C_q·v and C_qᵀ·v, one pair of
    /// sparse triangular solves, an m_f × m_f Cholesky.
    #[allow(clippy::too_many_arguments)]
    pub fn step(
        &mut self,
        model: &Model,
        s: &Scaling,
        ev: &mut Evaluation,
        fb: &mut Feedback,
        q: &mut [f64],
        q_ref: &[f64],
        targets: &[FingerTarget],
        step: f64,
        max_size_m: f64,
        lambda: &mut [f64],
    ) -> Result<Step, StepError> {
        ev.evaluate_values(model, q, targets)
            .map_err(StepError::Eval)?;
        let mut moved = false;
        for ((d, a), b) in self.d.iter_mut().zip(q.iter()).zip(q_ref) {
            *d = a - b;
            moved |= *d != 0.0;
        }
        let jac = ev.jacobian();
        if !self.jd_current {
            if moved {
                jac.mul_vec(&self.d, &mut self.jd)
                    .map_err(|_| StepError::NonFinite)?;
            } else {
                self.jd.fill(0.0);
            }
            self.jd_current = true;
        }
        let (c, scale) = (ev.values(), fb.row_scale());
        for i in 0..c.len() {
            self.r[i] = scale[i] * (c[i] - self.jd[i]);
        }
        // The pull limit: a finger group farther than d pulls as if d away.
        for &(r0, n) in &self.fingers {
            for g0 in (r0..r0 + n).step_by(3) {
                let norm = (g0..g0 + 3)
                    .map(|i| (s.ell[i] * c[i]).powi(2))
                    .sum::<f64>()
                    .sqrt();
                if norm > s.finger_limit_m {
                    let f = s.finger_limit_m / norm;
                    for i in g0..g0 + 3 {
                        self.r[i] = scale[i] * (f * c[i] - self.jd[i]);
                    }
                }
            }
        }
        fb.project(&self.r, &self.k_inv, &mut self.y)
            .map_err(|_| StepError::Solve)?;
        let scale = fb.row_scale();
        for (y, sc) in self.y.iter_mut().zip(scale) {
            *y *= sc;
        }
        jac.mul_t_vec(&self.y, &mut self.g)
            .map_err(|_| StepError::NonFinite)?;
        fb.apply_inverse_mass(&self.g, &mut self.mg);
        let size = self
            .d
            .iter()
            .zip(&self.mg)
            .zip(&s.sqrt_metric)
            .map(|((d, mg), w)| (step * (d + mg)).abs() * w)
            .fold(0.0, f64::max);
        if size > max_size_m {
            return Ok(Step::Refused);
        }
        // Predicted values of the inactive inequality rows after the step
        // (and the update of C_q d).
        jac.mul_vec(&self.mg, &mut self.jm)
            .map_err(|_| StepError::NonFinite)?;
        let c = ev.values();
        let mut activate = false;
        for (i, &ci) in c.iter().enumerate() {
            if matches!(s.role[i], Role::Inequality | Role::Contact)
                && fb.row_scale()[i] == 0.0
                && ci - step * (self.jd[i] + self.jm[i]) < -ACTIVATE_TOLERANCE_M
            {
                fb.forced[i] = true;
                activate = true;
            }
        }
        if activate {
            return Ok(Step::Activate);
        }
        for ((qc, d), mg) in q.iter_mut().zip(&self.d).zip(&self.mg) {
            *qc -= step * (d + mg);
        }
        for (jd, jm) in self.jd.iter_mut().zip(&self.jm) {
            *jd -= step * (*jd + jm);
        }
        for (i, (l, &y)) in lambda.iter_mut().zip(&self.y).enumerate() {
            *l = match s.role[i] {
                Role::Equality | Role::Friction => y,
                Role::Finger | Role::Redundant => 0.0,
                Role::Inequality | Role::Contact => (-y).max(0.0),
            };
        }
        Ok(Step::Taken(size))
    }
}
