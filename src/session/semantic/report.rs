//! What the semantic loop reports (`src/session/semantic/mod.rs`): its events
//! with their times and its figures; `src/report/semantic.rs` turns them
//! into `summary.json`'s `"semantic"` section and the printed lines.

/// What happened to a constraint (the kinds of `summary.json`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EventKind {
    /// A constraint was satisfied (Algorithm 1): the fast loop pulls the
    /// binding onto the offer.
    Snap,
    /// An offer object started moving and carried a bound object with it.
    GroupMove,
    /// A held object was pulled off its offer harder than `break_force`.
    Break,
    /// A broken pair separated and left the exception list.
    Release,
    /// An object at rest started moving on its own account (not carried by
    /// a moving parent; not a constraint: printed only).
    Move,
    /// The hand took hold of a body (not a constraint; printed only).
    Hold,
    /// The hand let go (printed only).
    LetGo,
    /// An object was added to the scene (`[[schedule]] add`), at the valid
    /// place nearest its declared pose; `offer_body` names what it was put
    /// on (empty: nothing).
    Add,
    /// An add found no valid place: the object stays out.
    AddFailed,
    /// An object was removed (`[[schedule]] remove`).
    Remove,
    /// The interaction mode switched (`offer_body`: the new mode; printed
    /// only).
    Mode,
}

impl EventKind {
    /// The name in reports.
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Snap => "snap",
            Self::GroupMove => "group_move",
            Self::Break => "break",
            Self::Release => "release",
            Self::Move => "move",
            Self::Hold => "hold",
            Self::LetGo => "let_go",
            Self::Add => "add",
            Self::AddFailed => "add_failed",
            Self::Remove => "remove",
            Self::Mode => "mode",
        }
    }

    /// True for the constraint events `summary.json` lists.
    pub fn is_constraint(self) -> bool {
        !matches!(self, Self::Move | Self::Hold | Self::LetGo | Self::Mode)
    }
}

/// One event, with its time (the snapshot's session time).
#[derive(Debug, Clone, PartialEq)]
pub struct Event {
    /// Session time, s.
    pub t_s: f64,
    /// What happened.
    pub kind: EventKind,
    /// The bound (held, moved) body.
    pub binding_body: String,
    /// The offering body (for holds: the finger; for a move: the finger
    /// holding the body, or empty).
    pub offer_body: String,
}

/// What the semantic loop saw and did.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SemanticReport {
    /// Every event, in time order.
    pub events: Vec<Event>,
    /// The grouping graph at the end: (offer body, binding body), sorted.
    pub graph: Vec<(String, String)>,
    /// Constraints satisfied when the scene loaded.
    pub loaded: usize,
    /// consistent(s) evaluations (after loading and after every operation).
    pub checks: u64,
    /// Those that found the mirrored scene inconsistent.
    pub inconsistent: u64,
    /// The first inconsistency found, in words.
    pub first_inconsistency: Option<String>,
    /// Snaps whose pull had not arrived (aligned) by the end.
    pub pending_at_end: usize,
    /// Longest time from a snap to its arrival, s (NaN: none arrived).
    pub arrival_max_s: f64,
    /// Programs sent for a semantic change.
    pub programs: u64,
    /// Changes whose program could not be built (the fast loop kept the
    /// old rows).
    pub program_failures: u64,
    /// Slow-loop cycles run, and their largest and total time, ns.
    pub cycles: u64,
    /// Largest cycle, ns.
    pub cycle_ns_max: u64,
    /// Total, ns.
    pub cycle_ns_sum: u64,
    /// Objects added, removed, and adds that found no valid place.
    pub adds: u64,
    /// See `adds`.
    pub removes: u64,
    /// See `adds`.
    pub add_failures: u64,
    /// Of the adds that found no valid place at their time, those added on
    /// a later try (the hand or another body moved out of the way), and the
    /// longest wait, s (NaN: none).
    pub adds_late: u64,
    /// See `adds_late`.
    pub add_wait_max_s: f64,
    /// Adds still waiting for a valid place at the end (never added).
    pub adds_waiting_at_end: usize,
    /// Objects in the scene at the end (declared ones minus removed and
    /// not-yet-added).
    pub present_at_end: usize,
    /// Satisfied constraints at the end.
    pub constraints_at_end: usize,
    /// The interaction mode at the end.
    pub mode_at_end: &'static str,
    /// Largest and total time to build a program for a change, ns.
    pub build_ns_max: u64,
    /// Total, ns.
    pub build_ns_sum: u64,
}
