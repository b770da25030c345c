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
