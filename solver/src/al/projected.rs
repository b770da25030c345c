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
//! which have no inertia, get a metric of their own and move through a
//! low-rank (Woodbury) correction on the same factor, their bounds a box
//! (`design`). Objectives act through q₀ (`program::objective`).
//! Inequalities follow the force solve's active set (a released row is free
//! from the next tick on). The y are the step's multipliers: stored as λ
//! (equalities) and ν = max(0, −y) (inequalities).
//!
//! **Redundant rows** (found by `Program::new`, see `force::redundancy`)
//! take no part: they are left out of A's pattern, so their y is exactly 0.
//! Without that, A_JJ is singular
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

use super::design::DesignStep;
use super::moved::Moved;
use super::prediction::Prediction;
use super::scaling::{Role, Scaling};
use crate::force::feedback::Feedback;
use crate::{EvalError, Evaluation, FingerTarget, Jacobian, Model};

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
    /// 1 / (K w m̄) per finger row, F order; coupling rows (contact-finger
    /// proxies) are set per step from the tick's dt.
    k_inv: Vec<f64>,
    /// First row and row count of each finger constraint (model finger
    /// order), and whether it is a coupling (proxy).
    fingers: Vec<(usize, usize, bool)>,
    /// F index of each finger's first row (model finger order).
    f_first: Vec<usize>,
    /// Per moving body with a shape: its first column and bounding radius,
    /// metres (the contact speed limit measures how far its points move).
    reach: Vec<(usize, f64)>,
    /// How far each of `reach` may move in this tick, metres (the contact
    /// speed limit, per body: `dynamics::allowance_m`).
    allow: Vec<f64>,
    /// The largest fraction of its allowance the last taken step used up
    /// on any shaped body.
    moved_m: f64,
    /// Whether the contact speed limit shortened the last step.
    speed_limited: bool,
    /// The design columns' correction (models with design variables).
    design: Option<DesignStep>,
    /// Which contact rows a step can change (`moved`).
    moved: Moved,
    /// The inequality rows' prediction (`prediction`).
    prediction: Prediction,
    /// The next step is the last of its sequence (`set_last`).
    last: bool,
    /// Tests: every step forms the whole product (the old path), and how
    /// many last steps took the masked one.
    #[cfg(test)]
    pub(crate) test_whole: bool,
    #[cfg(test)]
    pub(crate) test_lasts: u64,
}

/// The virtual coupling of contact-finger proxies, as the projected step
/// needs it.
#[derive(Debug, Clone, Copy)]
pub(crate) struct CouplingStep<'a> {
    /// The tick's period, s.
    pub dt_s: f64,
    /// Spring k, N/m.
    pub stiffness_n_per_m: f64,
    /// Damper c, N·s/m.
    pub damping_n_s_per_m: f64,
    /// p − t of each finger at the end of the previous tick (model finger
    /// order), m.
    pub prev_error: &'a [nalgebra::Vector3<f64>],
}

impl Projected {
    /// Buffers for `model`. Allocates.
    pub fn new(
        model: &Model,
        s: &Scaling,
        gain: f64,
        finger_weight: f64,
        mean_mass_kg: f64,
    ) -> Self {
        let fingers: Vec<(usize, usize, bool)> = model
            .fingers()
            .iter()
            .map(|f| {
                let rows = &model.constraints()[f.constraint.index()].rows;
                (
                    rows.start,
                    rows.len(),
                    s.role.get(rows.start) == Some(&Role::Coupling),
                )
            })
            .collect();
        // F order is model row order over the finger rows (as in the Gram
        // matrix).
        let mut order: Vec<usize> = (0..fingers.len()).collect();
        order.sort_by_key(|&k| fingers[k].0);
        let mut f_first = vec![0; fingers.len()];
        let mut next = 0;
        for &k in &order {
            f_first[k] = next;
            next += fingers[k].1;
        }
        let m_f = fingers.iter().map(|f| f.1).sum();
        let (n, m) = (model.n_coords(), model.n_rows());
        let reach: Vec<(usize, f64)> = model
            .layout()
            .moving_bodies()
            .filter_map(|(id, o)| {
                let shape = model.bodies()[id.index()].shape.as_ref()?;
                Some((o, shape.collider().ok()?.radius_m))
            })
            .collect();
        Self {
            allow: vec![f64::INFINITY; reach.len()],
            reach,
            d: vec![0.0; n],
            jd: vec![0.0; m],
            jd_current: false,
            jm: vec![0.0; m],
            r: vec![0.0; m],
            y: vec![0.0; m],
            g: vec![0.0; n],
            mg: vec![0.0; n],
            k_inv: vec![1.0 / (gain * finger_weight * mean_mass_kg); m_f],
            fingers,
            f_first,
            moved_m: 0.0,
            speed_limited: false,
            design: None,
            moved: Moved::new(model),
            prediction: Prediction::new(model, &s.role),
            last: false,
            #[cfg(test)]
            test_whole: false,
            #[cfg(test)]
            test_lasts: 0,
        }
    }

    /// Starts a sequence of steps with one chord Jacobian and one q_ref:
    /// the next step forms C_q (q − q_ref) afresh; the later ones update it
    /// (a taken step moves q by −s (d + M̃⁻¹ g), so C_q d moves by
    /// −s (C_q d + C_q M̃⁻¹ g), and C_q M̃⁻¹ g is formed anyway for the
    /// inequality rows' prediction): one product per step saved. With design
    /// columns, d is pinned and corrected per step, so it is formed afresh
    /// every step.
    pub fn begin(&mut self) {
        self.jd_current = false;
        self.last = false;
        self.moved.begin();
    }

    /// Tells whether the next [`step`](Self::step) is the last of its
    /// sequence (the caller takes no further step before the next
    /// [`begin`](Self::begin)): it then forms C_q M̃⁻¹ g only where the
    /// activation test reads it (`prediction`). Applies to one call.
    pub fn set_last(&mut self, last: bool) {
        self.last = last;
        #[cfg(test)]
        {
            self.last &= !self.test_whole;
        }
    }

    /// Evaluates and multiplies every row in every step (`full`), or only
    /// the contact rows that can change (the default; see `moved`).
    pub fn set_full_steps(&mut self, full: bool, model: &Model) {
        self.moved.set_full(full, model);
    }

    /// Contact constraints the steps' evaluations left out, summed.
    pub fn skipped_contacts(&self) -> u64 {
        self.moved.skipped()
    }

    /// Switches design column `k` (among the design columns) off or on.
    pub fn set_design_off(&mut self, k: usize, off: bool) {
        if let Some(d) = &mut self.design {
            d.set_off(k, off);
        }
    }

    /// Lets the design columns of `model` move, with metric `w_kg` each (see
    /// `design`), keeping its `masked` equality rows (model row, ℓ) closed.
    /// Allocates.
    pub fn with_design(mut self, model: &Model, w_kg: f64, masked: &[(usize, f64)]) -> Self {
        self.design = DesignStep::new(model, w_kg, masked);
        self
    }

    /// The largest fraction of its tick's allowance the last step used up on
    /// any shaped body (0 without a contact speed limit).
    pub fn last_moved_m(&self) -> f64 {
        self.moved_m
    }

    /// Whether the contact speed limit shortened the last step.
    pub fn last_speed_limited(&self) -> bool {
        self.speed_limited
    }

    /// The moving bodies with a shape: first column and bounding radius, m.
    pub fn reach(&self) -> &[(usize, f64)] {
        &self.reach
    }

    /// Sets how far each of [`reach`](Self::reach) may move this tick, m
    /// (in `reach` order; missing entries keep their value).
    ///
    /// # Real-time
    /// No allocation.
    pub fn set_allowances(&mut self, allow: impl Iterator<Item = f64>) {
        for (a, v) in self.allow.iter_mut().zip(allow) {
            *a = v;
        }
    }

    /// The last step's multipliers y (per row, scaled as the step applied
    /// them: q = q₀ − M̃⁻¹ C_qᵀ y), finger rows included.
    pub fn multipliers(&self) -> &[f64] {
        &self.y
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
        contact_step_m: f64,
        coupling: &CouplingStep,
        lambda: &mut [f64],
    ) -> Result<Step, StepError> {
        self.moved
            .evaluate(model, ev, q, targets)
            .map_err(StepError::Eval)?;
        let ev: &Evaluation = ev;
        self.displacement(ev.jacobian(), q, q_ref)?;
        self.residual(s, ev.values(), fb.row_scale(), coupling);
        self.solve(ev, fb, q, step)?;
        let mut step = step;
        let mut size = self
            .d
            .iter()
            .zip(&self.mg)
            .zip(&s.sqrt_metric)
            .map(|((d, mg), w)| (step * (d + mg)).abs() * w)
            .fold(0.0, f64::max);
        if size > max_size_m {
            return Ok(Step::Refused);
        }
        self.speed_limit(contact_step_m, &mut step, &mut size);
        let Some(last) = self.predict(ev, s, fb, step)? else {
            return Ok(Step::Activate);
        };
        self.apply(s, q, step, last, lambda);
        Ok(Step::Taken(size))
    }

    /// d = q − q_ref (design columns pinned) and C_q d, kept across the
    /// steps of a sequence unless d changed outside them.
    #[inline]
    fn displacement(&mut self, jac: &Jacobian, q: &[f64], q_ref: &[f64]) -> Result<(), StepError> {
        let mut moved = false;
        for ((d, a), b) in self.d.iter_mut().zip(q.iter()).zip(q_ref) {
            *d = a - b;
            moved |= *d != 0.0;
        }
        if let Some(design) = &self.design {
            design.pin(q, &mut self.d);
            self.jd_current = false;
        }
        if !self.jd_current {
            if moved || self.design.is_some() {
                jac.mul_vec(&self.d, &mut self.jd)
                    .map_err(|_| StepError::NonFinite)?;
            } else {
                self.jd.fill(0.0);
            }
            self.jd_current = true;
        }
        Ok(())
    }

    /// The scaled right-hand side r = ℓ (C − C_q d), the proxies' coupling
    /// and the fingers' pull limit applied.
    #[inline]
    fn residual(&mut self, s: &Scaling, c: &[f64], scale: &[f64], coupling: &CouplingStep) {
        for i in 0..c.len() {
            self.r[i] = scale[i] * (c[i] - self.jd[i]);
        }
        // Proxies: the implicit spring-damper over one tick, weight
        // w = k dt² + c dt toward t + (c dt / w) (p_prev − t_prev).
        let w = coupling.stiffness_n_per_m * coupling.dt_s * coupling.dt_s
            + coupling.damping_n_s_per_m * coupling.dt_s;
        let w = w.max(1e-15);
        let damp = coupling.damping_n_s_per_m * coupling.dt_s / w;
        for (k, &(r0, n, proxy)) in self.fingers.iter().enumerate() {
            if !proxy {
                continue;
            }
            let e = coupling.prev_error.get(k).copied().unwrap_or_default();
            for (c3, i) in (r0..r0 + n.min(3)).enumerate() {
                self.r[i] = scale[i] * (c[i] - damp * e[c3] - self.jd[i]);
                self.k_inv[self.f_first[k] + c3] = 1.0 / w;
            }
        }
        // The pull limit: a finger group farther than d pulls as if d away.
        for &(r0, n, proxy) in &self.fingers {
            if proxy {
                continue;
            }
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
    }

    /// The multipliers y (unscaled) by the force factor and the design
    /// correction, and the step's direction mg = M⁻¹ C_qᵀ y.
    #[inline]
    fn solve(
        &mut self,
        ev: &Evaluation,
        fb: &mut Feedback,
        q: &[f64],
        step: f64,
    ) -> Result<(), StepError> {
        let jac = ev.jacobian();
        fb.project(&self.r, &self.k_inv, &mut self.y)
            .map_err(|_| StepError::Solve)?;
        let mut d_changed = false;
        if let Some(design) = &mut self.design {
            d_changed = design
                .correct(
                    ev,
                    fb,
                    &self.k_inv,
                    q,
                    &mut self.d,
                    &self.r,
                    &mut self.y,
                    step,
                )
                .map_err(|()| StepError::Solve)?;
        }
        let scale = fb.row_scale();
        for (y, sc) in self.y.iter_mut().zip(scale) {
            *y *= sc;
        }
        self.moved
            .mul_t_vec(jac, &self.y, &mut self.g)
            .map_err(|_| StepError::NonFinite)?;
        fb.apply_inverse_mass(&self.g, &mut self.mg);
        if let Some(design) = &self.design {
            for (&c, &mg) in design.cols.iter().zip(&design.mg) {
                self.mg[c] = mg;
            }
            if d_changed {
                jac.mul_vec(&self.d, &mut self.jd)
                    .map_err(|_| StepError::NonFinite)?;
            }
        }
        Ok(())
    }

    /// The contact speed limit (SolverSettings::contact_step_m, per body
    /// `allow`; `contact_step_m` is the fraction of it left this tick):
    /// how far any point of a shaped body would move, |Δr| + R |Δθ| with
    /// |Δθ| ≈ 2 |Δe| (unit e); shortens the step, keeping its direction.
    #[inline]
    fn speed_limit(&mut self, contact_step_m: f64, step: &mut f64, size: &mut f64) {
        if contact_step_m.is_finite() {
            let mut moved: f64 = 0.0;
            for (k, &(o, radius)) in self.reach.iter().enumerate() {
                let dr = (0..3)
                    .map(|c| (self.d[o + c] + self.mg[o + c]).powi(2))
                    .sum::<f64>()
                    .sqrt();
                let de = (3..7)
                    .map(|c| (self.d[o + c] + self.mg[o + c]).powi(2))
                    .sum::<f64>()
                    .sqrt();
                moved = moved.max(*step * (dr + 2.0 * radius * de) / self.allow[k]);
            }
            self.speed_limited = moved > contact_step_m;
            if self.speed_limited {
                *step *= contact_step_m / moved;
                *size *= contact_step_m / moved;
                moved = contact_step_m;
            }
            self.moved_m = moved;
        } else {
            self.moved_m = 0.0;
            self.speed_limited = false;
        }
    }

    /// Predicted values of the inactive inequality rows after the step
    /// (and the update of C_q d): `None` when some would be violated (they
    /// are marked in `fb.forced`), else whether this was the sequence's
    /// last step.
    #[inline]
    fn predict(
        &mut self,
        ev: &Evaluation,
        s: &Scaling,
        fb: &mut Feedback,
        step: f64,
    ) -> Result<Option<bool>, StepError> {
        let jac = ev.jacobian();
        // The last step of a sequence needs the product only for the
        // activation test (no C_q d update follows); with design columns or
        // the contact bookkeeping on, every step forms it as before.
        let last = std::mem::take(&mut self.last) && self.design.is_none() && !self.moved.enabled();
        #[cfg(test)]
        {
            self.test_lasts += u64::from(last);
        }
        if last {
            self.prediction
                .last_step_product(jac, &s.role, fb.row_scale(), &self.mg, &mut self.jm)
        } else {
            self.moved.mul_vec(jac, &self.mg, &mut self.jm)
        }
        .map_err(|_| StepError::NonFinite)?;
        let c = ev.values();
        let mut activate = false;
        for &i in self.prediction.rows() {
            if matches!(s.role[i], Role::Inequality | Role::Contact)
                && fb.row_scale()[i] == 0.0
                && c[i] - step * (self.jd[i] + self.jm[i]) < -ACTIVATE_TOLERANCE_M
            {
                fb.forced[i] = true;
                activate = true;
            }
        }
        Ok((!activate).then_some(last))
    }

    /// Applies the step to q and C_q d, and stores the multipliers as λ
    /// (equalities) and ν = max(0, −y) (inequalities).
    #[inline]
    fn apply(&mut self, s: &Scaling, q: &mut [f64], step: f64, last: bool, lambda: &mut [f64]) {
        for ((qc, d), mg) in q.iter_mut().zip(&self.d).zip(&self.mg) {
            *qc -= step * (d + mg);
        }
        if last {
            // jm holds only the prediction's rows: C_q d is formed afresh
            // should another step come before `begin`.
            self.jd_current = false;
        } else {
            for (jd, jm) in self.jd.iter_mut().zip(&self.jm) {
                *jd -= step * (*jd + jm);
            }
        }
        for (i, (l, &y)) in lambda.iter_mut().zip(&self.y).enumerate() {
            *l = match s.role[i] {
                Role::Equality | Role::Friction => y,
                Role::Finger
                | Role::Coupling
                | Role::Redundant
                | Role::DesignBound
                | Role::DesignPin => 0.0,
                Role::Inequality | Role::Contact => (-y).max(0.0),
            };
        }
    }
}
