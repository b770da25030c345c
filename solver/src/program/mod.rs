//! [`Program`]: everything one fast tick needs, built once on the slow thread,
//! handed to the fast thread, ticked with zero allocation.
//!
//! ```text
//!  Arc<Model> + SolverSettings ──► Program::new (allocates: Evaluation, gains, Gram pattern,
//!                                  │             symbolic Cholesky, scratch; finds and masks
//!                                  │             redundant rows; σ_max; divergence limits)
//!                                  ├─ assemble(targets, cap, tol)   before the clock starts
//!                                  ├─ tick(targets, dt) ──► TickReport + finger_outputs()
//!                                  │     iterations × [projected step with last tick's factor,
//!                                  │                   stopped if the chord iteration diverges
//!                                  │                   | or Eq. 1–3 gradient step]
//!                                  │     guard: step and multipliers within limits
//!                                  │     evaluate C, C_q at final q → violations (guard)
//!                                  │     q history → b → factor C_q M⁻¹ C_qᵀ → λ_F → Eq. 8
//!                                  │     + coupling (the factor serves the next tick)
//!                                  └─ adopt_state(&old)              at a hand-over
//! ```
//!
//! **Redundant rows.** A model may have more equality rows than independent
//! ones (a planar loop of spatial revolutes repeats its out-of-plane rows:
//! 9 of the Peaucellier linkage's 57). `Program::new` finds them at q0
//! (`force::redundancy`, [`Program::redundancy`]) and masks them: still
//! evaluated and reported in every violation, but left out of both update
//! rules and the Eq. 7 solve, whose matrix then stays positive definite.
//!
//! **Divergence guard.** Everything a tick computes is finite or it fails
//! as [`TickOutcome::NonFinite`]; but finite can still be absurd (a singular
//! pose that turns round-off into a 300 m step). A tick whose iterations
//! move a coordinate, or leave a multiplier, beyond
//! [`Program::divergence_limits`], or whose final violation exceeds the
//! model's length scale, is refused as [`TickOutcome::Diverged`] like any
//! other failure: q and λ restored, outputs zero. Measured on the test
//! suite and the Peaucellier runs: steps up to 1.7 % of their limit,
//! multipliers 0.3 %; violations 0.01 % on the built-in mechanisms, 1.3 %
//! through the Peaucellier linkage's dead point, and 21 % (1 cm) with Eq. 3
//! on that linkage, which it cannot hold so close to its dead point
//! (`tests/al/redundant.rs`).
//!
//! # Real-time
//! `tick`, `adopt_state` and `set_q` never allocate, lock or make syscalls
//! (a counting-allocator test proves it on all three built-in mechanisms and
//! on a masked linkage) and are deterministic: sequential arithmetic, no
//! hashing, no clock. A tick costs `iterations` update steps (gradient: one
//! fused pass over the constraints; projected: a value-only evaluation,
//! C_q·v, C_qᵀ·v and one pair of sparse triangular solves), one evaluation
//! of C and C_q, one assembly of C_q M⁻¹ C_qᵀ, one numeric factorisation
//! with the crate's supernodal Cholesky (symbolic analysis fixed at
//! construction; a second, and with the projected rule a third, only when a
//! limit must be released) and one solve through it with the fingers' Schur
//! complement (in closed form when it is rank one, an m_f × m_f Cholesky
//! when it has full rank, else a Jacobi eigensolve; m_f = 3 per point
//! finger, 6 per rigid one), and the guards'
//! O(coordinates + rows) passes. All are bounded by the model's size;
//! nothing iterates to a tolerance. Measured (BENCHMARKS.md, issue 10,
//! whole session tick without the devices, the scenes' settings): four-bar
//! 4.3 µs, Stewart 21 µs, sphere toy 0.27 ms.

mod activation;
mod auxiliary;
mod contact;
mod converged;
mod design_flags;
mod handover;
mod inertial;
mod joint;
mod joint_cost;
mod joint_fallback;
mod joint_report;
mod objective;
#[cfg(test)]
mod probe;
mod refresh;
mod release;
mod report;
mod semantic;
mod setup;
mod stages;
mod state;
#[cfg(test)]
mod tests_norms;
#[cfg(test)]
mod tests_waste;
mod tick;

pub use converged::{ConvergedTick, ROUND_OFF_STEP_M, TickState};
pub use joint::CoordinatesChoice;
pub use joint_cost::CostEstimate;
pub use objective::OBJECTIVE_STEP_LIMIT_M;
pub use refresh::{FactorRefresher, RefreshedFactor};
pub use semantic::SNAP_RISE_S;
pub use stages::{SolverStage, StageMarks};
pub use tick::MAX_ACTIVATIONS;

pub use report::{
    AssemblyReport, Divergence, DivergenceLimits, FingerOutput, ProgramError, TickOutcome,
    TickReport,
};

use std::sync::Arc;
use std::time::Duration;

use crate::al::SolverSettings;
use crate::al::fused::Fused;
use crate::al::projected::Projected;
use crate::al::scaling::{Role, Scaling, check_stable};
use crate::force::Redundancy;
use crate::force::feedback::Feedback;
use crate::{Evaluation, FingerTarget, Model, Objectives, UpdateRule};

/// What [`Program::with_objectives`] analyses at q0 before it assembles the
/// program.
struct Analysis {
    ev: Evaluation,
    scaling: Scaling,
    feedback: Feedback,
    redundancy: Redundancy,
    sigma_max: f64,
    h: f64,
}

/// The fast loop's solver state for one model. `Send`: build it on the slow
/// thread, move it to the fast one. See the [module docs](self).
#[derive(Debug)]
pub struct Program {
    model: Arc<Model>,
    /// The design objectives and the built-in weights (`[[objective]]`).
    objectives: Arc<Objectives>,
    settings: SolverSettings,
    scaling: Scaling,
    sigma_max: f64,
    h: f64,
    redundancy: Redundancy,
    limits: DivergenceLimits,
    ev: Evaluation,
    q: Vec<f64>,
    /// q at the start of the tick (restored on failure; the guards measure
    /// steps from it).
    q_ref: Vec<f64>,
    /// q₀ of the least-astonishment objective: q at the start of the tick, or
    /// with `dynamics` its inertial prediction.
    q_goal: Vec<f64>,
    /// Refactorisations for in-tick activation this tick.
    activations: u32,
    /// The period of the last tick, s (the coupling of contact-finger
    /// proxies integrates over it; 1 ms before the first tick).
    last_dt_s: f64,
    /// The largest motion per tick (settings' `contact_step_m`).
    contact_step_m: f64,
    /// What is left of it in the current tick.
    step_budget_m: f64,
    /// The most motion, in ticks' worth of `contact_step_m`, the next tick
    /// may use ([`set_contact_budget`](Self::set_contact_budget)); infinite
    /// unless the caller bounds it.
    contact_budget: f64,
    /// The budget the current tick started with (its motion is this minus
    /// `step_budget_m`).
    tick_budget: f64,
    /// The contact speed limit held a body back in this tick.
    speed_limited: bool,
    /// Scratch: each finger's coupling error at the last force solve.
    prev_error_buf: Vec<nalgebra::Vector3<f64>>,
    /// Per witness-table slot: a friction stick row (its anchor is the fast
    /// loop's own while the contact persists).
    friction_slot: Vec<bool>,
    /// For each of `feedback.friction`, its index in the model's contact pairs.
    friction_pair: Vec<usize>,
    /// For each of `feedback.friction`, the indices in `feedback.masses` of
    /// its two bodies (`None`: fixed).
    friction_bodies: Vec<[Option<usize>; 2]>,
    /// The objectives' pull on q₀ (models with design objectives).
    objective: Option<objective::ObjectivePull>,
    /// Snap ramps and grouped carrying (models with semantic rows).
    semantic: Option<semantic::SemanticState>,
    /// Per design column: switched off (`design_flags`).
    design_off: Vec<bool>,
    /// Body velocities, friction states, restitution, energy (`dynamics`).
    inertial: inertial::Inertial,
    /// Rows released this tick (`release.rs`).
    released: release::Released,
    lambda: Vec<f64>,
    saved_lambda: Vec<f64>,
    g: Vec<f64>,
    fused: Fused,
    projected: Projected,
    /// The targets of the last successful tick (for refreshes between ticks).
    last_targets: Vec<FingerTarget>,
    /// Outputs of a refresh, which must not replace the tick's.
    spare_outputs: Vec<FingerOutput>,
    feedback: Feedback,
    outputs: Vec<FingerOutput>,
    report: TickReport,
    /// Refreshed force factors adopted (matvec-only tick).
    factor_adoptions: u64,
    /// The factor was prepared for a hand-over (`handover`): the next
    /// `adopt_state` keeps it.
    prepared: bool,
    /// Witness tables taken with the chord refresh (`contact`).
    chord_refreshes: u64,
    /// In-tick activations run a whole multiplier solve (`activation`).
    full_activation: bool,
    /// The tick in joint coordinates (`joint`), if the settings chose it.
    joint: Option<Box<joint::JointPath>>,
    /// Which coordinates the tick runs in, and why.
    choice: CoordinatesChoice,
    /// Joint ticks that failed and were run as augmented ticks
    /// (`joint_fallback`).
    joint_fallbacks: u64,
}

impl Program {
    /// Builds the program of `model` at its initial configuration q0 (at rest,
    /// multipliers zero). Finds and masks redundant rows at q0
    /// (`settings.redundancy`), measures σ_max at q0 to set h, rejects
    /// settings that would diverge and fixes the divergence limits.
    /// Allocates; call it off the real-time thread. No design objective
    /// and every built-in weight 1; see [`with_objectives`](Self::with_objectives).
    pub fn new(model: Arc<Model>, settings: SolverSettings) -> Result<Program, ProgramError> {
        Self::with_objectives(model, Arc::new(Objectives::default()), settings)
    }

    /// [`new`](Self::new) with the design objectives `objectives`
    /// ([`Objectives::compile`] against `model` or a model with its layout):
    /// their gradient shifts each tick's least-astonishment anchor, and their
    /// `finger` and `least_astonishment` weights scale the update.
    pub fn with_objectives(
        model: Arc<Model>,
        objectives: Arc<Objectives>,
        settings: SolverSettings,
    ) -> Result<Program, ProgramError> {
        settings.validate()?;
        setup::check_supported(&model, &settings)?;
        // The scene's `finger` and `least_astonishment` weights.
        let mut settings = settings;
        let weights = &objectives;
        settings.finger_weight *= weights.finger_weight / weights.least_astonishment;
        settings.validate()?;
        let ev = setup::initial_evaluation(&model, &settings)?;
        let mut scaling = Scaling::new(&model, &settings);
        let (feedback, redundancy) = setup::masked_feedback(&model, &ev, &settings, &mut scaling)?;
        let sigma_max = scaling.sigma_max(ev.jacobian(), settings.gain);
        let h = settings.step / (1.0 + settings.gain * sigma_max);
        check_stable(h, settings.gain, settings.multiplier_gain, sigma_max)
            .map_err(|(a, beta)| ProgramError::Unstable { a, beta })?;
        let analysis = Analysis {
            ev,
            scaling,
            feedback,
            redundancy,
            sigma_max,
            h,
        };
        let mut p = Self::at_rest(model, objectives, settings, analysis);
        p.reset_velocities();
        if p.refresh() != TickOutcome::Ok {
            return Err(ProgramError::Factorization(
                "the multiplier solve failed at the initial configuration".into(),
            ));
        }
        p.choose_coordinates()?;
        Ok(p)
    }

    /// The program at rest at q0 from what
    /// [`with_objectives`](Self::with_objectives) analysed: its update rules'
    /// state, divergence limits, friction and inertial bookkeeping, scratch.
    fn at_rest(
        model: Arc<Model>,
        objectives: Arc<Objectives>,
        settings: SolverSettings,
        a: Analysis,
    ) -> Program {
        let (n, m) = (model.n_coords(), model.n_rows());
        let Analysis {
            ev,
            scaling,
            feedback,
            redundancy,
            sigma_max,
            h,
        } = a;
        let limits = divergence_limits(&scaling, &settings, feedback.mean_mass_kg());
        let projected = setup::projected(
            &model,
            &scaling,
            &settings,
            &objectives,
            &feedback,
            &redundancy,
        );
        let objective = objective::ObjectivePull::new(&model, &objectives, feedback.mean_mass_kg());
        let friction = setup::Friction::new(&model, &feedback);
        let finger_rows = (0..m)
            .filter(|&i| matches!(scaling.role[i], Role::Finger | Role::Coupling))
            .collect();
        let inertial = inertial::Inertial::new(
            &model,
            &feedback.masses,
            finger_rows,
            friction.pair.len(),
            projected.reach(),
        );
        let fingers = model.fingers().len();
        Program {
            objectives,
            inertial,
            released: release::Released::new(m),
            friction_bodies: friction.bodies,
            q: model.q0().to_vec(),
            q_ref: model.q0().to_vec(),
            q_goal: model.q0().to_vec(),
            activations: 0,
            last_dt_s: 1e-3,
            step_budget_m: f64::INFINITY,
            contact_budget: f64::INFINITY,
            tick_budget: f64::INFINITY,
            speed_limited: false,
            contact_step_m: settings.contact_step_m,
            prev_error_buf: vec![nalgebra::Vector3::zeros(); fingers],
            objective,
            semantic: semantic::SemanticState::new(&model),
            friction_slot: friction.slot,
            friction_pair: friction.pair,
            design_off: vec![false; model.layout().design_coords()],
            lambda: vec![0.0; m],
            saved_lambda: vec![0.0; m],
            g: vec![0.0; n],
            fused: Fused::new(&model),
            projected,
            last_targets: model.initial_targets(),
            spare_outputs: vec![FingerOutput::default(); fingers],
            outputs: vec![FingerOutput::default(); fingers],
            report: TickReport::default(),
            factor_adoptions: 0,
            prepared: false,
            chord_refreshes: 0,
            full_activation: false,
            joint: None,
            choice: CoordinatesChoice {
                asked: settings.coordinates,
                joint: false,
                why: String::new(),
                estimate: None,
            },
            joint_fallbacks: 0,
            feedback,
            ev,
            h,
            sigma_max,
            redundancy,
            limits,
            scaling,
            settings,
            model,
        }
    }

    /// The model this program iterates.
    pub fn model(&self) -> &Model {
        &self.model
    }

    /// The shared model (to build a replacement program from it).
    pub fn model_arc(&self) -> &Arc<Model> {
        &self.model
    }

    /// The design objectives and built-in weights this program optimises
    /// (shared: a program rebuilt for a changed model passes them on).
    pub fn objectives(&self) -> &Arc<Objectives> {
        &self.objectives
    }

    /// The settings it was built with.
    pub fn settings(&self) -> &SolverSettings {
        &self.settings
    }

    /// The configuration after the last tick (layout order, see [`crate::Layout`]).
    pub fn q(&self) -> &[f64] {
        &self.q
    }

    /// The AL multipliers, one per row of C. Equality rows: λ of Eq. 2–3 (in
    /// the row's unit, scaled like C; not a physical force). Inequality rows:
    /// ν ≥ 0, the projected multiplier (Eq. 3 uses −ν). Finger rows: always 0
    /// (fingers are penalty rows).
    pub fn lambda(&self) -> &[f64] {
        &self.lambda
    }

    /// Per-finger outputs of the last tick, model finger order (zeros before
    /// the first tick and after any tick whose status is not `Ok`).
    pub fn finger_outputs(&self) -> &[FingerOutput] {
        &self.outputs
    }

    /// The torque (N·m; N on a prismatic joint) a motor on each of the
    /// model's [`torque_joints`](Model::torque_joints) would need to make
    /// the last tick's motion in place of the fingers (Nelson & Cohen §5.2;
    /// `force::torque`); NaN after a failed tick.
    pub fn joint_torques(&self) -> &[f64] {
        self.feedback.joint_torques_out()
    }

    /// The last tick's report.
    pub fn last_report(&self) -> &TickReport {
        &self.report
    }

    /// The absolute step h of Eq. 3 in use: `settings.step / (1 + K σ_max)`.
    pub fn step_h(&self) -> f64 {
        self.h
    }

    /// σ_max of the scaled Gram matrix D C_q W⁻¹ C_qᵀ D at q0 (dimensionless).
    pub fn sigma_max(&self) -> f64 {
        self.sigma_max
    }

    /// What the redundancy check at construction found: the masked rows
    /// (linearly dependent on the others at q0; evaluated and reported, but
    /// left out of every update and force solve) and how they were found.
    pub fn redundancy(&self) -> &Redundancy {
        &self.redundancy
    }

    /// Ticks on which the force solve released an active inequality that
    /// would have pulled and solved again (the release-and-re-solve branch),
    /// the joint tick's included.
    pub fn force_releases(&self) -> u64 {
        self.feedback.releases() + self.joint_releases()
    }

    /// Ticks of the release branch whose last solve (the kinematic active
    /// set for the projected steps) was the tick's first solve, kept aside,
    /// instead of a third assembly and factorisation (`force::feedback`'s
    /// `spare`).
    pub fn force_first_solves_kept(&self) -> u64 {
        self.feedback.first_solves_kept()
    }

    /// Releases whose second solve came from the first factor by a
    /// low-rank correction (`force::solve`'s `low_rank`) instead of a
    /// second factorisation.
    pub fn force_low_rank_releases(&self) -> u64 {
        self.feedback.low_rank_releases()
    }

    /// The low-rank release's attempts, refusals and releases skipped while
    /// backing off after a refusal (`force::solve`'s `BACK_OFF`).
    pub fn force_low_rank_tally(&self) -> crate::force::LowRankTally {
        self.feedback.low_rank_tally()
    }

    /// Solves every release by the masked refactorisation (the spare
    /// alone): the bit-for-bit reference of the spare's test, and the
    /// comparison of the low-rank correction's. Deallocates; not for the
    /// fast loop.
    pub fn drop_release_low_rank(&mut self) {
        self.feedback.drop_low_rank();
    }

    /// Solves every step of the release branch afresh (assembly and
    /// factorisation), as before the spare: the reference the exactness
    /// test compares with. Deallocates; not for the fast loop.
    pub fn drop_release_spare(&mut self) {
        self.feedback.drop_spare();
    }

    /// The sizes beyond which a tick refuses its result as diverged
    /// ([`TickOutcome::Diverged`]).
    pub fn divergence_limits(&self) -> &DivergenceLimits {
        &self.limits
    }

    /// The length scale L in use, metres.
    pub fn length_scale_m(&self) -> f64 {
        self.scaling.length_m
    }

    /// Conjugate-gradient iterations of the last force solve, summed over its
    /// right-hand sides (0 with the Cholesky).
    pub fn force_cg_iterations(&self) -> u32 {
        self.feedback.cg_iterations()
    }

    /// The tree tick (`ForceSolver::Tree`): its preconditioner's shape and
    /// its projected steps' iterations so far (`None` otherwise).
    pub fn tree_stats(&self) -> Option<crate::TreeStats> {
        self.feedback.tree_stats()
    }

    /// The multilevel tick (`ForceSolver::Multilevel`): its levels' sizes
    /// and its projected steps' iterations so far (`None` otherwise).
    pub fn multilevel_stats(&self) -> Option<crate::MultilevelStats> {
        self.feedback.multilevel_stats()
    }

    /// The matvec-only tick (`ForceSolver::Matvec`): conjugate-gradient
    /// solves (the force solve's and the projected steps') that stopped at
    /// the iteration cap above their tolerance, since the program was
    /// built; each was redone with a factorisation of the tick's own A
    /// (which then also preconditions the next solves). 0 for the other
    /// force solvers.
    pub fn matvec_unconverged(&self) -> u64 {
        self.feedback.matvec_unconverged()
    }

    /// Stored values of the Eq. 7 Cholesky factor (a size measure).
    pub fn force_factor_nnz(&self) -> usize {
        self.feedback.factor_nnz()
    }

    /// The force stage (comparisons in `force`'s tests).
    #[cfg(test)]
    pub(crate) fn feedback(&self) -> &Feedback {
        &self.feedback
    }

    /// How far the velocity estimates lag at tick period `dt`: half a tick for
    /// the backward difference plus the low-pass filter's low-frequency group
    /// delay τ/dt ticks. Accelerations lag half a tick more.
    pub fn motion_delay(&self, dt: Duration) -> Duration {
        let (dt_s, tau) = (
            dt.as_secs_f64(),
            self.settings.velocity_filter.as_secs_f64(),
        );
        Duration::from_secs_f64(0.5 * dt_s + tau)
    }
}

/// The limits documented on [`DivergenceLimits`].
/// The masked rows that are equalities (joints), with their ℓ: the ones a
/// moving design must keep closed (`al/design_closure.rs`). Masked
/// inequality rows (a contact the joints already hold) stay out.
fn masked_equalities(model: &Model, scaling: &Scaling, masked: &[usize]) -> Vec<(usize, f64)> {
    masked
        .iter()
        .filter(|&&i| model.rows()[i].sense == crate::Sense::Equality)
        .map(|&i| (i, scaling.ell[i]))
        .collect()
}

fn divergence_limits(
    s: &Scaling,
    settings: &SolverSettings,
    mean_mass_kg: f64,
) -> DivergenceLimits {
    let l = s.length_m;
    let pull = settings.finger_pull_limit_m;
    let d = if pull.is_finite() { pull } else { l };
    let mass = match settings.update {
        UpdateRule::Projected => mean_mass_kg,
        UpdateRule::Gradient => 1.0,
    };
    DivergenceLimits {
        step_m: 10.0 * (l + f64::from(settings.iterations) * d),
        multiplier: 1e6 * settings.gain * mass * (l + d),
        violation_m: l,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::al::RedundancyCheck;

    #[test]
    fn program_is_send() {
        fn is_send<T: Send>() {}
        is_send::<super::Program>();
    }

    /// The rows the ordered redundancy check masks are not in A's pattern:
    /// the joint block's order is the equality rows minus the masked ones
    /// (the Peaucellier linkage: 9 of 57), where with the check off every
    /// row is in it. (That the force stays exact is
    /// `redundant_linkage_static_force_matches_the_reference`, against an
    /// SVD null-space reference.)
    #[test]
    fn masked_rows_leave_the_force_factor() {
        let path =
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/peaucellier.toml");
        let model = Arc::new(crate::scene::load(&path).unwrap().compile().unwrap().model);
        let settings = SolverSettings::default();
        let p = Program::new(model.clone(), settings).unwrap();
        let masked = p.redundancy().rows.len();
        assert_eq!(masked, 9);
        let fingers: usize = model
            .fingers()
            .iter()
            .map(|f| model.constraints()[f.constraint.index()].rows.len())
            .sum();
        let (n_j, m_f, _) = p.feedback.gram_size();
        assert_eq!(m_f, fingers);
        assert_eq!(n_j, model.n_rows() - fingers - masked);
        let all = Program::new(
            model.clone(),
            SolverSettings {
                redundancy: RedundancyCheck::Off,
                ..settings
            },
        )
        .unwrap();
        assert_eq!(all.feedback.gram_size().0, model.n_rows() - fingers);
        assert!(p.force_factor_nnz() < all.force_factor_nnz());
    }
}
