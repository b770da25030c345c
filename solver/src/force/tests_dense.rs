//! The small-matrix dense path of the Eq. 7 factor (`cholesky`'s `dense`)
//! against the supernodal kernels on the fast loop's own matrices: the
//! four-bar, Bennett, Stewart and Peaucellier's A after a few ticks of
//! motion, each solved by both (the dense path forced on Stewart and
//! Peaucellier, which are above its size limit), finger and joint
//! multipliers and a projected step's solution compared.

use std::sync::Arc;
use std::time::Duration;

use super::solve::MultiplierSolve;
use crate::mechanisms::{bennett, four_bar, stewart};
use crate::{Model, Program, SolverSettings};

fn peaucellier() -> Model {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/peaucellier.toml");
    crate::scene::load(&path).unwrap().compile().unwrap().model
}

/// max |a − b| / max |a|.
fn rel(a: &[f64], b: &[f64]) -> f64 {
    let scale = a.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let diff = a
        .iter()
        .zip(b)
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
    diff / scale
}

#[test]
fn the_dense_path_solves_eq7_as_the_supernodal_factor() {
    for (name, model) in [
        ("four-bar", four_bar()),
        ("bennett", bennett()),
        ("stewart", stewart()),
        ("peaucellier", peaucellier()),
    ] {
        let model = Arc::new(model);
        let mut p = Program::new(model.clone(), SolverSettings::default()).unwrap();
        let small = p.feedback().is_dense();
        let targets0 = model.initial_targets();
        let mut targets = targets0.clone();
        for k in 0..20 {
            let a = 0.003 * (k as f64 * 0.3).sin();
            for (t, t0) in targets.iter_mut().zip(&targets0) {
                t.position_m = t0.position_m + nalgebra::Vector3::new(a, 0.5 * a, 0.2 * a);
            }
            let r = p.tick(&targets, Duration::from_millis(1));
            assert_eq!(r.status, crate::program::TickOutcome::Ok, "{name} tick {k}");
        }
        let (gram, r, known) = p.feedback().last_system();
        let n = gram.n_j + gram.m_f;
        let limit = std::hint::black_box(crate::cholesky::DENSE_MAX);
        assert_eq!(small, n <= limit, "{name}: n {n}");
        let mut sparse = MultiplierSolve::with_path(gram, None, None, &[], 0).unwrap();
        let mut dense = MultiplierSolve::with_path(gram, None, None, &[], usize::MAX).unwrap();
        assert!(dense.is_dense() && !sparse.is_dense());
        sparse.solve(gram, r, known).unwrap();
        dense.solve(gram, r, known).unwrap();
        assert_eq!(sparse.rank, dense.rank, "{name}");
        let e_f = rel(&sparse.lambda_f, &dense.lambda_f);
        let lj = |s: &MultiplierSolve| -> Vec<f64> {
            (0..gram.n_j).map(|j| s.joint_multiplier(j)).collect()
        };
        let e_j = rel(&lj(&sparse), &lj(&dense));
        // The finger coupling's compliance relative to A_FF's scale: a
        // k_inv far below it makes S + diag(k_inv) as ill-conditioned as S
        // (rank one on the 1-DOF linkages), and then any two summation
        // orders differ by that condition times round-off.
        let ff = &gram.values[gram.nnz() + gram.m_f * gram.n_j..];
        let reference = (0..gram.m_f)
            .map(|f| ff[f * gram.m_f + f])
            .fold(0.0, f64::max);
        let k_inv: Vec<f64> = (0..gram.m_f)
            .map(|f| 1e-2 * reference * (1 + f) as f64)
            .collect();
        let (mut ys, mut yd) = (vec![0.0; r.len()], vec![0.0; r.len()]);
        sparse.project(gram, r, &k_inv, &mut ys).unwrap();
        dense.project(gram, r, &k_inv, &mut yd).unwrap();
        let e_y = rel(&ys, &yd);
        assert!(
            e_f < 1e-12 && e_j < 1e-12 && e_y < 1e-12,
            "{name} (n {n}): λ_F {e_f:e}, λ_J {e_j:e}, projected step {e_y:e}"
        );
    }
}
