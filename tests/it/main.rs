//! Workspace-level integration tests: one binary, a module per area. The
//! counting allocator is installed so a test can prove a path allocates
//! nothing (counting is per thread and only inside `haptloop_rt::alloc::count`).

#[global_allocator]
static ALLOC: haptloop_rt::alloc::CountingAllocator = haptloop_rt::alloc::CountingAllocator;

mod bench;
mod browser;
mod chain_family;
mod chair;
mod contact;
mod design;
mod design_flags;
mod docs;
mod exits;
mod export;
mod figures;
mod lattice;
mod limits;
mod load_bounds;
mod matvec;
mod messages;
mod mock_session;
mod papers;
mod physics;
mod place;
mod preflight;
mod reference;
mod replay;
mod resting;
mod said;
mod scene_format;
mod scenes;
mod seeds;
mod semantic;
mod semantic_schedule;
mod session;
mod slow_late;
mod solver_honesty;
mod stability;
mod stall;
mod sweep;
mod torque;
mod trust;
mod view;
