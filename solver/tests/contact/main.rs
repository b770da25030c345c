//! Integration tests of the contact machinery (Choi & Cremer §3): witness
//! rows against finite differences, each witness kind on hand-made geometry,
//! degenerate geometry, the active set. One binary, a module per area.

#[global_allocator]
static ALLOC: haptloop_rt::alloc::CountingAllocator = haptloop_rt::alloc::CountingAllocator;

mod common;
// The solver tests' finite differences, shared.
mod backup_paths;
mod chord_refresh;
mod corners;
mod drags;
mod expansion;
#[allow(dead_code)]
#[path = "../solver/fd.rs"]
mod fd;
mod friction;
// The lockstep harness of the `al` tests, shared.
#[path = "../al/lockstep.rs"]
mod lockstep;
mod low_rank_back_off;
mod moved_evaluation;
mod moved_steps;
mod pinch;
mod pivoted_precheck;
mod recycle;
mod release_low_rank;
mod release_spare;
mod rest;
mod slots;
mod witness_fd;
mod witness_kinds;
