//! Integration tests of the Newton-KKT placement (`haptloop_solver::placement`):
//! one binary with the counting allocator installed, so `alloc` can prove
//! zero allocation per Newton iteration. A module per area.

#[global_allocator]
static ALLOC: haptloop_rt::alloc::CountingAllocator = haptloop_rt::alloc::CountingAllocator;

mod alloc;
mod cache;
mod common;
mod contact;
mod convergence;
mod dense_columns;
mod inequalities;
mod least_squares;
mod modes;
mod reference;
mod singular;
