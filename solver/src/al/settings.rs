//! [`SolverSettings`]: the speed/accuracy knobs of the fast loop, each with its
//! unit and the reason for its default.

use std::time::Duration;

/// Which step the fast loop takes each iteration.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum UpdateRule {
    /// Nelson & Cohen Eq. 1–3 as written: a first-order (gradient) step of
    /// the augmented Lagrangian, one C_qᵀ product per iteration. Converges
    /// linearly; slow modes (a finger dragging a whole linkage) lag.
    Gradient,
    /// A Gauss–Newton (chord) projection that reuses the factor of
    /// C_q M⁻¹ C_qᵀ the force solve computed at the end of the previous tick
    /// (see the `projected` module docs): fingers track within a tick, at
    /// the cost of one pair of sparse triangular solves per iteration.
    Projected,
}

/// How Eq. 7's joint block C_q M⁻¹ C_qᵀ is solved each tick.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ForceSolver {
    /// Sparse Cholesky (the crate's supernodal factor): AMD ordering and
    /// symbolic analysis once per program, a numeric refactorisation per
    /// tick. Exact; its factor also serves the projected update.
    Cholesky,
    /// Warm-started, Jacobi-preconditioned conjugate gradients, at most
    /// `max_iterations` per right-hand side. Gradient update only.
    ConjugateGradient {
        /// Cap per right-hand side (bounds the tick's time).
        max_iterations: u32,
    },
    /// The matvec-only tick (`haptloop run --force-solver matvec`): no
    /// numeric factorisation on the fast thread while the refreshed factor
    /// preconditions well (a solve that reaches the cap unconverged is
    /// redone with a factorisation of the tick's own A). Eq. 7's joint block is
    /// solved by conjugate gradients on the assembled C_q M⁻¹ C_qᵀ, all its
    /// right-hand sides in lockstep, warm-started from the previous tick's
    /// solutions and preconditioned by a Cholesky factor of the same matrix
    /// that the slow thread refreshes at a recent configuration
    /// ([`Program::factor_refresher`](crate::Program::factor_refresher));
    /// the projected update's steps are solved the same way (conjugate
    /// gradients preconditioned by that factor); the gradient update (Eq. 3)
    /// needs no factor. A tick costs products with C_q and A and solves
    /// with the factor, no factorisation; its force error against the
    /// converged reference is what `max_iterations` buys. Not for contact
    /// rows or design variables.
    Matvec {
        /// Cap on the conjugate-gradient iterations per force solve (all
        /// right-hand sides step together) and per projected step; each
        /// solve stops earlier at a relative residual of 1e-12. A solve
        /// stopped by the cap is counted
        /// ([`Program::matvec_unconverged`](crate::Program::matvec_unconverged)).
        max_iterations: u32,
    },
    /// The tree tick (`haptloop run --force-solver tree`): Eq. 7's joint
    /// block by conjugate gradients (all right-hand sides in lockstep,
    /// warm-started from the previous tick's solutions, to a relative
    /// residual of 1e-12) preconditioned by the exact Gram block of a
    /// spanning tree of the body graph plus each loop-closing joint's own
    /// block, factored from the tick's own A: that pattern has no fill, so
    /// a factorisation and an application cost O(nnz(C_q)), not the full
    /// factor's fill (`force::precond::tree`). The projected update's
    /// steps solve one column each with the same preconditioner (to 1e-6)
    /// and the force solve's A_JJ⁻¹ A_JF; the gradient update needs no
    /// solve. Not for contact rows or design variables.
    Tree {
        /// Cap on the conjugate-gradient iterations per solve; a solve
        /// stopped by it is counted
        /// ([`Program::matvec_unconverged`](crate::Program::matvec_unconverged))
        /// and its result used as it is.
        max_iterations: u32,
    },
    /// The multilevel tick (`haptloop run --force-solver multilevel`): the
    /// tree tick's conjugate gradients (force solve and projected steps)
    /// with an aggregation V-cycle as preconditioner instead of the
    /// spanning tree: block Gauss–Seidel per constraint, coarse levels from
    /// clusters of neighbouring joints whose coarse unknowns are each
    /// cluster's lowest-energy force patterns, Galerkin coarse operators
    /// from the tick's A, a dense coarsest factor
    /// (`force::precond::multilevel`). Not for contact rows or design
    /// variables.
    Multilevel {
        /// Cap on the conjugate-gradient iterations per solve; a solve
        /// stopped by it is counted
        /// ([`Program::matvec_unconverged`](crate::Program::matvec_unconverged))
        /// and its result used as it is.
        max_iterations: u32,
    },
}

impl ForceSolver {
    /// How the command line spells it: `cholesky`, `matvec` (the default
    /// cap), `matvec:N`, `cg:N`.
    pub fn label(&self) -> String {
        match *self {
            ForceSolver::Cholesky => "cholesky".into(),
            f if f == ForceSolver::MATVEC => "matvec".into(),
            ForceSolver::Matvec { max_iterations } => format!("matvec:{max_iterations}"),
            ForceSolver::ConjugateGradient { max_iterations } => format!("cg:{max_iterations}"),
            f if f == ForceSolver::TREE => "tree".into(),
            ForceSolver::Tree { max_iterations } => format!("tree:{max_iterations}"),
            f if f == ForceSolver::MULTILEVEL => "multilevel".into(),
            ForceSolver::Multilevel { max_iterations } => format!("multilevel:{max_iterations}"),
        }
    }

    /// The matvec-only tick with its default cap: 64 iterations, a safety
    /// bound (each solve stops at its tolerance, 11–26 iterations on the
    /// Bennett linkage and the lattice with a 5 ms old factor). The old
    /// default of 4 truncated the projected steps' solves: inexact
    /// Gauss–Newton steps let the violation grow until the tick's guard
    /// failed it (661 of 1000 ticks on Bennett; BENCHMARKS.md, issue 23).
    pub const MATVEC: ForceSolver = ForceSolver::Matvec { max_iterations: 64 };

    /// The tree tick with its default cap: 500 iterations a solve, a
    /// safety bound (each solve stops at its tolerance; BENCHMARKS.md,
    /// issue 23, the spanning-tree preconditioner).
    pub const TREE: ForceSolver = ForceSolver::Tree {
        max_iterations: 500,
    };

    /// The multilevel tick with its default cap: 500 iterations a solve, a
    /// safety bound (each solve stops at its tolerance).
    pub const MULTILEVEL: ForceSolver = ForceSolver::Multilevel {
        max_iterations: 500,
    };
}

/// The coordinates the fast loop's tick iterates in (scene key `[solver]
/// coordinates`, `haptloop run --coordinates`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Coordinates {
    /// Every body's seven coordinates, every joint a set of rows: the
    /// projected (or Eq. 1–3) update and the sparse Eq. 7 solve. Covers
    /// every model.
    #[default]
    Augmented,
    /// The joint tick (`reduced::JointTick`): the projected update on the
    /// spanning tree's joint coordinates with forward kinematics, only the
    /// loop-closing and finger rows evaluated, Eq. 7 in joint coordinates.
    /// Quasi-static mechanisms of revolute, universal, spherical,
    /// prismatic and fixed joints, point or rigid fingers, and limits on
    /// tree joints: `Program::new` fails, naming why, on any other model or
    /// setting.
    Joint,
    /// `Joint` where the joint tick accepts the model and settings, else
    /// `Augmented`; [`Program::coordinates`](crate::Program::coordinates)
    /// says which ran and why.
    Auto,
}

impl Coordinates {
    /// How scenes and the command line spell it.
    pub fn label(self) -> &'static str {
        match self {
            Coordinates::Augmented => "augmented",
            Coordinates::Joint => "joint",
            Coordinates::Auto => "auto",
        }
    }

    /// The inverse of [`label`](Self::label).
    pub fn parse(s: &str) -> Option<Self> {
        [
            Coordinates::Augmented,
            Coordinates::Joint,
            Coordinates::Auto,
        ]
        .into_iter()
        .find(|c| c.label() == s)
    }
}

/// Whether and how [`Program::new`](crate::Program::new) looks for redundant
/// (linearly dependent) equality rows, which it then leaves out of the
/// projected step and the Eq. 7 force solve (see the `redundancy` module of
/// [`force`](crate::force)).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RedundancyCheck {
    /// A cheap test first: inverse iteration with the sparse factor of the
    /// scaled C_q M⁻¹ C_qᵀ at q0 estimates its smallest eigenvalue; only if
    /// that is below 1e-8 × the largest diagonal entry does the dense ordered
    /// QR run. Inequality rows are always tested against the kept equality
    /// rows (one sparse solve each).
    Auto,
    /// Always the dense ordered QR (to measure it, or for a scene whose
    /// Gram matrix is ill-conditioned without being singular).
    Dense,
    /// No detection: every row takes part, as before the check existed. A
    /// scene with structurally redundant rows (a planar loop of spatial
    /// revolutes) then factors a singular matrix and can diverge; kept for
    /// comparisons.
    Off,
}

/// Everything a [`Program`](crate::Program) needs to know besides the model.
///
/// Gains are dimensionless because the update runs in *scaled* coordinates in
/// which every row and every column is measured in metres (see the
/// [`al`](crate::al) module docs for the rule). `Default` gives settings that
/// converge on all three built-in mechanisms; the trade-off table in
/// BENCHMARKS.md shows what the knobs buy.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SolverSettings {
    /// Gradient (Eq. 3) or projected update. Default `Projected`: on the
    /// trade-off circle it lags the converged solution by nanometres where
    /// Eq. 3 lags by 0.2–3 mm at 1–16 iterations per tick, for 1.3× the
    /// tick's time (BENCHMARKS.md).
    pub update: UpdateRule,
    /// Update steps per tick. Default 4: with the projected rule each step
    /// gains about a decade (4 steps: 4 nm of lag on the trade-off circle, 8:
    /// round-off); a step costs one value evaluation, C_q·v, C_qᵀ·v and a
    /// pair of sparse triangular solves (gradient: one fused pass).
    pub iterations: u32,
    /// The step size, dimensionless, in (0, 1.3]. Default 0.9.
    ///
    /// Gradient rule: h as a **fraction of the largest stable step**, the
    /// update uses h = step / (1 + K σ_max), where σ_max is the largest
    /// eigenvalue of the scaled Gram matrix D C_q W⁻¹ C_qᵀ D, measured by
    /// [`Program::new`](crate::Program::new) at the model's configuration.
    /// Projected rule: the fraction of the Gauss–Newton step taken (1 = full).
    /// A damped step converges by about a decade per step, a full one
    /// roughly quadratically: the built-in mechanism scenes take full steps,
    /// 2–3 a tick (BENCHMARKS.md, issue 10), but near a singular pose (the
    /// Peaucellier linkage's dead point) full steps quadrupled the transient.
    ///
    /// Why relative: σ_max is 11.5, 14.3 and 27.1 on the four-bar, Stewart
    /// platform and sphere toy (the absolute h used is
    /// [`Program::step_h`](crate::Program::step_h)), so no absolute h is both
    /// stable on the stiffest and fast on the softest.
    pub step: f64,
    /// K, the base penalty gain of Eq. 3, dimensionless (penalty per square
    /// metre of scaled violation relative to the least-astonishment objective
    /// per square metre of scaled motion). Row i uses K·ℓ_i² (the K rule in the
    /// module docs). Default 1000: a finger the mechanism can follow then lags
    /// at most 1/(1 + K) = 0.1 % of one tick's motion at the fixed point of a
    /// tick, and K ≫ 1 makes h ≈ step/(K σ_max), so the objective acts as a
    /// mild proximal term and never fights the constraints. The projected
    /// rule weighs fingers with K m̄ (m̄ the mean body mass) against its
    /// mass-metric objective, so K keeps its meaning: the lag is about
    /// m_eff / (K m̄) of a tick's motion (0.2 % on the four-bar, tested).
    pub gain: f64,
    /// k₂ of Eq. 2, same scaling and unit as K (row i integrates k₂·ℓ_i²·C_i).
    /// Default 1000 (= K, the method-of-multipliers choice); stability needs
    /// h k₂ σ_max < 4 − 2 h K σ_max, checked by `Program::new`.
    pub multiplier_gain: f64,
    /// Pull limit d of a finger, metres: a finger's point error (or, rigid,
    /// its orientation error times L) counts at most d, along its direction.
    /// A trust region for far targets: with the projected rule an unlimited
    /// pull toward a target 3 cm off a 1-DOF linkage's reach diverged (the
    /// linearised step overshoots), and with the gradient rule it loads the
    /// joints with K·ℓ²·(the whole distance). Default 1 cm: on the trade-off
    /// circle, whose target is up to 1 cm off the reachable curve, it changes
    /// nothing, while 1 mm (clamping the reachable part of the error too)
    /// multiplied the lag by 100. `f64::INFINITY` switches it off.
    pub finger_pull_limit_m: f64,
    /// Largest motion of any body per tick in a model with contact rows,
    /// metres (a projected step that would move a body's points farther is
    /// shortened to this, keeping its direction). The witness rows the fast
    /// loop runs on were built by the slow loop at most one cycle ago, for
    /// the features nearest then; a pair enters the active set below the
    /// contact distance plus twice what its bodies moved in the last cycle.
    /// Bounding the motion per tick bounds both: the session sets it to
    /// `contact_distance` over the slow cycle's ticks (5 mm over 5 ms: a
    /// contact speed limit of 1 m/s), which is what keeps a cube shoved into
    /// a corner from tumbling 40° between two witness updates and through
    /// the table. Infinite (the default): scenes without contact.
    pub contact_step_m: f64,
    /// Weight of finger rows relative to K (fingers are penalty rows with no
    /// multiplier, see the module docs). Dimensionless, > 0. Default 1: the
    /// finger pulls as hard as a joint holds.
    pub finger_weight: f64,
    /// The length ℓ that converts angle and quaternion-norm rows and
    /// Euler-parameter columns to metres, in metres. `None` (default): the
    /// model's [`characteristic_length_m`](crate::Model::characteristic_length_m),
    /// its largest lever arm. `Some(1.0)` switches the scaling off (plain Eq. 3
    /// with one K for every row), which the tests show converges slower.
    pub length_scale_m: Option<f64>,
    /// Stiffness of the virtual coupling between the device point (target) and
    /// the finger's attachment point on the mechanism, N/m. Default 400 N/m:
    /// about half the 700–800 N/m a PHANToM renders stably at 1 kHz, and with
    /// K·T/2 = 0.2 N·s/m it leaves room for the default damping even with the
    /// light grip of the devices' stability table (b = 0.31 N·s/m).
    pub coupling_stiffness_n_per_m: f64,
    /// Damping of the virtual coupling on the relative velocity of attachment
    /// and target, N·s/m. Default 0.05 N·s/m: sampled virtual damping adds to
    /// the passivity requirement b > K T/2 + B (Colgate), so it stays small;
    /// it takes the edge off the wall the coupling renders in directions the
    /// mechanism cannot move.
    pub coupling_damping_n_s_per_m: f64,
    /// Torsional stiffness of the coupling for rigid grasps, N·m/rad, acting on
    /// the rotation from the target orientation to the body's. Default 0: a
    /// PHANToM-class device renders no torque.
    pub coupling_angular_stiffness_nm_per_rad: f64,
    /// Time constant of the first-order low-pass filter applied to the body
    /// velocities estimated from q (for noisy position sensors). Zero
    /// (default) switches it off; encoders need none (Nelson & Cohen §5.2).
    /// The filter delays velocities by about this much (plus the half tick of
    /// the backward difference): [`Program::motion_delay`](crate::Program::motion_delay).
    pub velocity_filter: Duration,
    /// Solver of Eq. 7's joint block. Default `Cholesky`: faster than
    /// warm-started CG on all three mechanisms, exact, and the projected
    /// update reuses its factor (BENCHMARKS.md compares them).
    pub force_solver: ForceSolver,
    /// Relative Tikhonov regularisation μ of the Eq. 7 multiplier solve:
    /// μ·(mean diagonal) is added to the joint block of the scaled
    /// C_q M⁻¹ C_qᵀ (the projected step shares it). Default 0: exactly
    /// redundant rows (a planar linkage built from spatial joints) are masked
    /// by `Program::new` ([`redundancy`](Self::redundancy)), and the
    /// factorisation's dynamic regularisation (a pivot below 1e-14 × the
    /// largest diagonal replaced by 1e-10 × it) only keeps the factor alive
    /// through a round-off pivot. A Tikhonov term does not make a singular
    /// block well-posed, it trades the blow-up for bias: unmasked, the
    /// Peaucellier linkage still came apart with μ = 1e-14 (6 m) and 1e-10
    /// (1 m), and μ = 1e-12 already put a spurious 1e-9 of the load into the
    /// four-bar's finger. Raise it only for nearly (not exactly) redundant
    /// scenes.
    pub force_regularization: f64,
    /// Inertial motion (scene key `[solver] dynamics`). Off (the solver's
    /// default; a session's default is `dynamics::inertial_by_default`):
    /// the least-astonishment objective of Nelson & Cohen anchors each tick
    /// at the previous configuration, so nothing moves unless a finger moves
    /// it (a mechanism held still stays put under gravity; gravity is felt
    /// through Eq. 7). On: every body carries its own velocity and the
    /// anchor is its inertial prediction, so the projection with the mass
    /// metric is a constrained Verlet (SHAKE) step: released objects fall,
    /// slide with Coulomb friction, bounce with their restitution and rest
    /// on what supports them ([`crate::dynamics`]). Needs the projected
    /// rule's mass metric to be physical.
    pub dynamics: bool,
    /// Detection of redundant rows at `Program::new` (see
    /// [`RedundancyCheck`]). Default `Auto`: the Peaucellier linkage's 9
    /// dependent rows (of 57) are found and masked, after which it recovers
    /// from off-manifold states that made every projected tick fail; on the
    /// full-rank built-in mechanisms the check costs one extra factorisation
    /// and eight sparse solves (BENCHMARKS.md).
    pub redundancy: RedundancyCheck,
    /// Takes each body's quaternion-norm row out of the Cholesky force
    /// factor's pattern where its coupling with the body's other rows is
    /// zero in exact arithmetic (`force::feedback::norms`): the lattice's
    /// factor 153 k → 120 k multiply-adds. Default off: the forces agree
    /// with the coupled factor's to round-off, but that round-off flips
    /// four knife-edge integration tests (a dead-point snap, cluttered's
    /// backups); see BENCHMARKS.md, "the quaternion-norm rows out of the
    /// force factor".
    pub norm_rows_out: bool,
    /// The tick's coordinates (see [`Coordinates`]). Default `Augmented`.
    pub coordinates: Coordinates,
}

impl Default for SolverSettings {
    fn default() -> Self {
        Self {
            update: UpdateRule::Projected,
            iterations: 4,
            step: 0.9,
            gain: 1000.0,
            multiplier_gain: 1000.0,
            finger_pull_limit_m: 1e-2,
            contact_step_m: f64::INFINITY,
            finger_weight: 1.0,
            length_scale_m: None,
            coupling_stiffness_n_per_m: 400.0,
            coupling_damping_n_s_per_m: 0.05,
            coupling_angular_stiffness_nm_per_rad: 0.0,
            velocity_filter: Duration::ZERO,
            force_solver: ForceSolver::Cholesky,
            force_regularization: 0.0,
            dynamics: false,
            redundancy: RedundancyCheck::Auto,
            norm_rows_out: false,
            coordinates: Coordinates::Augmented,
        }
    }
}

/// A setting out of its valid range.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
#[error("setting `{name}` = {value} is invalid: {why}")]
pub struct InvalidSetting {
    /// Field name.
    pub name: &'static str,
    /// Value given.
    pub value: f64,
    /// The valid range.
    pub why: &'static str,
}

impl SolverSettings {
    /// Checks every field's range (stability against the model is checked by
    /// `Program::new`, which knows σ_max).
    pub fn validate(&self) -> Result<(), InvalidSetting> {
        let bad = |name, value: f64, why| Err(InvalidSetting { name, value, why });
        let pos = |v: f64| v.is_finite() && v > 0.0;
        let nonneg = |v: f64| v.is_finite() && v >= 0.0;
        if self.iterations == 0 || self.iterations > 10_000 {
            return bad("iterations", self.iterations as f64, "1 ..= 10000");
        }
        if !(pos(self.step) && self.step <= 1.3) {
            return bad(
                "step",
                self.step,
                "0 < step <= 1.3 (fraction of the stable step)",
            );
        }
        if !pos(self.gain) {
            return bad("gain", self.gain, "finite and > 0");
        }
        if !nonneg(self.multiplier_gain) {
            return bad("multiplier_gain", self.multiplier_gain, "finite and >= 0");
        }
        if self.finger_pull_limit_m.is_nan() || self.finger_pull_limit_m <= 0.0 {
            return bad(
                "finger_pull_limit_m",
                self.finger_pull_limit_m,
                "> 0 (infinity: no limit)",
            );
        }
        if self.contact_step_m.is_nan() || self.contact_step_m <= 0.0 {
            return bad(
                "contact_step_m",
                self.contact_step_m,
                "> 0 (infinity: no limit)",
            );
        }
        if !pos(self.finger_weight) {
            return bad("finger_weight", self.finger_weight, "finite and > 0");
        }
        if let Some(l) = self.length_scale_m
            && !pos(l)
        {
            return bad("length_scale_m", l, "finite and > 0");
        }
        for (name, v) in [
            (
                "coupling_stiffness_n_per_m",
                self.coupling_stiffness_n_per_m,
            ),
            (
                "coupling_damping_n_s_per_m",
                self.coupling_damping_n_s_per_m,
            ),
            (
                "coupling_angular_stiffness_nm_per_rad",
                self.coupling_angular_stiffness_nm_per_rad,
            ),
        ] {
            if !nonneg(v) {
                return bad(name, v, "finite and >= 0");
            }
        }
        if let ForceSolver::ConjugateGradient { max_iterations } = self.force_solver {
            if max_iterations == 0 {
                return bad("force_solver.max_iterations", 0.0, ">= 1");
            }
            if self.update == UpdateRule::Projected {
                return bad(
                    "force_solver",
                    max_iterations as f64,
                    "the projected update needs the Cholesky factor",
                );
            }
        }
        if let ForceSolver::Matvec { max_iterations }
        | ForceSolver::Tree { max_iterations }
        | ForceSolver::Multilevel { max_iterations } = self.force_solver
            && (max_iterations == 0 || max_iterations > 1000)
        {
            return bad(
                "force_solver.max_iterations",
                max_iterations as f64,
                "1 ..= 1000",
            );
        }
        if !(nonneg(self.force_regularization) && self.force_regularization < 1.0) {
            return bad(
                "force_regularization",
                self.force_regularization,
                "0 <= μ < 1",
            );
        }
        Ok(())
    }
}
