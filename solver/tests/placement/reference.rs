//! Agreement with an independent dense reference: Newton on the full KKT
//! system [W Jᵀ; J 0] solved by nalgebra's LU (no normal equations, no
//! damping, no dense-column split), on small full-rank problems: q to 1e-10,
//! λ to 1e-9 relative.

use haptloop_solver::mechanisms::stewart;
use haptloop_solver::{FingerTarget, Model, Placement, PlacementOptions, SolveStatus};
use nalgebra::{DMatrix, DVector};

use super::common::{hub, perturbed};

/// min ½‖q − q_ref‖²_W s.t. the equality rows, by dense KKT Newton; returns
/// q and the equality multipliers (W(q − q_ref) + Jᵀλ = 0).
fn dense_reference(
    model: &Model,
    start: &[f64],
    q_ref: &[f64],
    targets: &[FingerTarget],
    w: &[f64],
) -> (Vec<f64>, Vec<f64>) {
    let (n, m) = (model.n_coords(), model.equality_rows().end);
    let mut ev = model.evaluation();
    let mut q = DVector::from_column_slice(start);
    let mut lambda = DVector::zeros(m);
    for _ in 0..200 {
        ev.evaluate(model, q.as_slice(), targets).unwrap();
        let j = ev.jacobian().to_dense().rows(0, m).into_owned();
        let mut kkt = DMatrix::zeros(n + m, n + m);
        let mut rhs = DVector::zeros(n + m);
        for i in 0..n {
            kkt[(i, i)] = w[i];
            rhs[i] = -w[i] * (q[i] - q_ref[i]);
        }
        kkt.view_mut((0, n), (n, m)).copy_from(&j.transpose());
        kkt.view_mut((n, 0), (m, n)).copy_from(&j);
        for r in 0..m {
            rhs[n + r] = -ev.values()[r];
        }
        let sol = kkt.lu().solve(&rhs).expect("full-rank KKT");
        let step = sol.rows(0, n).amax();
        q += sol.rows(0, n);
        lambda.copy_from(&sol.rows(n, m));
        if step < 1e-15 {
            break;
        }
    }
    (q.as_slice().to_vec(), lambda.as_slice().to_vec())
}

fn compare(model: &Model, options: PlacementOptions, seed: u64) {
    let targets = model.initial_targets();
    let start = perturbed(model, model.q0(), 0.01, 5f64.to_radians(), seed);
    let w = options
        .weights
        .clone()
        .unwrap_or_else(|| vec![1.0; model.n_coords()]);
    let (q_ref_dense, l_ref) = dense_reference(model, &start, &start, &targets, &w);
    // Stationarity converges linearly (the Hessian block is W, Eq. 8), so
    // agreement to 1e-10 needs a step tolerance below the default 1e-9.
    let options = PlacementOptions {
        step_tolerance: 1e-12,
        max_iterations: 200,
        ..options
    };
    let mut p = Placement::analyze(model, &options).unwrap();
    let mut q = start.clone();
    let info = p.solve(model, &mut q, &start, &targets).unwrap();
    assert_eq!(info.status, SolveStatus::Converged, "{info:?}");
    let dq = q
        .iter()
        .zip(&q_ref_dense)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(dq <= 1e-10, "q differs from the dense reference by {dq:e}");
    let lam = p.multipliers();
    let scale = l_ref.iter().fold(1.0f64, |s, v| s.max(v.abs()));
    let dl = lam
        .iter()
        .zip(&l_ref)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(dl <= 1e-9 * scale, "λ differs by {dl:e} (scale {scale})");
    // Inequality rows (the Stewart strokes) are inactive here: λ_j = 0.
    for l in &lam[model.equality_rows().end..] {
        assert!(l.abs() <= 1e-12, "inactive inequality with λ = {l:e}");
    }
}

#[test]
fn stewart_matches_dense_kkt_reference() {
    compare(&stewart(), PlacementOptions::default(), 3);
}

#[test]
fn weighted_stewart_matches_dense_kkt_reference() {
    let model = stewart();
    let weights = (0..model.n_coords())
        .map(|i| 1.0 + (i % 5) as f64)
        .collect();
    let options = PlacementOptions {
        weights: Some(weights),
        ..Default::default()
    };
    compare(&model, options, 5);
}

#[test]
fn dense_column_split_matches_dense_kkt_reference() {
    // Threshold 10 makes the 6-spoke hub's 7 columns (22 entries) dense, so
    // the modified Schur complement is what is being compared.
    let options = PlacementOptions {
        dense_column_threshold: 10,
        ..Default::default()
    };
    let model = hub(6, false);
    assert_eq!(
        Placement::analyze(&model, &options)
            .unwrap()
            .stats()
            .dense_columns,
        7
    );
    compare(&model, options, 11);
}
