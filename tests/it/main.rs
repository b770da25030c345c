//! Workspace-level integration tests: one binary, a module per area. The
//! counting allocator is installed so a test can prove a path allocates
//! nothing (counting is per thread and only inside `haptloop_rt::alloc::count`).

#[global_allocator]
static ALLOC: haptloop_rt::alloc::CountingAllocator = haptloop_rt::alloc::CountingAllocator;

mod bench;
mod contact;
mod design;
mod docs;
mod exits;
mod export;
mod limits;
mod messages;
mod papers;
mod preflight;
mod reference;
mod replay;
mod scene_format;
mod scenes;
mod seeds;
mod semantic;
mod session;
mod stability;
mod sweep;
mod trust;
