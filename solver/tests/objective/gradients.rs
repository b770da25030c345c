//! Every objective kind's analytic gradient (body, Euler-parameter, anchor
//! and free-position columns) against central finite differences at random
//! states with non-unit quaternions. Fixed seed.
//!
//! Tolerance as for the constraint Jacobians (`tests/solver/fd.rs`):
//! 1e-7 (1 + |g|) plus 10× the difference's own error estimate
//! |FD(h) − FD(h/2)|, h = 1e-6, plus the rounding of F itself, 100 ε |F| / h
//! (an obstacle's barrier reaches F ≈ 200 m² next to gradients of 0.06); a
//! wrong sign, factor or missing term errs by the order of |g| and fails.

use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed, TestRunner};

use crate::common::{self, fd, gradient, state, state_len, total};

const CASES: u32 = 48;

fn check(model: &common::Designed, q: &[f64]) -> Result<(), String> {
    let (g, f) = gradient(model, q);
    let direct = total(model, q);
    if (f - direct).abs() > 1e-12 * (1.0 + direct.abs()) {
        return Err(format!(
            "gradient() returned F = {f}, values() say {direct}"
        ));
    }
    let (a, b) = (fd(model, q, 1e-6), fd(model, q, 5e-7));
    let rounding = 100.0 * f64::EPSILON * f.abs() / 1e-6;
    for c in 0..q.len() {
        let tol = 1e-7 * (1.0 + g[c].abs()) + 10.0 * (a[c] - b[c]).abs() + rounding;
        if !g[c].is_finite() || (g[c] - a[c]).abs() > tol {
            return Err(format!(
                "column {c}: analytic {:e}, finite difference {:e} (tolerance {tol:e})",
                g[c], a[c]
            ));
        }
    }
    Ok(())
}

fn run(model: common::Designed) {
    let config = Config {
        cases: CASES,
        rng_seed: RngSeed::Fixed(0x0b1e_c71e),
        failure_persistence: None,
        ..Config::default()
    };
    let nonzero = std::cell::Cell::new(0usize);
    TestRunner::new(config)
        .run(
            &prop::collection::vec(-1.0f64..1.0, state_len(&model)),
            |u| {
                let q = state(&model, &u);
                if gradient(&model, &q).0.iter().any(|v| v.abs() > 1e-9) {
                    nonzero.set(nonzero.get() + 1);
                }
                check(&model, &q).map_err(TestCaseError::fail)
            },
        )
        .unwrap();
    // The states exercise the objective: it pulls somewhere in most of them.
    let nonzero = nonzero.get();
    assert!(
        nonzero as u32 >= CASES / 2,
        "gradient zero in {} of {CASES} states",
        CASES as usize - nonzero
    );
}

#[test]
fn dexterity_of_a_revolute_arm_with_a_free_base() {
    run(common::dexterity());
}

#[test]
fn dexterity_of_a_mixed_chain_with_free_anchors_and_two_directions() {
    run(common::dexterity_mixed());
}

#[test]
fn dexterity_with_eq_13s_angular_rows() {
    run(common::dexterity_angular());
}

#[test]
fn dexterity_of_a_closed_chain() {
    run(common::dexterity_closed(false));
}

#[test]
fn dexterity_of_a_two_dof_loop_with_an_angular_row() {
    run(common::dexterity_closed(true));
}

#[test]
fn obstacle_at_a_world_point() {
    run(common::obstacle(false));
}

#[test]
fn inverse_distance_eq_15_as_written() {
    run(common::inverse_distance());
}

#[test]
fn workspace_volume_through_free_anchors() {
    run(common::workspace());
}

#[test]
fn straight_line() {
    run(common::straight_line());
}

#[test]
fn joint_limit_distance_with_free_anchors_and_position() {
    run(common::joint_limits());
}

/// The obstacle's own body is an input: its columns get nothing, every other
/// column matches finite differences.
#[test]
fn obstacle_on_a_moving_body_leaves_that_body_alone() {
    let model = common::obstacle(true);
    let bullet = model.body_id("bullet").unwrap();
    let cols = model.layout().body_offset(bullet).unwrap();
    let u: Vec<f64> = (0..state_len(&model))
        .map(|k| ((k * 29 % 17) as f64 / 8.5) - 1.0)
        .collect();
    let q = state(&model, &u);
    let (g, _) = gradient(&model, &q);
    assert!(g[cols..cols + 7].iter().all(|&v| v == 0.0));
    assert!(
        g.iter().any(|v| v.abs() > 1e-6),
        "the obstacle pulls nothing"
    );
    let (a, b) = (fd(&model, &q, 1e-6), fd(&model, &q, 5e-7));
    for c in (0..q.len()).filter(|c| !(cols..cols + 7).contains(c)) {
        let tol = 1e-7 * (1.0 + g[c].abs()) + 10.0 * (a[c] - b[c]).abs();
        assert!(
            (g[c] - a[c]).abs() <= tol,
            "column {c}: {} vs {}",
            g[c],
            a[c]
        );
    }
}

/// The checker can fail: a gradient with one term's sign flipped is caught.
#[test]
fn a_wrong_gradient_is_caught() {
    let model = common::straight_line();
    let q = model.q0().to_vec();
    let (mut g, _) = gradient(&model, &q);
    let a = fd(&model, &q, 1e-6);
    g[0] = -g[0];
    assert!(g[0].abs() > 1e-3);
    assert!((g[0] - a[0]).abs() > 1e-7 * (1.0 + g[0].abs()));
}
