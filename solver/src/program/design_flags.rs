//! Design variables switched on and off during a run: Nelson & Cohen §3,
//! "design parameters, and therefore Jacobian columns, can be removed or
//! turned off with flags without reformulating the system equations".
//!
//! A switched-off variable keeps its columns (the model and every pattern
//! stay as built) and is held at its current value: the projected step
//! freezes its columns like a pinned bound (`al::design`), the gradient
//! rule's step is undone on them after every iteration, the objectives'
//! pull skips them, a re-projection's shift leaves them (`shift_q`), a
//! hand-over carries the flags (`adopt_state`) and so does a saved tick
//! state (the converged reference replays with the same flags).
//! A recovery from a broken configuration (`set_q`) is the exception: it
//! restores the last good configuration whole, this variable included.
//!
//! # Real-time
//! No allocation: one flag per design column, sized by `Program::new`.

use super::{Program, ProgramError};

impl Program {
    /// Switches design variable `var` (index into the model's
    /// [`design_vars`](crate::Layout::design_vars)) on (free to move) or off
    /// (held where it is).
    ///
    /// # Real-time
    /// No allocation; O(the variable's width).
    pub fn set_design_active(&mut self, var: usize, on: bool) -> Result<(), ProgramError> {
        let layout = self.model.layout();
        let Some(d) = layout.design_vars().get(var) else {
            return Err(ProgramError::Length {
                expected: layout.design_vars().len(),
                got: var,
            });
        };
        let first = d.offset - layout.body_coords();
        for k in first..first + d.width {
            self.design_off[k] = !on;
            self.projected.set_design_off(k, !on);
        }
        Ok(())
    }

    /// Whether design variable `var` is switched on (every variable starts
    /// on; `false` for an unknown index).
    pub fn design_active(&self, var: usize) -> bool {
        let layout = self.model.layout();
        layout.design_vars().get(var).is_some_and(|d| {
            let first = d.offset - layout.body_coords();
            !self.design_off[first..first + d.width].iter().any(|&f| f)
        })
    }

    /// Per design column (after the body columns): switched off.
    pub(super) fn design_off_flags(&self) -> &[bool] {
        &self.design_off
    }

    /// Takes `flags` (one per design column) as this program's.
    pub(super) fn load_design_flags(&mut self, flags: &[bool]) {
        if flags.len() != self.design_off.len() {
            return;
        }
        for (k, &off) in flags.iter().enumerate() {
            self.design_off[k] = off;
            self.projected.set_design_off(k, off);
        }
    }

    /// Puts the switched-off design columns back where the tick started
    /// (after a gradient step, which moves every column).
    pub(super) fn hold_design_off(&mut self) {
        let nb = self.model.layout().body_coords();
        for (k, &off) in self.design_off.iter().enumerate() {
            if off {
                self.q[nb + k] = self.q_ref[nb + k];
            }
        }
    }
}
