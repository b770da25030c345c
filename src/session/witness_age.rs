//! How far the bodies moved since the snapshot the fast loop's witness rows
//! were computed at, and what motion those rows are still trusted for.
//!
//! ```text
//!  fast loop, every tick:  motion += the tick's motion (ticks' worth of the contact speed limit)
//!                          Snapshot { contact_motion: motion }  ─► slow loop
//!  slow loop, every cycle: witness table / contact program / "table still current",
//!                          stamped with its snapshot's contact_motion (the mark)
//!  fast loop, on taking it over: mark = that stamp (a backup's reset: mark = motion now)
//!  before every tick:      budget = WINDOW − (motion − mark)   ─► Program::set_contact_budget
//! ```
//!
//! The contact speed limit (`contact_distance` per 5 ms slow-loop cycle) is
//! sized for witness rows at most two cycles old: the cycle the hand-over
//! takes and the cycle they are used for. A slow loop that is late (a
//! contact program that takes 12–21 ms to build in real time, a descheduled
//! thread) left the fast loop moving bodies on at that limit past pairs its
//! rows did not hold, and the exact check then found them deep inside each
//! other (BENCHMARKS.md, "Contact: the slow loop late"). Counted from the
//! snapshot's age instead of per tick, the bodies slow to a stop once the
//! rows are as old as the limit allows and move again when fresh ones come.

/// Motion the witness rows are trusted for since their snapshot, in ticks'
/// worth of the contact speed limit: two slow-loop cycles (5 ms at 1 kHz
/// each), what the per-tick limit already allowed on time. On time the
/// budget never runs out: in a deterministic run a table is at most 6 ticks
/// old when it is replaced (BENCHMARKS.md).
pub const WINDOW_CYCLES: f64 = 2.0;

/// After a backup the window shrinks by this factor (down to
/// [`MIN_SCALE`]); it grows back by [`RECOVERY`] with every later table or
/// confirmation from the slow loop. A backup resets the world to the last
/// clean configuration but not the hand: the fingers then pull the bodies
/// back along the same path at the speed limit, the same penetration comes
/// back, and the backup repeats every cycle from the same stale
/// configuration (`stack` after 50-period stalls: 610 backups in a row, each
/// cycle 2.522 mm again; `cluttered` after a late slow loop: tens). Retried
/// slower, the slow loop's witnesses follow the motion and the last clean
/// configuration moves on.
pub const BACKUP_SLOWDOWN: f64 = 0.5;
/// The smallest window scale.
pub const MIN_SCALE: f64 = 1.0 / 16.0;
/// Growth of the window scale per later stamp, up to 1.
pub const RECOVERY: f64 = 1.25;

/// The fast loop's ledger (no allocation; see the module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WitnessAge {
    /// Motion so far, ticks' worth of the limit.
    motion: f64,
    /// `motion` at the snapshot of the witness rows in use.
    mark: f64,
    /// The window, ticks' worth (`WINDOW_CYCLES` slow cycles of ticks).
    window: f64,
    /// The share of the window (and of the per-tick limit) in force: 1, or
    /// less after backups.
    scale: f64,
    /// Ticks that found no motion left (the bodies held still).
    pub stopped_ticks: u64,
    /// The most motion since a snapshot the rows in use were ever asked to
    /// cover, ticks' worth (≤ the window).
    pub max_age: f64,
}

impl WitnessAge {
    /// A ledger for `ticks_per_cycle` fast ticks per slow-loop cycle.
    pub fn new(ticks_per_cycle: u64) -> Self {
        WitnessAge {
            motion: 0.0,
            mark: 0.0,
            window: WINDOW_CYCLES * ticks_per_cycle as f64,
            scale: 1.0,
            stopped_ticks: 0,
            max_age: 0.0,
        }
    }

    /// Motion so far (what a snapshot carries).
    pub fn motion(&self) -> f64 {
        self.motion
    }

    /// The motion left for the next tick, ticks' worth (≤ 0: none; at most
    /// the scale, 1 without backups).
    pub fn budget(&mut self) -> f64 {
        let age = self.motion - self.mark;
        self.max_age = self.max_age.max(age);
        let left = (self.window * self.scale - age).min(self.scale);
        self.stopped_ticks += u64::from(left <= 0.0);
        left
    }

    /// The share of the window in force (1 without backups).
    pub fn scale(&self) -> f64 {
        self.scale
    }

    /// A tick moved the bodies `ticks` ticks' worth.
    pub fn moved(&mut self, ticks: f64) {
        if ticks.is_finite() && ticks > 0.0 {
            self.motion += ticks;
        }
    }

    /// A program whose rows were computed at a snapshot that carried
    /// `motion` is in use now (its snapshot may be older than the rows it
    /// replaces: the budget may shrink).
    pub fn rows_from(&mut self, motion: f64) {
        if motion.is_finite() {
            self.mark = motion.min(self.motion);
            self.recover();
        }
    }

    /// A witness table (or the confirmation of the one in use) computed at
    /// a snapshot that carried `motion`: moves the mark forward only (a
    /// frame left in the mailbox from before a hand-over is no news).
    pub fn table_from(&mut self, motion: f64) {
        if motion.is_finite() && motion > self.mark {
            self.mark = motion.min(self.motion);
            self.recover();
        }
    }

    /// Rows computed where the bodies are now are in use: a backup's reset
    /// to the configuration they were computed at. The next motion is
    /// slower (see [`BACKUP_SLOWDOWN`]).
    pub fn rows_fresh(&mut self) {
        self.mark = self.motion;
        self.scale = (self.scale * BACKUP_SLOWDOWN).max(MIN_SCALE);
    }

    fn recover(&mut self) {
        self.scale = (self.scale * RECOVERY).min(1.0);
    }
}

#[cfg(test)]
mod tests {
    use super::WitnessAge;

    /// The budget counts from the rows' snapshot, not from the hand-over:
    /// rows taken over late come with the motion since their snapshot
    /// already spent.
    #[test]
    fn the_budget_counts_from_the_snapshot() {
        let mut a = WitnessAge::new(5);
        assert_eq!(a.budget(), 1.0, "one tick's worth at most");
        for _ in 0..4 {
            a.moved(1.0);
        }
        let stamp = a.motion(); // a snapshot after 4 ticks at the limit
        for _ in 0..8 {
            a.moved(1.0);
        }
        assert_eq!(a.budget(), -2.0, "12 ticks on rows from the start");
        a.rows_from(stamp);
        assert_eq!(a.budget(), 1.0, "8 of 10 spent since their snapshot");
        a.moved(1.0);
        assert_eq!(a.budget(), 1.0);
        a.moved(1.0);
        assert_eq!(a.budget(), 0.0);
        a.table_from(stamp);
        assert_eq!(a.budget(), 0.0, "an older table is no news");
        a.table_from(a.motion());
        assert_eq!(a.budget(), 1.0);
        assert_eq!(a.stopped_ticks, 3);
        assert_eq!(a.max_age, 12.0);
        a.rows_from(f64::NAN);
        assert_eq!(a.budget(), 1.0, "a non-finite stamp changes nothing");
    }

    /// Backups in a row slow the motion down (to a floor); later tables
    /// bring it back.
    #[test]
    fn backups_slow_the_motion_down_until_tables_come() {
        let mut a = WitnessAge::new(5);
        a.rows_fresh();
        assert_eq!(a.budget(), 0.5);
        a.moved(0.5);
        assert_eq!(a.budget(), 0.5);
        for _ in 0..10 {
            a.rows_fresh();
        }
        assert_eq!(a.scale(), super::MIN_SCALE);
        assert_eq!(a.budget(), super::MIN_SCALE);
        for _ in 0..20 {
            let m = a.motion();
            a.moved(0.01);
            a.table_from(m + 0.01);
        }
        assert_eq!(a.scale(), 1.0);
    }
}
