//! Integration tests of flexible bodies (Nelson & Cohen §4, Eq. 4, Eq. 6's
//! K_f q_f): one binary, a module per area. The counting allocator is
//! installed so `alloc` can prove that flexible ticks allocate nothing.

#[global_allocator]
static ALLOC: haptloop_rt::alloc::CountingAllocator = haptloop_rt::alloc::CountingAllocator;

mod alloc;
mod common;
mod jacobian;
mod statics;
