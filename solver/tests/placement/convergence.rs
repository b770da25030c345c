//! Quadratic convergence from perturbed starts (1 cm / 5° on every body).

use haptloop_solver::mechanisms::{four_bar, stewart};
use haptloop_solver::{Model, Placement, PlacementOptions, SolveStatus};

use super::common::{perturbed, residual};

/// Solves from a perturbed start (q_ref = the start: re-projection) and
/// checks θ_{k+1} ≤ K θ_k² on every step whose result is above the damping
/// floor (below ~1e-10 the residual is the bias μ|λ| of the 1e-12 damping).
fn assert_quadratic(model: &Model, seed: u64, max_iterations: u32) {
    let targets = model.initial_targets();
    let start = perturbed(model, model.q0(), 0.01, 5f64.to_radians(), seed);
    let mut p = Placement::analyze(model, &PlacementOptions::default()).unwrap();
    let mut q = start.clone();
    let info = p.solve(model, &mut q, &start, &targets).unwrap();
    assert_eq!(info.status, SolveStatus::Converged, "{info:?}");
    assert!(info.iterations <= max_iterations, "{info:?}");
    assert!(info.residual <= 1e-9 && residual(model, &q, &targets) <= 1e-9);
    let mut thetas = vec![residual(model, &start, &targets)];
    thetas.extend(p.history().iter().map(|h| h.residual));
    assert!(
        thetas[0] > 1e-3,
        "the perturbation must matter: {}",
        thetas[0]
    );
    let mut checked = 0;
    for w in thetas.windows(2) {
        if w[1] > 1e-10 {
            assert!(w[1] <= 10.0 * w[0] * w[0], "not quadratic: {thetas:?}");
            checked += 1;
        }
    }
    assert!(checked >= 2, "too few steps to see the rate: {thetas:?}");
}

#[test]
fn four_bar_converges_quadratically_from_perturbed_starts() {
    for seed in [1, 7, 42] {
        assert_quadratic(&four_bar(), seed, 6);
    }
}

#[test]
fn stewart_converges_quadratically_from_perturbed_starts() {
    for seed in [1, 7, 42] {
        assert_quadratic(&stewart(), seed, 6);
    }
}

#[test]
fn an_assembled_start_is_left_in_place() {
    let model = stewart();
    let mut p = Placement::analyze(&model, &PlacementOptions::default()).unwrap();
    let mut q = model.q0().to_vec();
    let info = p
        .solve(&model, &mut q, model.q0(), &model.initial_targets())
        .unwrap();
    assert_eq!(info.status, SolveStatus::Converged);
    let moved = q
        .iter()
        .zip(model.q0())
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(moved < 1e-14, "moved {moved}");
    assert!(p.multipliers().iter().all(|l| l.abs() < 1e-12));
}
