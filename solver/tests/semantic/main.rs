//! Integration tests of the semantic layer (Gösele & Stuerzlinger): every
//! algorithm step on hand-made geometry, the paper's special cases, random
//! operation sequences that keep the scene consistent, the rows a satisfied
//! constraint becomes (finite differences), and the fast loop's snap ramp,
//! grouped carrying and allocation-free tick. One binary, a module per area.

#[global_allocator]
static ALLOC: haptloop_rt::alloc::CountingAllocator = haptloop_rt::alloc::CountingAllocator;

mod algorithms;
mod common;
// The solver tests' finite differences, shared.
mod fast;
#[allow(dead_code)]
#[path = "../solver/fd.rs"]
mod fd;
mod presence;
mod random_ops;
mod rows_fd;
mod special;
