//! The release branch's second solve without a second factorisation
//! (`force::solve`'s `low_rank`): the released rows come out of the first
//! factor's solve by a rank-k correction, and the third solve (the first
//! active set again) finds the first factor still in place.
//!
//! Taken only where the first factor is all the release branch's later
//! stages read: the projected update (its third solve restores or
//! refactors), no joint torques (they re-solve with the last factor), no
//! Tikhonov term (it depends on the rows taking part, so the kept block
//! would not be the first A's). Not bit-identical to the masked
//! refactorisation (`spare`), which stays the fallback: the tests compare
//! the two within round-off.

use super::*;
use crate::force::solve::{BACK_OFF, LowRank, LowRankTally};

impl Feedback {
    /// Gives the spare the buffers of the low-rank release when this
    /// program's later stages only read the first factor (module docs).
    /// Allocates.
    pub(super) fn enable_low_rank(&mut self, settings: &SolverSettings) {
        let fits = settings.update == UpdateRule::Projected
            && settings.force_regularization == 0.0
            && self.torques.is_none();
        if let Some(sp) = &mut self.spare
            && fits
        {
            sp.low_rank = Some(LowRank::new(&self.gram));
        }
    }

    /// The released rows' solve by the low-rank correction from the first
    /// solve (factor and multipliers of the current A, row scales `then`
    /// of its assembly): true when it was taken (the first multipliers kept
    /// aside for [`restore_first`](Self::restore_first)), false when the
    /// caller must solve another way (nothing changed).
    pub(super) fn solve_released_low_rank(&mut self, sp: &mut spare::Spare) -> bool {
        let Some(lr) = &mut sp.low_rank else {
            return false;
        };
        // Backing off after a refusal (`BACK_OFF`).
        if lr.skip > 0 {
            lr.skip -= 1;
            lr.tally.skipped += 1;
            return false;
        }
        lr.tally.attempts += 1;
        lr.clear();
        for (j, &row) in self.gram.j_rows.iter().enumerate() {
            if self.scale[row] == 0.0 && sp.scale[row] != 0.0 && !lr.release(j) {
                lr.skip = BACK_OFF;
                lr.tally.refusals += 1;
                return false;
            }
        }
        match self
            .solve
            .solve_low_rank(&self.gram, &self.cy, &self.known, lr)
        {
            Ok(true) => {
                sp.low_rank_holds = true;
                true
            }
            Ok(false) => {
                lr.skip = BACK_OFF;
                lr.tally.refusals += 1;
                false
            }
            // A non-finite finger solve: the first multipliers back, and
            // the refactorisation decides (and reports the failure if it
            // fails too).
            Err(_) => {
                self.solve.restore_low_rank(lr);
                lr.skip = BACK_OFF;
                lr.tally.refusals += 1;
                false
            }
        }
    }

    /// Releases solved by the low-rank correction (no second factorisation).
    pub fn low_rank_releases(&self) -> u64 {
        self.spare
            .as_ref()
            .and_then(|sp| sp.low_rank.as_ref())
            .map_or(0, |lr| lr.done)
    }

    /// What the low-rank release did with the releases that reached it
    /// (all zero without it).
    pub fn low_rank_tally(&self) -> LowRankTally {
        self.spare
            .as_ref()
            .and_then(|sp| sp.low_rank.as_ref())
            .map_or(LowRankTally::default(), |lr| lr.tally)
    }

    /// Solves every release by the masked refactorisation (the comparison
    /// the tests make). Deallocates; not for the fast loop.
    pub fn drop_low_rank(&mut self) {
        if let Some(sp) = &mut self.spare {
            sp.low_rank = None;
        }
    }
}
