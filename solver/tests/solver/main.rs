//! Integration tests of haptloop-solver: one binary, a module per area.
//! The counting allocator is installed so `alloc` can prove zero allocation.

#[global_allocator]
static ALLOC: haptloop_rt::alloc::CountingAllocator = haptloop_rt::alloc::CountingAllocator;

mod alloc;
mod build_errors;
mod common;
mod design;
mod fd;
mod jacobian_fd;
mod joint_choice;
mod joint_coordinates;
mod joint_fallback;
mod joint_scenes;
mod joint_stewart;
mod mechanisms;
mod model;
mod pattern;
mod reduced_tick;
