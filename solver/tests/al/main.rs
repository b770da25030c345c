//! Integration tests of the fast update, force feedback and `Program`: one
//! binary, a module per area. The counting allocator is installed so
//! `alloc` can prove that ticks allocate nothing.

#[global_allocator]
static ALLOC: haptloop_rt::alloc::CountingAllocator = haptloop_rt::alloc::CountingAllocator;

mod common;
mod convergence;
mod design;
mod force;
mod gears;
mod joint_redundant;
mod limits;
mod lockstep;
mod matvec;
mod multilevel;
mod pivoted_finger;
mod planar;
mod program;
mod redundant;
mod release_low_rank;
mod release_spare;
mod rules;
mod torque;
mod tree;
mod unreachable;
