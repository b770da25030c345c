//! Evaluation and the products allocate nothing (counting global allocator).

use haptloop_rt::alloc::{count, is_installed};
use haptloop_solver::mechanisms::{four_bar, sphere_toy, stewart};
use haptloop_solver::{EvalError, Model};

fn assert_no_alloc(model: &Model) {
    assert!(is_installed());
    let mut ev = model.evaluation();
    let mut q = model.q0().to_vec();
    let targets = model.initial_targets();
    let mut y = vec![0.0; model.n_rows()];
    let mut z = vec![0.0; model.n_coords()];
    let (result, stats) = count(|| {
        for k in 0..10 {
            q[0] += 1e-4 * k as f64;
            ev.evaluate(model, &q, &targets)?;
            ev.evaluate_values(model, &q, &targets)?;
            let j = ev.jacobian();
            j.mul_vec(&z, &mut y).unwrap();
            j.mul_t_vec(ev.values(), &mut z).unwrap();
            j.mul_t_vec_add(-0.1, &y, &mut z).unwrap();
        }
        q[3] = f64::NAN;
        match ev.evaluate(model, &q, &targets) {
            Err(EvalError::NonFiniteCoordinate { index: 3 }) => Ok::<(), EvalError>(()),
            other => panic!("expected a NaN error, got {other:?}"),
        }
    });
    result.unwrap();
    assert_eq!(stats.total(), 0, "allocations during evaluation: {stats:?}");
}

#[test]
fn evaluate_and_products_allocate_nothing_four_bar() {
    assert_no_alloc(&four_bar());
}

#[test]
fn evaluate_and_products_allocate_nothing_stewart() {
    assert_no_alloc(&stewart());
}

#[test]
fn evaluate_and_products_allocate_nothing_sphere_toy() {
    assert_no_alloc(&sphere_toy());
}
