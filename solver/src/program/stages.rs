//! The stages of one [`Program::tick`](super::Program::tick), for callers
//! that time them. The solver reads no clock: a caller that wants per-stage
//! times passes a [`StageMarks`] to [`Program::tick_marked`](super::Program::tick_marked)
//! and reads its own clock when a stage ends (the session does, with
//! `rt::clock`).

/// A stage of the solver's part of a tick, in the order they end.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SolverStage {
    /// The update iterations toward the finger targets (projected or
    /// Eq. 1–3 steps, in-tick activations, the step and multiplier guards).
    Update,
    /// C and C_q at the tick's final q, friction anchors, the violation
    /// statistics and their guard.
    Evaluation,
    /// The Eq. 7 multiplier solve, Eq. 8 wrenches and the virtual coupling
    /// (and, on a failed tick, restoring the state).
    Force,
}

impl SolverStage {
    /// Every stage, in order.
    pub const ALL: [SolverStage; 3] = [
        SolverStage::Update,
        SolverStage::Evaluation,
        SolverStage::Force,
    ];
}

/// Told when each [`SolverStage`] of a tick ends, always once per stage and
/// in order, also on a failed tick (a stage that did not run ends right
/// after the previous one).
///
/// # Real-time
/// Called on the fast thread inside the tick: implementations must not
/// allocate, lock or do I/O. `()` ignores every mark and costs nothing.
pub trait StageMarks {
    /// `stage` has just ended.
    fn end(&mut self, stage: SolverStage);
}

impl StageMarks for () {
    #[inline(always)]
    fn end(&mut self, _stage: SolverStage) {}
}

/// Forwards marks to `inner` in order, each stage exactly once.
pub(super) struct Ordered<'a, M: StageMarks> {
    inner: &'a mut M,
    next: usize,
}

impl<'a, M: StageMarks> Ordered<'a, M> {
    pub fn new(inner: &'a mut M) -> Self {
        Self { inner, next: 0 }
    }

    /// Ends `stage` and any earlier stage not yet ended.
    #[inline]
    pub fn end(&mut self, stage: SolverStage) {
        let upto = stage as usize;
        while self.next <= upto {
            self.inner.end(SolverStage::ALL[self.next]);
            self.next += 1;
        }
    }

    /// Ends every remaining stage.
    #[inline]
    pub fn finish(&mut self) {
        self.end(SolverStage::Force);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Log(Vec<SolverStage>);
    impl StageMarks for Log {
        fn end(&mut self, stage: SolverStage) {
            self.0.push(stage);
        }
    }

    #[test]
    fn every_stage_ends_once_and_in_order() {
        let mut log = Log(Vec::new());
        let mut o = Ordered::new(&mut log);
        o.end(SolverStage::Evaluation);
        o.end(SolverStage::Update);
        o.finish();
        o.finish();
        assert_eq!(log.0, SolverStage::ALL);
    }
}
