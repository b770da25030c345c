//! The matvec-only tick's factor (`--force-solver matvec`): the slow loop
//! refactors the Eq. 7 matrix at the newest snapshot's configuration and
//! hands the factor to the fast loop through a program channel of its own
//! (`rt::exchange`, the same credit-bounded queues as the programs), which
//! adopts it at its next handover stage.
//!
//! ```text
//!  slow step: collect returned boxes (reused) ─► FactorRefresher::refresh(snapshot q)
//!             ─► try_send(Box<RefreshedFactor>)
//!  fast tick (handover stage): try_swap ─► Program::adopt_factor (swap buffers, no allocation)
//! ```
//!
//! A re-projection hands over a new program, whose factor is its own (built
//! on the slow thread); the refresher follows it ([`RefreshSender::follow`])
//! and a factor refreshed for the old one is refused by id.

use haptloop_rt::exchange::{ProgramReceiver, ProgramSender, program_channel};
use haptloop_solver::{FactorRefresher, Program, RefreshedFactor};

/// Factors in flight at most: one being adopted, one on its way.
const IN_FLIGHT: usize = 2;

/// The slow loop's end.
pub struct RefreshSender {
    tx: ProgramSender<RefreshedFactor>,
    refresher: FactorRefresher,
    /// Buffers back from the fast loop (or new), reused. Boxed: the
    /// channel moves boxes, and a box kept is a box not allocated again.
    #[allow(clippy::vec_box)]
    spare: Vec<Box<RefreshedFactor>>,
    /// Factors sent.
    pub sent: u64,
}

/// The fast loop's end.
pub struct RefreshReceiver {
    rx: ProgramReceiver<RefreshedFactor>,
    current: Box<RefreshedFactor>,
}

/// The two ends for `program`, or `None` unless it runs the matvec-only
/// tick. Allocates (slow thread, before the loops start).
pub fn channel(program: &Program) -> Option<(RefreshSender, RefreshReceiver)> {
    let refresher = program.factor_refresher()?;
    let (tx, rx) = program_channel(IN_FLIGHT);
    let current = Box::new(refresher.buffer());
    Some((
        RefreshSender {
            tx,
            refresher,
            spare: Vec::new(),
            sent: 0,
        },
        RefreshReceiver { rx, current },
    ))
}

impl RefreshSender {
    /// One slow step: takes back what the fast loop returned, and refreshes
    /// the factor at `q` (the newest snapshot's) unless the queue is full.
    /// Allocates only a buffer's first use.
    pub fn step(&mut self, q: &[f64]) {
        while let Some(b) = self.tx.collect() {
            self.spare.push(b);
        }
        if self.tx.in_flight() >= IN_FLIGHT {
            return;
        }
        let mut b = self
            .spare
            .pop()
            .unwrap_or_else(|| Box::new(self.refresher.buffer()));
        if !self.refresher.refresh(q, &mut b) {
            self.spare.push(b);
            return;
        }
        match self.tx.try_send(b) {
            Ok(()) => self.sent += 1,
            Err(haptloop_rt::exchange::SendError::Full(b)) => self.spare.push(b),
        }
    }

    /// The slow loop sent `program` to replace the running one: refresh its
    /// factor from now on. Allocates.
    pub fn follow(&mut self, program: &Program) {
        if let Some(r) = program.factor_refresher() {
            self.refresher = r;
        }
    }
}

impl RefreshReceiver {
    /// The fast tick's handover: takes the newest refreshed factor, if one
    /// came, and gives it to `program` (which ignores one made for another
    /// program). True if the program adopted one.
    ///
    /// # Real-time
    /// No allocation or deallocation: boxes and buffers swap.
    pub fn apply(&mut self, program: &mut Program) -> bool {
        self.rx.try_swap(&mut self.current, |_, _| {});
        program.adopt_factor(&mut self.current)
    }
}
