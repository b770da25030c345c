//! After `analyze`, a solve allocates nothing (counting global allocator):
//! evaluation, normal-matrix fill, numeric Cholesky, dense-column Woodbury
//! solve, line search and the history all use preallocated buffers.

use haptloop_rt::alloc::{count, is_installed};
use haptloop_solver::mechanisms::{four_bar, sphere_toy, stewart};
use haptloop_solver::{Model, Placement, PlacementOptions};

use super::common::{chain212, hub, perturbed};

fn assert_solve_allocates_nothing(model: &Model) {
    assert!(is_installed());
    let targets = model.initial_targets();
    let start = perturbed(model, model.q0(), 0.01, 5f64.to_radians(), 5);
    let mut p = Placement::analyze(model, &PlacementOptions::default()).unwrap();
    let mut q = start.clone();
    let (info, stats) = count(|| p.solve(model, &mut q, &start, &targets).unwrap());
    assert!(info.iterations >= 3, "{info:?}");
    assert_eq!(stats.total(), 0, "allocations during solve: {stats:?}");
    // A second model object of the same structure: one Evaluation, then none.
    let twin = model.with_inequalities(&[]).unwrap();
    let mut q = start.clone();
    p.solve(&twin, &mut q, &start, &targets).unwrap();
    let mut q = start.clone();
    let (_, stats) = count(|| p.solve(&twin, &mut q, &start, &targets).unwrap());
    assert_eq!(stats.total(), 0, "allocations on the twin: {stats:?}");
}

#[test]
fn solve_allocates_nothing_four_bar() {
    assert_solve_allocates_nothing(&four_bar());
}

#[test]
fn solve_allocates_nothing_stewart() {
    assert_solve_allocates_nothing(&stewart());
}

#[test]
fn solve_allocates_nothing_chain212() {
    assert_solve_allocates_nothing(&chain212());
}

#[test]
fn solve_allocates_nothing_with_dense_columns() {
    let model = hub(50, false);
    assert_eq!(
        Placement::analyze(&model, &PlacementOptions::default())
            .unwrap()
            .stats()
            .dense_columns,
        7
    );
    assert_solve_allocates_nothing(&model);
}

#[test]
fn solve_allocates_nothing_sphere_toy() {
    assert_solve_allocates_nothing(&sphere_toy());
}
