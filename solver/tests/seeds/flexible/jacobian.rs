//! The analytic Jacobian of rows that reach deformation columns (spherical,
//! distance, point-on-plane joints and a point finger on a flexible body,
//! the clamp's weld) against central finite differences at random states,
//! non-unit quaternions and deformations of several millimetres.

use haptloop_solver::{FingerTarget, Model};
use nalgebra::{DMatrix, Vector3};

use crate::flexible::common::{Lcg, belly, cantilever};

fn fd(model: &Model, q: &[f64], t: &[FingerTarget], h: f64) -> DMatrix<f64> {
    let mut ev = model.evaluation();
    let mut j = DMatrix::zeros(model.n_rows(), model.n_coords());
    let mut x = q.to_vec();
    for c in 0..q.len() {
        x[c] = q[c] + h;
        ev.evaluate_values(model, &x, t).unwrap();
        let plus = ev.values().to_vec();
        x[c] = q[c] - h;
        ev.evaluate_values(model, &x, t).unwrap();
        for (r, p) in plus.iter().enumerate() {
            j[(r, c)] = (p - ev.values()[r]) / (2.0 * h);
        }
        x[c] = q[c];
    }
    j
}

fn check(model: &Model, seed: u64) {
    let mut rng = Lcg(seed);
    let flex = model.layout().aux_blocks()[0].clone();
    for case in 0..24 {
        let mut q = model.q0().to_vec();
        for (c, v) in q.iter_mut().enumerate() {
            let size = if flex.offset <= c { 5e-3 } else { 0.3 };
            *v += size * rng.next();
        }
        let t: Vec<FingerTarget> = model
            .initial_targets()
            .iter()
            .map(|t| FingerTarget::at(t.position_m + Vector3::new(0.01, -0.02, 0.005)))
            .collect();
        let mut ev = model.evaluation();
        ev.evaluate(model, &q, &t).unwrap();
        let a = ev.jacobian().to_dense();
        let (f1, f2) = (fd(model, &q, &t, 1e-6), fd(model, &q, &t, 5e-7));
        let mut reached = false;
        for r in 0..a.nrows() {
            for c in 0..a.ncols() {
                let est = (f1[(r, c)] - f2[(r, c)]).abs();
                let tol = 1e-7 * (1.0 + a[(r, c)].abs()) + 10.0 * est;
                let err = (a[(r, c)] - f2[(r, c)]).abs();
                assert!(
                    err <= tol,
                    "case {case}, row {r}, col {c}: {:e} vs FD {:e}",
                    a[(r, c)],
                    f2[(r, c)]
                );
                reached |= c >= flex.offset && a[(r, c)].abs() > 1e-3;
            }
        }
        assert!(reached, "no row reached the deformation columns");
    }
}

#[test]
fn cantilever_rows_match_finite_differences() {
    check(&cantilever(3), 11);
}

#[test]
fn belly_rows_match_finite_differences() {
    check(&belly(true), 12);
}
