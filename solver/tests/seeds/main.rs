//! Integration tests of the seeds' remaining kinds (issue 22): flexible
//! bodies (Nelson & Cohen §4, Eq. 4, Eq. 6's K_f q_f) and surface contact
//! and rolling (App. E, Eq. 16). One binary, a module per kind. The
//! counting allocator is installed so the `alloc` modules can prove that
//! their ticks allocate nothing.

#[global_allocator]
static ALLOC: haptloop_rt::alloc::CountingAllocator = haptloop_rt::alloc::CountingAllocator;

mod flexible {
    mod alloc;
    pub(crate) mod common;
    mod jacobian;
    mod statics;
}

mod errors;

mod surface {
    mod alloc;
    pub(crate) mod common;
    mod inertia;
    mod jacobian;
    mod rate;
    mod rolling;
}
