//! haptloop-rt integration tests: one binary, with the counting allocator
//! installed so any module can prove a path allocates nothing.

#[global_allocator]
static ALLOC: haptloop_rt::alloc::CountingAllocator = haptloop_rt::alloc::CountingAllocator;

mod alloc_free;
mod exchange_stress;
mod real_thread;
mod scheduler_mock;
mod support;
