//! The fast-loop force pipeline of one [`Program`](crate::Program): motion
//! history → b = Q_e + Q_v − M q̈ → scaled Gram matrix → finger multipliers →
//! Eq. 8 wrench, plus the virtual coupling.

use nalgebra::{Quaternion, UnitQuaternion, Vector3};

use super::friction::FrictionPair;
use super::gram::{Gram, Slot};
use super::inertia::BodyMass;
use super::motion::Motion;
use super::output::FingerOutput;
use super::redundancy::{self, Redundancy};
use super::reference::INEQUALITY_ACTIVE_BAND;
use super::solve::{FactorError, MultiplierSolve};
use super::wrench::on_finger;
use crate::al::scaling::{Role, Scaling};
use crate::al::{ForceSolver, RedundancyCheck};
use crate::rotation::BodyFrame;
use crate::{Evaluation, FingerTarget, Model, SolverSettings, UpdateRule};

/// The small accessors and re-factorisations around `compute`.
mod access;
/// The construction (`Feedback::new`).
mod build;
/// The release branch's second solve by a low-rank correction.
mod low_rank;
mod norms;
/// The release branch's second and third solves from the first.
mod spare;

/// One finger's rows and where its body's columns sit in each of them.
#[derive(Debug, Clone)]
struct FingerRows {
    rows: std::ops::Range<usize>,
    /// Value index of the body's first column in each row (≤ 6 rows).
    pos: [usize; 6],
    offset: usize,
    point: Vector3<f64>,
    rigid: bool,
    /// A contact finger's proxy under inertial motion (its rows have
    /// [`Role::Coupling`]): the coupling force is known, not solved for.
    proxy: bool,
    /// A point on a flexible body: it moves with the deformation.
    flex: Option<crate::flexible::anchor::FlexAnchor>,
}

impl FingerRows {
    /// The attachment point, body frame, at `q` (deformed on a flexible
    /// body).
    #[inline]
    fn point_at(&self, q: &[f64]) -> Vector3<f64> {
        self.flex.map_or(self.point, |a| a.point(q))
    }
}

/// Buffers and factor of the force computation.
#[derive(Debug, Clone)]
pub(crate) struct Feedback {
    pub masses: Vec<BodyMass>,
    pub motion: Motion,
    gram: Gram,
    solve: MultiplierSolve,
    /// The coupled pattern for the assemblies where the decoupled one is
    /// not exact (`norms`); `None` without decoupled norm rows or with a
    /// force solver other than the Cholesky.
    coupled: Option<norms::CoupledPattern>,
    fingers: Vec<FingerRows>,
    b: Vec<f64>,
    y: Vec<f64>,
    cy: Vec<f64>,
    scale: Vec<f64>,
    /// attachment − target at the previous tick, per finger (coupling damping).
    prev_error: Vec<Vector3<f64>>,
    /// Ticks on which an active inequality would have pulled and was
    /// released (the solve ran again without it).
    releases: u64,
    /// Per row: a friction stick row that is currently sticking (active).
    pub stick: Vec<bool>,
    /// Per row: an inequality row a step of this tick predicted would be
    /// violated, kept active until the tick's force solve (and through it,
    /// see `carry_forced`).
    pub forced: Vec<bool>,
    /// Set by a tick whose last in-tick activation took no step after it
    /// (out of refactorisations, or stopped): its forced rows have no
    /// multiplier from a step yet, so the force solve at the tick's end keeps
    /// them active (unless they pull) instead of dropping them. A resting
    /// contact sits at gap 0 with λ = 0 then, and would be released and
    /// activated again every tick (issue 23: a 4-layer pile needs four
    /// activations, one per layer, and never got past three). Consumed by
    /// the next `compute`.
    pub carry_forced: bool,
    /// The fingertip pairs with friction rows.
    pub friction: Vec<FrictionPair>,
    /// Ticks on which a sticking pair left the Coulomb cone (slipped).
    slips: u64,
    /// Per finger: p − t and its rate at this compute (the coupling).
    coupling: Vec<(Vector3<f64>, Vector3<f64>)>,
    /// F order: finger multipliers known in advance (proxies).
    known: Vec<Option<f64>>,
    /// The largest pulling force of an active contact row in the last solve,
    /// N (0 when every contact pushes or none is active).
    pub max_pull_n: f64,
    /// Per friction pair: its normal force in the last solve, N (Eq. 7,
    /// physical; kinetic friction of a slipping pair is μ times it).
    pub normal_force_n: Vec<f64>,
    /// Per row: a contact or friction row, solved with a small relative
    /// compliance ([`CONTACT_COMPLIANCE`]).
    compliant: Vec<bool>,
    /// Counts the factorisations: whatever caches products with the factor
    /// (the projected update's design columns) recomputes when it changes.
    pub generation: u64,
    /// The named joints' motor torques (§5.2; `torque`).
    torques: Option<super::torque::JointTorques>,
    /// Per flexible body of the model: its body's column offset (its
    /// deformation columns' b is the elastic force, `crate::flexible`).
    flex_offsets: Vec<usize>,
    /// Per moving body: a force (N, at its centre of mass) and torque (N·m)
    /// known in advance, world frame, added to Eq. 7's Q_e: the kinetic
    /// friction of slipping contacts (inertial motion), which no row holds.
    pub applied: Vec<(Vector3<f64>, Vector3<f64>)>,
    /// Per coordinate: the generalized force of the last step's contact and
    /// friction rows (scratch of [`Feedback::take_contact_forces`]).
    contact_raw: Vec<f64>,
    /// Per row: its force in the steps, physical sign (λ > 0 pulls, so a
    /// push is < 0), N, through the two filter stages (`row_known`: after
    /// the second). With known contact forces a row's force in Eq. 7 is
    /// this plus its multiplier (`row_force`).
    row_known_f: Vec<f64>,
    row_known: Vec<f64>,
    /// The first solve kept aside by the release branch (`spare`).
    spare: Option<Box<spare::Spare>>,
    /// Ticks whose third solve was the first one, kept (`spare`).
    first_kept: u64,
}

/// Relative compliance of contact and friction rows in A: their diagonal is
/// scaled by 1 + this. Four corners of a face resting on another are four
/// rows of rank three (a plane contact holds three motions), so A_JJ is
/// singular whenever they all push; the faer regularisation then turns the
/// null direction into 1e10-sized entries of A_JJ⁻¹ and the finger's Schur
/// complement into noise (measured: diagonal entries of −414 where the
/// true S is positive semidefinite). With the compliance the redundant
/// rows share the load (the minimum-norm split, as a stiff contact patch
/// does) and every row holds to 1e-6 of its own scale.
pub(crate) const CONTACT_COMPLIANCE: f64 = 1e-6;

/// Whether Eq. 7 takes the contact and friction forces as known from the
/// projected steps (inertial motion): their filtered generalized force
/// (`Motion::contact_a`) goes into b, and their rows, still in A (one
/// factorisation a tick, the step's), take only what the filtered balance
/// leaves over, of either sign (not released when it "pulls").
///
/// Under inertial motion the steps are the physics: a body's velocity
/// changes by exactly the impulses of its rows. Eq. 7 balances the
/// *filtered* M q̈, which spreads a contact's impulse over the next
/// τ + τ_a; a contact row that takes part only while it is closed cannot
/// carry that tail. A link pushing a sliding box follows the device's
/// encoder counts (30 µm steps of a PHANToM), strikes the box for one tick
/// and the box coasts ahead: the closed row saw a quarter of the ticks and
/// the hand felt 0.13 N of the box's μ m g = 0.49 N (issue 19,
/// `arm-push`). The steps' contact forces, filtered like q̈, balance the
/// box's filtered M q̈ (up to the filter's lag on its kinetic friction)
/// and pass its mean push, μ m g, to the links: 0.52 N. (Taking the rows
/// out of Eq. 7 instead gave 0.51 N, at a second factorisation on every
/// tick with a contact.)
pub(crate) fn contact_forces_known(settings: &SolverSettings) -> bool {
    settings.dynamics && settings.update == UpdateRule::Projected
}

impl Feedback {
    /// Equality rows dependent on earlier rows of the same body pair at q0
    /// (`ev` evaluated there): to leave out of A before it is built (pass them
    /// to [`Feedback::new`] as excluded). Allocates.
    pub fn locally_dependent(model: &Model, ev: &Evaluation, s: &Scaling) -> Vec<usize> {
        redundancy::locally_dependent(model, ev, s, &BodyMass::of_model(model))
    }

    /// Finds the rows of `model` to mask (see `redundancy`) at q0, where `ev`
    /// is evaluated. Leaves the factor of a test matrix behind: refactor
    /// (`compute`) before stepping. Allocates.
    pub fn find_redundant(
        &mut self,
        model: &Model,
        ev: &Evaluation,
        s: &Scaling,
        mode: RedundancyCheck,
    ) -> Redundancy {
        redundancy::detect(
            model,
            ev,
            s,
            mode,
            &mut self.gram,
            &mut self.solve,
            &self.masses,
        )
    }

    /// Advances the motion history to `q` (unless `advance` is false: a
    /// refresh at an unchanged state) and computes every finger's output at
    /// the evaluated `ev` (C and C_q at `q` with `targets`). `lambda` holds
    /// the multipliers: an inequality row takes part (is active) when its
    /// ν > 0 or it is violated by more than [`INEQUALITY_ACTIVE_BAND`]; an
    /// active row that would pull is released for this tick.
    ///
    /// # Real-time
    /// No allocation, no locks. Time: O(bodies + Σ_b rows_b²) assembly, one
    /// numeric sparse Cholesky with the symbolic analysis of `new`, one
    /// solve through it, an m_f × m_f Cholesky or eigensolve.
    #[allow(clippy::too_many_arguments)]
    pub fn compute(
        &mut self,
        model: &Model,
        s: &Scaling,
        settings: &SolverSettings,
        q: &[f64],
        ev: &Evaluation,
        lambda: &[f64],
        targets: &[FingerTarget],
        dt_s: f64,
        advance: bool,
        out: &mut [FingerOutput],
    ) -> Result<(), FactorError> {
        // Rows forced active by the tick's steps are decided afresh by their
        // multipliers and values now, unless no step gave them a multiplier
        // (`carry_forced`): those stay active while they push.
        if !std::mem::take(&mut self.carry_forced) {
            self.forced.fill(false);
        }
        if advance {
            self.motion.advance(&self.masses, q, dt_s);
        }
        self.right_hand_side(model, q)?;
        self.couplings(s, settings, q, targets, dt_s)?;
        self.activate(s, ev.values(), lambda);
        // Inertial motion: the contact and friction forces are the steps'
        // own, known (`take_contact_forces`); their rows stay in A and take
        // only what the filtered balance leaves over, of either sign.
        let known = contact_forces_known(settings);
        if known {
            for (b, f) in self.b.iter_mut().zip(&self.motion.contact_a) {
                *b += f;
            }
        }
        self.solve_multipliers(ev, settings)?;
        // An active inequality may only push (physical λ ≤ 0 in Eq. 6's
        // sign). If the solve made one pull, release those rows and solve
        // again: the bound keeps the tick's cost fixed. A sticking pair that
        // leaves the Coulomb cone slips (its rows released) the same way.
        let pulled = self.release_pulling(s, known);
        let slipped = self.judge_friction(model, s, settings, q, ev, targets);
        if !(pulled || slipped) {
            self.max_pull_n = self.contact_pull(s);
            self.pair_normal_forces(s);
            self.joint_torques(q, ev);
            return self.wrenches(s, settings, q, ev, targets, out);
        }
        self.releases += 1;
        self.solve_released(ev, settings)?;
        self.max_pull_n = self.contact_pull(s);
        self.pair_normal_forces(s);
        self.joint_torques(q, ev);
        self.wrenches(s, settings, q, ev, targets, out)?;
        if settings.update == UpdateRule::Projected {
            // The projected update steps with this factor and must keep the
            // kinematic active set: whether a limit stops the motion the user
            // asks for is its business, not the instantaneous inertial load's
            // (a stop that just halted a rebound "pulls" for a tick). The
            // first solve comes back from the spare when the active set is
            // its own again; otherwise a third factorisation.
            self.activate(s, ev.values(), lambda);
            if !self.restore_first() {
                self.solve_multipliers(ev, settings)?;
            }
        }
        Ok(())
    }

    /// b = Q_e + Q_v − M q̈ per moving body at `q` (plus the forces known
    /// in advance, `applied`) and each flexible body's elastic force.
    #[inline]
    fn right_hand_side(&mut self, model: &Model, q: &[f64]) -> Result<(), FactorError> {
        let g = model.gravity_m_s2();
        for (k, m) in self.masses.iter().enumerate() {
            let f = frame(q, m.offset).ok_or(FactorError)?;
            let mo = &self.motion;
            let o = m.offset;
            m.generalized_force(
                &f,
                &g,
                &mo.a[k],
                &mo.w[k],
                &mo.alpha[k],
                &mut self.b[o..o + 7],
            );
            let (force, torque) = self.applied[k];
            if force != Vector3::zeros() || torque != Vector3::zeros() {
                let te = f.omega.transpose() * torque;
                for c in 0..3 {
                    self.b[o + c] += force[c];
                }
                for c in 0..4 {
                    self.b[o + 3 + c] += te[c];
                }
            }
        }
        for (fb, &o) in model.flexible.iter().zip(&self.flex_offsets) {
            let f = frame(q, o).ok_or(FactorError)?;
            let (c, w) = (fb.col, fb.width());
            let a = c - self.motion.aux_start;
            fb.generalized_force(
                q,
                &f.rot,
                &g,
                &self.motion.aux_a[a..a + w],
                &mut self.b[c..c + w],
            );
        }
        Ok(())
    }

    /// Releases (scale 0) the active inequality rows, and the contact rows
    /// unless their forces are `known`, that the last solve made pull;
    /// whether any was.
    #[inline]
    fn release_pulling(&mut self, s: &Scaling, known: bool) -> bool {
        let mut released = false;
        for (j, &row) in self.gram.j_rows.iter().enumerate() {
            let releasable = match s.role[row] {
                Role::Inequality => true,
                Role::Contact => !known,
                _ => false,
            };
            if releasable && self.scale[row] != 0.0 && self.solve.joint_multiplier(j) > 0.0 {
                self.scale[row] = 0.0;
                self.forced[row] = false;
                released = true;
            }
        }
        released
    }

    /// Coulomb: a sticking pair whose friction load exceeds μ times the
    /// user's grip slips this tick (its rows released); whether any did.
    /// (Inertial motion judges the cone on the step's own forces instead:
    /// `program::inertial`.)
    #[inline]
    fn judge_friction(
        &mut self,
        model: &Model,
        s: &Scaling,
        settings: &SolverSettings,
        q: &[f64],
        ev: &Evaluation,
        targets: &[FingerTarget],
    ) -> bool {
        let mut released = false;
        let judged = if settings.dynamics {
            0
        } else {
            self.friction.len()
        };
        for k in 0..judged {
            let p = self.friction[k];
            if !(self.stick[p.rows[0]] && self.scale[p.rows[0]] != 0.0) {
                continue;
            }
            let mut lt2 = 0.0;
            for &row in &p.rows {
                if let Slot::J(j) = self.gram.slot[row] {
                    lt2 += (s.ell[row] * self.solve.joint_multiplier(j)).powi(2);
                }
            }
            let proxy = p.finger.is_none_or(|f| self.fingers[f].proxy);
            let grip = if proxy {
                // The contact's own normal force (Eq. 7, physical).
                (p.normal_rows[0]..p.normal_rows[1])
                    .filter(|&row| self.scale[row] != 0.0)
                    .filter_map(|row| match self.gram.slot[row] {
                        Slot::J(j) => Some((-s.ell[row] * self.solve.joint_multiplier(j)).max(0.0)),
                        _ => None,
                    })
                    .sum()
            } else {
                super::friction::grip(
                    model,
                    q,
                    ev.witnesses(),
                    targets,
                    settings.coupling_stiffness_n_per_m,
                    &p,
                )
            };
            if lt2.sqrt() > p.mu * grip {
                for &row in &p.rows {
                    self.stick[row] = false;
                    self.scale[row] = 0.0;
                }
                self.slips += 1;
                released = true;
            }
        }
        released
    }

    /// The named joints' motor torques with the factor of the last solve
    /// (`torque`; NaN with the conjugate-gradient solver, which has no
    /// factor).
    fn joint_torques(&mut self, q: &[f64], ev: &Evaluation) {
        let Some(t) = &mut self.torques else { return };
        if self.solve.cg.is_some() {
            t.clear();
            return;
        }
        t.compute(
            &self.gram,
            &mut self.solve,
            &self.masses,
            &self.scale,
            &self.b,
            q,
            ev,
        );
    }

    /// The named joints' motor torques (N·m, or N on a prismatic joint) at
    /// the last force solve, [`Model::torque_joints`] order; NaN after a
    /// failed tick.
    pub fn joint_torques_out(&self) -> &[f64] {
        self.torques.as_ref().map_or(&[], |t| &t.torque)
    }

    /// Marks the torques unknown (a failed tick).
    pub fn clear_torques(&mut self) {
        if let Some(t) = &mut self.torques {
            t.clear();
        }
    }

    /// Each friction pair's normal force in the last solve, N.
    fn pair_normal_forces(&mut self, s: &Scaling) {
        for (k, p) in self.friction.iter().enumerate() {
            self.normal_force_n[k] = (p.normal_rows[0]..p.normal_rows[1])
                .filter(|&row| self.scale[row] != 0.0)
                .filter_map(|row| match self.gram.slot[row] {
                    Slot::J(j) => Some((-self.row_force(s, row, j)).max(0.0)),
                    _ => None,
                })
                .sum();
        }
    }

    /// The largest pull (physical λ > 0, N) of an active contact row in the
    /// last solve (with known contact forces, the row's known force and its
    /// multiplier together: `row_force`).
    fn contact_pull(&self, s: &Scaling) -> f64 {
        let mut pull: f64 = 0.0;
        for (j, &row) in self.gram.j_rows.iter().enumerate() {
            if s.role[row] == Role::Contact && self.scale[row] != 0.0 {
                pull = pull.max(self.row_force(s, row, j));
            }
        }
        pull
    }

    /// Row `row`'s force in the last solve, physical sign (λ > 0 pulls), N:
    /// ℓ times its multiplier (slot `j`) plus its filtered force from the
    /// steps (`row_known`; 0 unless contact forces are known,
    /// `contact_forces_known`).
    fn row_force(&self, s: &Scaling, row: usize, j: usize) -> f64 {
        s.ell[row] * self.solve.joint_multiplier(j) + self.row_known[row]
    }

    /// Inertial motion: the generalized force −(ℓ C_q)ᵀ y / dt² of the
    /// contact and friction rows in the step just taken (`y` its
    /// multipliers, `jac` C_q; rows out of the step's factor have none),
    /// into the filtered history Eq. 7 balances ([`Feedback::compute`]).
    ///
    /// # Real-time
    /// No allocation; O(nonzeros of the contact rows + coordinates).
    pub fn take_contact_forces(
        &mut self,
        s: &Scaling,
        jac: &crate::Jacobian,
        y: &[f64],
        dt_s: f64,
    ) {
        self.contact_raw.fill(0.0);
        let (ptr, cols, vals) = (jac.row_ptr(), jac.col_idx(), jac.values());
        let inv_dt2 = 1.0 / (dt_s * dt_s);
        let (alpha_f, alpha_a) = self.motion.alphas(dt_s);
        for (i, &role) in s.role.iter().enumerate() {
            let stepped = matches!(role, Role::Contact | Role::Friction) && self.scale[i] != 0.0;
            // Physical sign (Eq. 7's λ): the step's y is −ν for a push.
            let lambda = if stepped {
                s.ell[i] * y[i] * inv_dt2
            } else {
                0.0
            };
            self.row_known_f[i] += (lambda - self.row_known_f[i]) * alpha_f;
            self.row_known[i] += (self.row_known_f[i] - self.row_known[i]) * alpha_a;
            let f = -lambda;
            if f == 0.0 {
                continue;
            }
            for p in ptr[i]..ptr[i + 1] {
                self.contact_raw[cols[p]] += vals[p] * f;
            }
        }
        self.motion.advance_contact(&self.contact_raw, dt_s);
    }

    /// Row scales: ℓ_i for equality and finger rows and for inequality rows
    /// with ν > 0 or C < −band; 0 for the other inequality rows and for
    /// redundant (masked) rows, which the assembly then decouples (unit
    /// diagonal, zero coupling, zero right-hand side: multiplier exactly 0).
    fn activate(&mut self, s: &Scaling, c: &[f64], lambda: &[f64]) {
        for (i, sc) in self.scale.iter_mut().enumerate() {
            let active = match s.role[i] {
                Role::Inequality | Role::Contact => {
                    lambda[i] > 0.0 || c[i] < -INEQUALITY_ACTIVE_BAND || self.forced[i]
                }
                Role::Equality | Role::Finger | Role::Coupling => true,
                Role::Friction => self.stick.get(i).copied().unwrap_or(false),
                // Design rows touch no body: never part of the solve.
                Role::Redundant | Role::DesignBound | Role::DesignPin => false,
            };
            *sc = if active { s.ell[i] } else { 0.0 };
        }
    }

    /// Assembles the scaled Gram matrix with the current row scales (0 drops
    /// a row), regularises it and solves for λ̃_F.
    fn solve_multipliers(
        &mut self,
        ev: &Evaluation,
        settings: &SolverSettings,
    ) -> Result<(), FactorError> {
        self.generation = self.generation.wrapping_add(1);
        self.assemble_regularized(ev, settings);
        self.solve_assembled(ev)
    }

    /// C y scaled, and the solve for λ̃_F with the assembled A.
    fn solve_assembled(&mut self, ev: &Evaluation) -> Result<(), FactorError> {
        let jac = ev.jacobian();
        jac.mul_vec(&self.y, &mut self.cy)
            .map_err(|_| FactorError)?;
        for (v, sc) in self.cy.iter_mut().zip(&self.scale) {
            *v *= sc;
        }
        self.solve.solve(&self.gram, &self.cy, &self.known)
    }

    /// Assembles the scaled Gram matrix with the current row scales (0
    /// drops a row: unit diagonal) at the motion history's newest q, and
    /// y = M̃⁻¹ b; adds the Tikhonov term and the contact compliance.
    fn assemble_regularized(&mut self, ev: &Evaluation, settings: &SolverSettings) {
        let jac = ev.jacobian();
        // After `advance`, the motion history's newest q is this tick's q.
        self.pick_pattern(jac);
        let q = &self.motion.q_prev;
        self.gram
            .assemble(q, jac, &self.scale, &self.masses, &self.b, &mut self.y);
        self.note_assembly();
        self.regularize(settings);
    }

    /// Adds the Tikhonov term (a fraction of the taking-part rows' mean
    /// diagonal) and the contact compliance to A's diagonal; unit diagonal
    /// for dropped rows.
    fn regularize(&mut self, settings: &SolverSettings) {
        let (mut sum, mut count) = (0.0, 0usize);
        for (&d, &row) in self.gram.diag.iter().zip(&self.gram.j_rows) {
            if self.scale[row] != 0.0 {
                sum += self.gram.values[d];
                count += 1;
            }
        }
        let mu = settings.force_regularization * sum / count.max(1) as f64;
        for j in 0..self.gram.n_j {
            let (d, row) = (self.gram.diag[j], self.gram.j_rows[j]);
            self.gram.values[d] = if self.scale[row] == 0.0 {
                1.0
            } else if self.compliant[row] {
                self.gram.values[d] * (1.0 + CONTACT_COMPLIANCE) + mu
            } else {
                self.gram.values[d] + mu
            };
        }
    }

    /// Each finger's coupling error p − t and its rate, and the known
    /// multipliers of proxies: λ_F = k (p − t) + c (ṗ − ṫ) (the coupling's
    /// force on the fingertip is −λ_F).
    fn couplings(
        &mut self,
        s: &Scaling,
        settings: &SolverSettings,
        q: &[f64],
        targets: &[FingerTarget],
        dt_s: f64,
    ) -> Result<(), FactorError> {
        for (k, fr) in self.fingers.iter().enumerate() {
            let f = frame(q, fr.offset).ok_or(FactorError)?;
            let err = f.point(&fr.point_at(q)) - targets[k].position_m;
            let rate = if self.motion.ticks > 1 && dt_s > 0.0 {
                (err - self.prev_error[k]) / dt_s
            } else {
                Vector3::zeros()
            };
            self.coupling[k] = (err, rate);
            if fr.proxy {
                let force = err * settings.coupling_stiffness_n_per_m
                    + rate * settings.coupling_damping_n_s_per_m;
                for (c, r) in fr.rows.clone().take(3).enumerate() {
                    if let Slot::F(fi) = self.gram.slot[r] {
                        self.known[fi] = Some(force[c] / s.ell[r]);
                    }
                }
            }
        }
        Ok(())
    }

    #[allow(clippy::too_many_arguments)]
    fn wrenches(
        &mut self,
        s: &Scaling,
        settings: &SolverSettings,
        q: &[f64],
        ev: &Evaluation,
        targets: &[FingerTarget],
        out: &mut [FingerOutput],
    ) -> Result<(), FactorError> {
        let vals = ev.jacobian().values();
        for (k, fr) in self.fingers.iter().enumerate() {
            let f = frame(q, fr.offset).ok_or(FactorError)?;
            let mut w_c = [0.0; 7];
            for (n, r) in fr.rows.clone().enumerate() {
                if fr.proxy {
                    break;
                }
                let Slot::F(fi) = self.gram.slot[r] else {
                    continue;
                };
                let lam = s.ell[r] * self.solve.lambda_f[fi];
                for (c, w) in w_c.iter_mut().enumerate() {
                    *w += vals[fr.pos[n] + c] * lam;
                }
            }
            let p = f.point(&fr.point_at(q));
            let (force, torque) = on_finger(&f, &p, &w_c);
            let t = &targets[k];
            let (err, rate) = self.coupling[k];
            self.prev_error[k] = err;
            let coupling = err * settings.coupling_stiffness_n_per_m
                + rate * settings.coupling_damping_n_s_per_m;
            let coupling_torque = if fr.rigid {
                rigid_coupling_torque(
                    q,
                    fr.offset,
                    t,
                    settings.coupling_angular_stiffness_nm_per_rad,
                )
            } else {
                Vector3::zeros()
            };
            out[k] = FingerOutput {
                force_n: force + coupling,
                torque_nm: torque + coupling_torque,
                constraint_force_n: force,
                constraint_torque_nm: torque,
                coupling_force_n: coupling,
                coupling_torque_nm: coupling_torque,
                attachment_m: p,
                target_m: t.position_m,
                tracking_error_m: err.norm(),
            };
        }
        Ok(())
    }
}

/// Per joint row of `gram`: its witness constraint's index for a contact
/// pair's rows (normal and friction: each switched on and off as a whole
/// more often than not), `u32::MAX` for every other row; empty without
/// contact pairs. The factor keeps a pair's rows in supernodes of their own
/// (`Cholesky::analyze_grouped`), which it skips while they are off.
fn contact_groups(model: &Model, gram: &super::gram::Gram) -> Vec<u32> {
    let pairs = &model.contact().pairs;
    if pairs.is_empty() {
        return Vec::new();
    }
    let mut key = vec![u32::MAX; model.constraints().len()];
    for p in pairs {
        for c in std::iter::once(p.normal).chain(p.friction) {
            key[c.index()] = c.index() as u32;
        }
    }
    let rows = model.rows();
    gram.j_rows
        .iter()
        .map(|&row| key[rows[row].constraint.index()])
        .collect()
}

fn frame(q: &[f64], o: usize) -> Option<BodyFrame> {
    BodyFrame::new(
        Vector3::new(q[o], q[o + 1], q[o + 2]),
        [q[o + 3], q[o + 4], q[o + 5], q[o + 6]],
    )
}

/// The virtual coupling's torque on a rigid finger whose body's pose starts
/// at column `o` of q: the rotation from the target's orientation to the
/// body's, as a rotation vector, times the angular stiffness (shared with
/// the joint tick's `reduced::finger6`).
pub(crate) fn rigid_coupling_torque(
    q: &[f64],
    o: usize,
    target: &FingerTarget,
    stiffness_nm_per_rad: f64,
) -> Vector3<f64> {
    let body =
        UnitQuaternion::new_normalize(Quaternion::new(q[o + 3], q[o + 4], q[o + 5], q[o + 6]));
    (body * target.orientation.inverse()).scaled_axis() * stiffness_nm_per_rad
}
