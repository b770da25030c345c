//! One body joined to 50 others (Choi & Cremer's star): the dense columns are
//! split off, so the factor stays as small as for the same bodies in a chain.

use haptloop_solver::{Placement, PlacementOptions, SolveStatus};

use super::common::{hub, perturbed};

#[test]
fn star_of_50_keeps_factor_near_the_sparse_case() {
    let star = hub(50, false);
    let chain = hub(50, true);
    let split = Placement::analyze(&star, &PlacementOptions::default())
        .unwrap()
        .stats();
    let unsplit_options = PlacementOptions {
        dense_column_threshold: usize::MAX,
        ..Default::default()
    };
    let unsplit = Placement::analyze(&star, &unsplit_options).unwrap().stats();
    let sparse = Placement::analyze(&chain, &PlacementOptions::default())
        .unwrap()
        .stats();
    assert_eq!(
        (split.rows, split.jacobian_nnz),
        (sparse.rows, sparse.jacobian_nnz)
    );
    // The hub's 7 columns have 3·50 + 3 + 1 = 154 entries each.
    assert_eq!(split.dense_columns, 7);
    assert_eq!(sparse.dense_columns, 0);
    // Rank of the correction: 7 dense columns + 4 F columns (the hub's
    // ground joint rows and norm row have no sparse entry left).
    assert_eq!(split.low_rank, 11);
    // Factor size and flops, with the k = 11 dense columns of Z = S⁻¹U
    // counted as factor entries: near the chain, far below the unsplit star.
    let split_entries = split.factor_nnz + split.rows * split.low_rank;
    let split_flops = split.factor_flops + (split.rows * split.low_rank * split.low_rank) as u64;
    assert!(
        split.factor_nnz <= sparse.factor_nnz,
        "{split:?} vs {sparse:?}"
    );
    assert!(
        split_entries <= 3 * sparse.factor_nnz,
        "{split:?} vs {sparse:?}"
    );
    assert!(
        split_flops <= 5 * sparse.factor_flops,
        "{split:?} vs {sparse:?}"
    );
    assert!(
        unsplit.factor_nnz >= 10 * sparse.factor_nnz,
        "{unsplit:?} vs {sparse:?}"
    );
    assert!(
        unsplit.factor_flops >= 100 * sparse.factor_flops,
        "{unsplit:?}"
    );
}

#[test]
fn split_and_unsplit_solves_agree() {
    let star = hub(50, false);
    let targets = star.initial_targets();
    let start = perturbed(&star, star.q0(), 0.01, 5f64.to_radians(), 9);
    let unsplit_options = PlacementOptions {
        dense_column_threshold: usize::MAX,
        ..Default::default()
    };
    let mut results = Vec::new();
    for options in [PlacementOptions::default(), unsplit_options] {
        let mut p = Placement::analyze(&star, &options).unwrap();
        let mut q = start.clone();
        let info = p.solve(&star, &mut q, star.q0(), &targets).unwrap();
        assert_eq!(info.status, SolveStatus::Converged, "{info:?}");
        assert!(info.residual <= 1e-9);
        results.push(q);
    }
    let d = results[0]
        .iter()
        .zip(&results[1])
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(d <= 1e-10, "split and unsplit differ by {d:e}");
}

/// Many rows that touch only the dense hub (30 copies of the hub's ground
/// joint: 90 F rows) are eliminated row by row instead of widening the
/// Woodbury capacitance to 7 + 91 columns: the split solve still agrees with
/// the unsplit one from a perturbed start.
#[test]
fn many_rows_on_the_dense_hub_alone_agree_with_the_unsplit_solve() {
    use haptloop_solver::{BodySpec, FingerSpec, JointKind, JointSpec, ModelBuilder};
    let mut b = ModelBuilder::new();
    b.body(BodySpec::fixed("ground"));
    b.body(BodySpec::new("hub"));
    for k in 0..30 {
        b.joint(JointSpec::new(JointKind::Spherical, "ground", "hub").named(format!("g{k}")));
    }
    for k in 0..12 {
        let t = 2.0 * std::f64::consts::PI * k as f64 / 12.0;
        let c = [0.1 * t.cos(), 0.1 * t.sin(), 0.0];
        let name = format!("s{k}");
        b.body(BodySpec::new(&name).at(c));
        let p = c.map(|v| 0.5 * v);
        b.joint(
            JointSpec::new(JointKind::Spherical, "hub", &name)
                .anchors(p, [p[0] - c[0], p[1] - c[1], p[2] - c[2]]),
        );
    }
    b.finger(FingerSpec::point("index", "s0", [0.0, 0.0, 0.01]));
    let model = b.build().unwrap();
    let split_options = PlacementOptions {
        dense_column_threshold: 16,
        ..Default::default()
    };
    let unsplit_options = PlacementOptions {
        dense_column_threshold: usize::MAX,
        ..Default::default()
    };
    let split = Placement::analyze(&model, &split_options).unwrap().stats();
    assert_eq!(split.dense_columns, 7);
    assert!(split.low_rank >= 7 + 90, "{split:?}");
    let solve = |options: &PlacementOptions, targets: &[haptloop_solver::FingerTarget]| {
        let start = perturbed(&model, model.q0(), 0.01, 5f64.to_radians(), 3);
        let mut p = Placement::analyze(&model, options).unwrap();
        let mut q = start;
        let info = p.solve(&model, &mut q, model.q0(), targets).unwrap();
        (q, info)
    };
    // Reachable: both converge to the same configuration.
    let targets = model.initial_targets();
    let (qs, split_info) = solve(&split_options, &targets);
    let (qu, unsplit_info) = solve(&unsplit_options, &targets);
    assert_eq!(split_info.status, SolveStatus::Converged, "{split_info:?}");
    assert_eq!(
        unsplit_info.status,
        SolveStatus::Converged,
        "{unsplit_info:?}"
    );
    let d = qs
        .iter()
        .zip(&qu)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(d <= 1e-9, "split and unsplit differ by {d:e}");
    // Out of reach (the finger lifted 2 cm): the same least-squares
    // compromise, residual equal to 1e-9 relative.
    let mut lifted = model.initial_targets();
    lifted[0].position_m.z += 0.02;
    let (_, s) = solve(&split_options, &lifted);
    let (_, u) = solve(&unsplit_options, &lifted);
    assert_eq!(
        (s.status, u.status),
        (SolveStatus::LeastSquares, SolveStatus::LeastSquares)
    );
    assert!(
        (s.residual - u.residual).abs() <= 1e-9 * u.residual,
        "{s:?} vs {u:?}"
    );
}
