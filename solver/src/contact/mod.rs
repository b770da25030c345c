//! Contact on the slow loop (Choi & Cremer §3.2): from the fast loop's
//! configuration to what the fast loop should run next.
//!
//! | file | what it owns |
//! |---|---|
//! | `manager.rs` | [`ContactManager`]: one cycle per snapshot — poses, the active set, a new program when the set of pairs changes, a witness table when only features change, the backup on penetration |
//! | `bodies.rs` | which bodies take part (shaped ones) and which pairs never collide (jointed ones) |
//!
//! The fast loop never waits for any of this and never runs a symbolic
//! analysis: a structure change arrives as a whole [`Program`](crate::Program)
//! built here (on the slow thread), a feature change as a witness table the
//! running program copies in ([`Program::apply_witnesses`](crate::Program::apply_witnesses)).
//! The exchange between the threads (mailboxes, queues) is the caller's.

mod bodies;
mod manager;

pub use bodies::{contact_bodies, jointed_pairs};
pub use manager::{BuildCounts, ContactError, ContactManager, ContactUpdate, PROGRAM_CACHE};
