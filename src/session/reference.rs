//! The fast loop's force error, measured against a converged reference.
//!
//! ```text
//!  fast thread, every `every` ticks (ReferenceCapture):
//!    before the tick: Program::save_state ──► pending.before
//!    after it: the state after, the targets, the force the solver asked for
//!              (before the safety layer) ──► reference mailbox (newest wins)
//!  slow thread (ReferenceCheck), or right after the tick when deterministic:
//!    Program::converged_tick on its own program (projected rule, gain K_ref)
//!    ──► F* and q*; |F − F*| and |r − r*| into ReferenceStats
//! ```
//!
//! The reference replays the very tick the fast loop ran, from the state it
//! started from, to convergence (see `haptloop_solver::program` docs of
//! `converged_tick`): so the error measures the fast loop's update
//! (iterations, rule, gain), not the history it inherited. Its gain is
//! [`REFERENCE_GAIN`] (or the fast loop's, if larger): the hard-finger
//! limit within 1e-6 N on the Stewart platform, where a finger reaches its
//! target. Scenes with contact rows are reported as not measured.
//!
//! # Real-time
//! The capture allocates nothing: every buffer of the mailbox and of the
//! pending sample is sized when the session is built; a capture costs two
//! copies of the program's state (O(coordinates + rows + bodies)) on the
//! ticks it samples and nothing on the others.

use haptloop_rt::exchange::{MailboxReader, MailboxWriter, mailbox};
use haptloop_solver::program::ROUND_OFF_STEP_M;
use haptloop_solver::{
    FingerTarget, Program, ProgramError, SolverSettings, TickOutcome, TickState, UpdateRule,
};
use nalgebra::Vector3;
use std::sync::Arc;

/// The reference's finger gain K, or the fast loop's own if that is larger
/// (its default is 1000). The penalty's bias falls as 1/K: on the Stewart
/// platform, whose finger reaches its target, the converged force moves by
/// 1e-4 N from K = 1e3 to 1e9 and by 1e-6 N from 1e5 to 1e9. Larger K costs
/// convergence where a finger cannot reach its target: the Gauss–Newton
/// step then stalls at round-off (four-bar: 1e-11 m at 1e6, 1e-8 m at 1e8;
/// Peaucellier: most samples ran out of 50 iterations at 1e7).
pub const REFERENCE_GAIN: f64 = 1e5;

/// The converged reference stops at a step of this size, scaled metres.
pub const REFERENCE_TOLERANCE_M: f64 = 1e-12;

/// Iterations the reference may take per sample.
pub const REFERENCE_MAX_ITERATIONS: u32 = 50;

/// One sampled tick, as the fast loop ran it.
#[derive(Debug, Default)]
pub struct ReferenceSample {
    /// Samples captured so far, this one included (0: none yet).
    pub seq: u64,
    /// Grid slot of the tick.
    pub tick: u64,
    /// The tick's period, s.
    pub dt_s: f64,
    /// The program's state before the tick.
    pub before: TickState,
    /// And after it.
    pub after: TickState,
    /// The finger targets of the tick.
    pub targets: Vec<FingerTarget>,
    /// Per finger, the force the solver asked for (before the safety
    /// layer), N, world (scene) frame.
    pub force_n: Vec<Vector3<f64>>,
    /// False if the tick's solve failed (nothing to compare).
    pub solved: bool,
}

impl ReferenceSample {
    /// Buffers sized for `program`'s model. Allocates.
    fn sized(program: &Program) -> Self {
        let fingers = program.model().fingers().len();
        Self {
            before: program.tick_state(),
            after: program.tick_state(),
            targets: program.model().initial_targets(),
            force_n: vec![Vector3::zeros(); fingers],
            ..Self::default()
        }
    }
}

/// The fast loop's side: samples every `every`-th tick.
pub struct ReferenceCapture {
    every: u64,
    armed: bool,
    seq: u64,
    pending: ReferenceSample,
    out: MailboxWriter<ReferenceSample>,
}

impl ReferenceCapture {
    /// Saves the program's state if tick `index` is to be sampled.
    ///
    /// # Real-time
    /// No allocation; a copy of the state on sampled ticks.
    #[inline]
    pub fn before(&mut self, index: u64, program: &Program) {
        self.armed = (index + 1).is_multiple_of(self.every);
        if self.armed {
            program.save_state(&mut self.pending.before);
        }
    }

    /// Publishes the sample of this tick, if it is one; true if it did.
    ///
    /// # Real-time
    /// No allocation (the mailbox's slots were sized at build); a copy of
    /// the state and the targets.
    pub fn after(
        &mut self,
        index: u64,
        program: &Program,
        targets: &[FingerTarget],
        dt_s: f64,
        solved: bool,
    ) -> bool {
        if !std::mem::take(&mut self.armed) {
            return false;
        }
        self.seq += 1;
        let (seq, pending) = (self.seq, &mut self.pending);
        self.out.publish_with(|s| {
            s.seq = seq;
            s.tick = index;
            s.dt_s = dt_s;
            // The slot's buffers have the same sizes: a swap, not a copy.
            std::mem::swap(&mut s.before, &mut pending.before);
            program.save_state(&mut s.after);
            if s.targets.len() == targets.len() {
                s.targets.copy_from_slice(targets);
            }
            for (f, o) in s.force_n.iter_mut().zip(program.finger_outputs()) {
                *f = o.force_n;
            }
            s.solved = solved;
        });
        true
    }
}

/// What the comparisons found. Every figure covers the compared samples
/// only; the others are counted by why they were not compared.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ReferenceStats {
    /// Ticks sampled by the fast loop.
    pub captured: u64,
    /// Samples compared with a converged reference.
    pub compared: u64,
    /// Samples the slow loop never saw (a newer one replaced it first).
    pub overwritten: u64,
    /// Samples of ticks whose solve failed (zero force: nothing to compare;
    /// the failures are counted with the session's failed ticks).
    pub fast_failed: u64,
    /// Samples the reference could not replay (its own solve failed).
    pub reference_failed: u64,
    /// Samples whose reference ran out of iterations above round-off.
    pub not_converged: u64,
    /// Compared samples whose reference stopped at round-off above
    /// [`REFERENCE_TOLERANCE_M`] (included in the figures).
    pub round_off: u64,
    /// Largest |F − F*| over fingers and samples, N.
    pub force_error_max_n: f64,
    /// Σ |F − F*|², N².
    pub force_error_sumsq: f64,
    /// Largest |F*|, N.
    pub force_max_n: f64,
    /// Σ |F*|², N².
    pub force_sumsq: f64,
    /// Finger samples in the sums.
    pub force_n: u64,
    /// Largest distance of a body origin from the reference's, m.
    pub q_error_max_m: f64,
    /// Σ (largest distance per sample)², m².
    pub q_error_sumsq: f64,
    /// Most iterations a reference took.
    pub iterations_max: u32,
    /// Largest last step of a compared reference, m.
    pub last_step_max_m: f64,
}

impl ReferenceStats {
    /// RMS force error, N (NaN without samples).
    pub fn force_error_rms_n(&self) -> f64 {
        rms(self.force_error_sumsq, self.force_n)
    }
    /// RMS reference force, N.
    pub fn force_rms_n(&self) -> f64 {
        rms(self.force_sumsq, self.force_n)
    }
    /// RMS configuration error, m.
    pub fn q_error_rms_m(&self) -> f64 {
        rms(self.q_error_sumsq, self.compared)
    }
}

fn rms(sumsq: f64, n: u64) -> f64 {
    if n == 0 {
        f64::NAN
    } else {
        (sumsq / n as f64).sqrt()
    }
}

/// The slow loop's side: replays samples to convergence and compares.
pub struct ReferenceCheck {
    samples: MailboxReader<ReferenceSample>,
    program: Program,
    last_seq: u64,
    stats: ReferenceStats,
}

/// Why a scene's force error is not measured, if it is not.
pub fn unsupported(has_contact: bool) -> Option<&'static str> {
    has_contact.then_some(
        "the scene has contact rows, whose witness tables change with the slow loop's \
         active set; the converged replay covers joints, limits and fingers",
    )
}

/// The capture and check pair for a session whose fast program is
/// `program`, sampling every `every_ticks` ticks. Allocates (builds the
/// reference program).
pub fn pair(
    program: &Program,
    every_ticks: u64,
) -> Result<(ReferenceCapture, ReferenceCheck), ProgramError> {
    let fast = program.settings();
    let settings = SolverSettings {
        update: UpdateRule::Projected,
        gain: REFERENCE_GAIN.max(fast.gain),
        force_solver: haptloop_solver::ForceSolver::Cholesky,
        // The replay is the augmented program's; the fast program's saved
        // states carry its joint tick's motion history (`save_state`).
        coordinates: haptloop_solver::Coordinates::Augmented,
        ..*fast
    };
    let reference = Program::with_objectives(
        Arc::clone(program.model_arc()),
        Arc::clone(program.objectives()),
        settings,
    )?;
    let (out, samples) = mailbox(|| ReferenceSample::sized(program));
    Ok((
        ReferenceCapture {
            every: every_ticks.max(1),
            armed: false,
            seq: 0,
            pending: ReferenceSample::sized(program),
            out,
        },
        ReferenceCheck {
            samples,
            program: reference,
            last_seq: 0,
            stats: ReferenceStats::default(),
        },
    ))
}

impl ReferenceCheck {
    /// Compares the newest sample, if it is new. Slow thread: allocates
    /// nothing per sample but runs up to [`REFERENCE_MAX_ITERATIONS`]
    /// factorisations.
    pub fn check(&mut self) {
        if !self.samples.refresh() {
            return;
        }
        let s = self.samples.latest();
        if s.seq <= self.last_seq {
            return;
        }
        let st = &mut self.stats;
        st.overwritten += s.seq - self.last_seq - 1;
        st.captured = s.seq;
        self.last_seq = s.seq;
        if !s.solved {
            st.fast_failed += 1;
            return;
        }
        let r = match self.program.converged_tick(
            &s.before,
            &s.after,
            &s.targets,
            s.dt_s,
            REFERENCE_TOLERANCE_M,
            REFERENCE_MAX_ITERATIONS,
        ) {
            Ok(r) if r.status == TickOutcome::Ok => r,
            _ => {
                st.reference_failed += 1;
                return;
            }
        };
        let at_round_off = !r.converged && r.last_step_m <= ROUND_OFF_STEP_M;
        if !r.converged && !at_round_off {
            st.not_converged += 1;
            return;
        }
        st.round_off += u64::from(at_round_off);
        st.compared += 1;
        st.iterations_max = st.iterations_max.max(r.iterations);
        st.last_step_max_m = st.last_step_max_m.max(r.last_step_m);
        for (f, o) in s.force_n.iter().zip(self.program.finger_outputs()) {
            let e = (f - o.force_n).norm();
            let mag = o.force_n.norm();
            st.force_error_max_n = st.force_error_max_n.max(e);
            st.force_error_sumsq += e * e;
            st.force_max_n = st.force_max_n.max(mag);
            st.force_sumsq += mag * mag;
            st.force_n += 1;
        }
        let (q, q_star) = (s.after.q(), self.program.q());
        let mut d_max: f64 = 0.0;
        for (_, o) in self.program.model().layout().moving_bodies() {
            let d = (0..3)
                .map(|k| (q[o + k] - q_star[o + k]).powi(2))
                .sum::<f64>()
                .sqrt();
            d_max = d_max.max(d);
        }
        st.q_error_max_m = st.q_error_max_m.max(d_max);
        st.q_error_sumsq += d_max * d_max;
    }

    /// What the comparisons found.
    pub fn stats(&self) -> ReferenceStats {
        self.stats
    }
}
