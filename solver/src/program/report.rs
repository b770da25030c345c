//! What a [`Program`](super::Program) reports: per-finger outputs (defined
//! with the force computation that fills them, `force::output`), per-tick and
//! assembly diagnostics, and construction errors. All tick-path types are
//! `Copy` and heap-free.

use crate::EvalError;
use crate::al::InvalidSetting;
pub use crate::force::FingerOutput;

/// How a tick (or an assembly) ended. Anything but `Ok` leaves q and the
/// multipliers as they were before the call and zeroes every finger output:
/// the caller should cut forces for this tick.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum TickOutcome {
    /// Iterated and computed forces.
    #[default]
    Ok,
    /// The iteration produced a NaN or infinity (divergence): state restored.
    NonFinite,
    /// The input could not be evaluated (wrong target count, non-finite
    /// target, corrupted q).
    Eval(EvalError),
    /// The Eq. 7 multiplier solve failed (singular after regularisation).
    ForceSolve,
    /// `dt` was zero: no velocities can be formed.
    ZeroDt,
    /// Every number stayed finite but one was absurd (beyond
    /// [`Program::divergence_limits`](super::Program::divergence_limits)):
    /// the tick's result was not applied. The session should cut force and
    /// re-project (Newton-KKT) from its last good configuration.
    Diverged(Divergence),
}

/// Which quantity of a tick was absurd ([`TickOutcome::Diverged`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Divergence {
    /// The iterations moved a coordinate farther than
    /// [`DivergenceLimits::step_m`].
    Step,
    /// A multiplier exceeded [`DivergenceLimits::multiplier`].
    Multiplier,
    /// A mechanism row's violation at the tick's end exceeded
    /// [`DivergenceLimits::violation_m`].
    Violation,
}

/// The sizes beyond which a tick's result is refused as diverged, fixed by
/// [`Program::new`](super::Program::new) from the model's length scale L
/// (its largest lever arm, or `SolverSettings::length_scale_m`), the finger
/// pull limit d (L when the limit is off), the iterations per tick n and the
/// gain K. Everything is in
/// the update's scaled units: coordinates and rows in metres, angle and
/// Euler-parameter entries times L.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DivergenceLimits {
    /// Largest change of any scaled coordinate over one tick's iterations,
    /// metres: 10 (L + n d). A tick moves a finger at most n d (one
    /// pull limit per step) and turns a body at most about its own lever L;
    /// ten times that in 1 ms is hundreds of m/s, which no hand produces.
    pub step_m: f64,
    /// Largest |λ_i| / ℓ_i after a tick's iterations (metres-equivalent
    /// multiplier): 10⁶ K (L + d), times the mean body mass m̄ with
    /// the projected rule (its multipliers are K m̄ times a distance). Joint
    /// multipliers balance the fingers' pull, at most K (d + L) per finger
    /// row times the mechanism's lever ratios; measured: 3e3 × that close
    /// to the Peaucellier linkage's dead point, 4e8 × in the divergence this
    /// guard exists for.
    pub multiplier: f64,
    /// Largest violation of a mechanism row (joints, norms, limits, masked
    /// rows included; angle and norm rows times L) at the end of a tick,
    /// metres: L, a joint apart by the mechanism's own lever arm. A session
    /// that needs a tighter definition of "broken" applies its own on top.
    pub violation_m: f64,
}

/// Diagnostics of one tick. Violations are of the mechanism's constraints
/// (joints, quaternion norms, inequalities) at the tick's final q; finger rows
/// are excluded (see `max_tracking_error_m`).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct TickReport {
    /// AL iterations run.
    pub iterations: u32,
    /// Largest violation of a length row, metres.
    pub max_violation_m: f64,
    /// Largest violation of an angle row, radians.
    pub max_violation_rad: f64,
    /// Largest |eᵀe − 1| (dimensionless).
    pub max_norm_violation: f64,
    /// RMS violation over length rows, metres.
    pub rms_violation_m: f64,
    /// Largest finger |attachment − target|, metres.
    pub max_tracking_error_m: f64,
    /// Deepest penetration of a contact witness row at the final q, metres
    /// (0 without contacts or when nothing penetrates).
    pub max_penetration_m: f64,
    /// Contact witness rows active in the force solve (pushing).
    pub active_contacts: u32,
    /// Refactorisations a step needed because it would have violated an
    /// inactive contact or limit (the fast loop's own activation).
    pub activations: u32,
    /// Friction pairs sticking after the force solve.
    pub sticking: u32,
    /// The contact speed limit (`SolverSettings::contact_step_m`) held a
    /// shaped body back this tick: a step was shortened, or the tick's
    /// steps stopped on its budget.
    pub speed_limited: bool,
    /// Energy of the moving bodies at the tick's start and the fingers' work
    /// up to then (inertial motion; not `valid` otherwise or on failure).
    pub energy: crate::dynamics::EnergySample,
    /// How it ended.
    pub status: TickOutcome,
}

/// Result of [`Program::assemble`](super::Program::assemble).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct AssemblyReport {
    /// Iterations run.
    pub iterations: u32,
    /// Scaled violation < tolerance and the last step < tolerance / 100.
    pub converged: bool,
    /// Largest violation of any mechanism row with angle and norm rows scaled
    /// to metres by the length scale L, at the final q.
    pub max_scaled_violation_m: f64,
    /// Largest violation of a length row, metres.
    pub max_violation_m: f64,
    /// Largest violation of an angle row, radians.
    pub max_violation_rad: f64,
    /// Largest scaled coordinate change of the last iteration, metres.
    pub last_step_m: f64,
    /// Largest finger |attachment − target|, metres.
    pub max_tracking_error_m: f64,
    /// `Ok`, or why it stopped early (q restored to the last finite iterate,
    /// multipliers to their values before the call).
    pub status: TickOutcome,
}

/// Why a [`Program`](super::Program) could not be built or changed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ProgramError {
    /// A setting is out of range.
    #[error(transparent)]
    Settings(#[from] InvalidSetting),
    /// The model's initial configuration could not be evaluated.
    #[error("evaluating the initial configuration: {0}")]
    Eval(#[from] EvalError),
    /// The settings would make the update diverge on this model.
    #[error(
        "unstable gains: h(1 + K σ_max) = {a:.3} (must be < 2) and h k₂ σ_max = {beta:.3} \
         (must be < 4 − 2a); lower `step` or `multiplier_gain`"
    )]
    Unstable {
        /// h (1 + K σ_max).
        a: f64,
        /// h k₂ σ_max.
        beta: f64,
    },
    /// The symbolic Cholesky analysis failed (index overflow, out of memory).
    #[error("symbolic factorisation of C_q M⁻¹ C_qᵀ failed: {0}")]
    Factorization(String),
    /// A vector given has the wrong length.
    #[error("{got} coordinates given; the model has {expected}")]
    Length {
        /// Coordinates of the model.
        expected: usize,
        /// Entries given.
        got: usize,
    },
    /// A coordinate given is NaN or infinite.
    #[error("coordinate {index} is not finite")]
    NonFinite {
        /// Its index.
        index: usize,
    },
    /// The settings do not cover a part of this model.
    #[error("{0}")]
    Unsupported(&'static str),
    /// `coordinates = "joint"` on a model or settings the joint tick does
    /// not cover (what, in the message).
    #[error(
        "`coordinates = \"joint\"`: the joint tick does not cover {0}; use \"augmented\" \
         or \"auto\""
    )]
    Coordinates(String),
}

/// Largest |v| of the given outputs' tracking errors.
pub(crate) fn max_tracking(outputs: &[FingerOutput]) -> f64 {
    outputs
        .iter()
        .map(|o| o.tracking_error_m)
        .fold(0.0, f64::max)
}
