//! The auxiliary blocks' part of a tick (`model::auxiliary`): where the
//! update's anchor q₀ puts their columns; and the rolling rows' anchors.

use super::Program;
use crate::model::Rest;

impl Program {
    /// Sets q₀ on every auxiliary block whose rest is [`Rest::Zero`] to 0:
    /// with the block's metric K_f the update's objective on a flexible
    /// body's deformation is then its strain energy (Nelson & Cohen Eq. 4),
    /// not the distance from the last tick's shape. Call after q₀ is set
    /// from q and before the objectives shift it.
    ///
    /// # Real-time
    /// No allocation; O(auxiliary columns).
    pub(super) fn rest_aux(&mut self) {
        for b in self.model.layout().aux_blocks() {
            if b.rest == Rest::Zero {
                self.q_goal[b.offset..b.offset + b.width].fill(0.0);
            }
        }
    }

    /// Anchors the rolling rows (`crate::parametric::rolling`) at the
    /// current q, the start of a tick: each tick's steps then keep the
    /// contact point's displacement since this q free of slip.
    ///
    /// # Real-time
    /// No allocation; O(rolling constraints).
    pub(super) fn anchor_rolling(&mut self) {
        if !self.model.rolling.is_empty() {
            self.ev.anchor_rolling(&self.model, &self.q);
        }
    }
}
