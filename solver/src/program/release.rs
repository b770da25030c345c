//! Contact rows that pull in a step of inertial motion: released for the
//! tick's next solve, and taken back when that solve changes a friction
//! state instead.
//!
//! A slow slip tries to stick first on each tick (`arm_slow_slips`): the
//! stop impulse of that attempt tips a pushed block onto its front edge,
//! so its back rows pull and are released; the attempt then breaks loose
//! and the tick is solved again slipping, where the back rows press as
//! before. Released, they were inactive at that solve's start, its first
//! step predicted them violated and activated them: one in-tick activation
//! (an assembly and numeric factorisation) on every tick of a steady
//! slide (`stack`: 2775 in 4 s). The release was judged under the other
//! friction state, so a friction change takes the rows back (forced active
//! as that activation would): the same steps without the refactorisation.
//! Should one of them pull again in the tick's last solve, it is released
//! and the tick solved once more, as it would have stayed open before.

use super::Program;
use crate::al::scaling::Role;

/// A row released this tick (`Program::release_pulling`).
const RELEASED: u8 = 1;
/// A row released and taken back this tick (`Program::readmit_released`).
const READMITTED: u8 = 2;

/// Per row: 0, [`RELEASED`] or [`READMITTED`] this tick.
#[derive(Debug, Clone)]
pub(super) struct Released {
    rows: Vec<u8>,
    /// Some row is set in `rows`.
    any: bool,
    /// The last `release_pulling` released a row taken back this tick.
    repulled: bool,
}

impl Released {
    /// Nothing released, for `rows` rows. Allocates.
    pub fn new(rows: usize) -> Self {
        Self {
            rows: vec![0; rows],
            any: false,
            repulled: false,
        }
    }

    /// Forgets the last tick's releases.
    ///
    /// # Real-time
    /// No allocation; O(rows) only after a tick that released.
    pub fn begin(&mut self) {
        if std::mem::take(&mut self.any) {
            self.rows.fill(0);
        }
    }

    /// True when the last `release_pulling` released a row taken back.
    pub fn repulled(&self) -> bool {
        self.repulled
    }
}

impl Program {
    /// Inequality rows (contacts, joint limits) that pulled in the step just
    /// taken (inertial motion): the step holds every active row as an
    /// equality, so a contact that should open (a rebound, a body lifted
    /// off) would be held shut for a tick and lose that tick's motion. They
    /// are released for the tick's next solve (their start multiplier and
    /// in-tick activation cleared) and remembered (`readmit_released`).
    /// Returns true if any was.
    ///
    /// # Real-time
    /// No allocation; O(rows).
    pub(super) fn release_pulling(&mut self) -> bool {
        let y = self.projected.multipliers();
        let tol = 1e-9 * y.iter().fold(0.0_f64, |a, v| a.max(v.abs()));
        let mut any = false;
        self.released.repulled = false;
        for (i, role) in self.scaling.role.iter().enumerate() {
            let active = self.feedback.row_scale()[i] != 0.0;
            if matches!(role, Role::Contact | Role::Inequality) && active && y[i] > tol {
                self.saved_lambda[i] = 0.0;
                self.feedback.forced[i] = false;
                let r = &mut self.released;
                r.repulled |= r.rows[i] == READMITTED;
                r.rows[i] = RELEASED;
                r.any = true;
                any = true;
            }
        }
        any
    }

    /// Takes the rows released this tick back (forced active) for a solve
    /// that changes a friction state: their release was judged on a step
    /// under the other state. Returns true if any was.
    ///
    /// # Real-time
    /// No allocation; O(rows) when some row was released.
    pub(super) fn readmit_released(&mut self) -> bool {
        if !self.released.any {
            return false;
        }
        let mut any = false;
        let rows = self.released.rows.iter_mut();
        for (f, r) in self.feedback.forced.iter_mut().zip(rows) {
            if *r != 0 {
                *r = READMITTED;
                *f = true;
                any = true;
            }
        }
        any
    }
}
