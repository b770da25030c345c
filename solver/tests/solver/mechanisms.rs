//! Built-in mechanisms: exact counts, assembled initial configurations, and the
//! degrees of freedom the docs claim (coordinates − rank of the equality rows
//! without finger rows).

use haptloop_solver::mechanisms::{
    bennett, chain, chain_sized, four_bar, lattice, lattice_shape, lattice_sized, sphere_toy,
    stewart,
};
use haptloop_solver::{ConstraintKind, Model};

use crate::common::initial_residual;

/// Rank of the rows `keep` of C_q(q0), by diagonally pivoted Cholesky of
/// J Jᵀ (assembled sparsely from the transposed index). A pivot below 1e-12 ×
/// the largest diagonal (a singular value below 1e-6 × the largest) ends it.
fn rank(model: &Model, keep: impl Fn(usize) -> bool) -> usize {
    let mut ev = model.evaluation();
    ev.evaluate(model, model.q0(), &model.initial_targets())
        .unwrap();
    let j = ev.jacobian();
    let rows: Vec<usize> = (0..j.nrows()).filter(|&r| keep(r)).collect();
    let mut index = vec![usize::MAX; j.nrows()];
    for (k, &r) in rows.iter().enumerate() {
        index[r] = k;
    }
    let n = rows.len();
    let mut g = vec![0.0; n * n];
    let (ptr, col_rows, pos, val) = (j.col_ptr(), j.col_rows(), j.col_value_index(), j.values());
    for c in 0..j.ncols() {
        for a in ptr[c]..ptr[c + 1] {
            for b in ptr[c]..ptr[c + 1] {
                let (ra, rb) = (index[col_rows[a]], index[col_rows[b]]);
                if ra != usize::MAX && rb != usize::MAX {
                    g[ra * n + rb] += val[pos[a]] * val[pos[b]];
                }
            }
        }
    }
    let max_diag = (0..n).map(|i| g[i * n + i]).fold(0.0, f64::max);
    let mut perm: Vec<usize> = (0..n).collect();
    for k in 0..n {
        let (p, d) = (k..n)
            .map(|i| (i, g[perm[i] * n + perm[i]]))
            .max_by(|a, b| a.1.total_cmp(&b.1))
            .unwrap();
        if d <= 1e-12 * max_diag {
            return k;
        }
        perm.swap(k, p);
        let pk = perm[k];
        let s = d.sqrt();
        for &pi in &perm[k + 1..] {
            g[pi * n + pk] /= s;
        }
        for a in k + 1..n {
            let pa = perm[a];
            let la = g[pa * n + pk];
            for &pb in &perm[k + 1..] {
                g[pa * n + pb] -= la * g[pb * n + pk];
            }
        }
    }
    n
}

fn dof_without_fingers(model: &Model) -> usize {
    let finger_rows = |r: usize| {
        let kind = model.constraints()[model.rows()[r].constraint.index()].kind;
        matches!(
            kind,
            ConstraintKind::PointFinger | ConstraintKind::RigidFinger
        )
    };
    let eq = model.equality_rows();
    model.n_coords() - rank(model, |r| eq.contains(&r) && !finger_rows(r))
}

fn counts(model: &Model) -> (usize, usize, usize, usize, usize) {
    let nnz = model.evaluation().jacobian().nnz();
    (
        model.bodies().len(),
        model.n_coords(),
        model.equality_rows().len(),
        model.inequality_rows().len(),
        nnz,
    )
}

/// Independent loops of the joint graph: joints − bodies + connected components.
fn loops(model: &Model) -> usize {
    let mut parent: Vec<usize> = (0..model.bodies().len()).collect();
    fn find(p: &mut [usize], i: usize) -> usize {
        if p[i] != i {
            p[i] = find(p, p[i]);
        }
        p[i]
    }
    // Joints: two-body constraints that are not limits (norms and fingers
    // have no second body).
    let joints: Vec<_> = model
        .constraints()
        .iter()
        .filter(|c| c.bodies[1].is_some() && c.limits.is_none())
        .collect();
    for c in &joints {
        let (a, b) = (c.bodies[0].unwrap().index(), c.bodies[1].unwrap().index());
        let (ra, rb) = (find(&mut parent, a), find(&mut parent, b));
        parent[ra] = rb;
    }
    let components = (0..parent.len())
        .filter(|&i| find(&mut parent, i) == i)
        .count();
    joints.len() + components - model.bodies().len()
}

#[test]
fn four_bar_counts_assembly_and_one_dof() {
    let m = four_bar();
    // bodies, coordinates, equality rows (5+3+4+5 joints, 3 finger, 3 norms), inequality rows, nnz
    assert_eq!(counts(&m), (4, 21, 23, 0, 201));
    assert!(
        initial_residual(&m) < 1e-15,
        "C(q0) = {:e}",
        initial_residual(&m)
    );
    assert_eq!(dof_without_fingers(&m), 1);
    assert_eq!(loops(&m), 1);
}

#[test]
fn stewart_counts_assembly_and_six_dof() {
    let m = stewart();
    // 6 × (4 + 5 + 3) joint rows + 6 finger + 13 norms; 6 × 2 limit rows.
    assert_eq!(counts(&m), (14, 91, 91, 12, 1102));
    assert!(
        initial_residual(&m) < 1e-15,
        "C(q0) = {:e}",
        initial_residual(&m)
    );
    assert_eq!(dof_without_fingers(&m), 6);
    // The rigid grasp pins the platform: all 91 equality rows are independent.
    assert_eq!(rank(&m, |r| m.equality_rows().contains(&r)), 91);
    assert_eq!(loops(&m), 5);
    // Every leg starts mid-stroke: both limit rows equal the stroke.
    let mut ev = m.evaluation();
    ev.evaluate(&m, m.q0(), &m.initial_targets()).unwrap();
    for &v in &ev.values()[m.inequality_rows()] {
        assert!(
            (v - haptloop_solver::mechanisms::STEWART_STROKE_M).abs() < 1e-15,
            "{v}"
        );
    }
}

#[test]
fn sphere_toy_counts_assembly_and_full_rank() {
    let m = sphere_toy();
    // 120 U × 4 + 72 S × 3 + 132 norms + 3 finger = 831 rows; nnz 120·56 + 72·42 + 132·4 + 21.
    assert_eq!(counts(&m), (132, 924, 831, 0, 10_293));
    assert_eq!(
        m.constraints()
            .iter()
            .filter(|c| c.kind == ConstraintKind::Universal)
            .count(),
        120
    );
    assert_eq!(
        m.constraints()
            .iter()
            .filter(|c| c.kind == ConstraintKind::Spherical)
            .count(),
        72
    );
    assert!(
        initial_residual(&m) < 1e-15,
        "C(q0) = {:e}",
        initial_residual(&m)
    );
    assert_eq!(loops(&m), 61);
    assert_eq!(dof_without_fingers(&m), 96);
    assert_eq!(rank(&m, |_| true), 831, "finger rows independent too");
}

fn count_kind(model: &Model, kind: ConstraintKind) -> usize {
    model
        .constraints()
        .iter()
        .filter(|c| c.kind == kind)
        .count()
}

/// Equality rows without the finger's that the rank shows to be dependent.
fn redundant_rows(model: &Model) -> usize {
    let eq = model.equality_rows();
    let n_fingers = model
        .constraints()
        .iter()
        .filter(|c| {
            matches!(
                c.kind,
                ConstraintKind::PointFinger | ConstraintKind::RigidFinger
            )
        })
        .count();
    let rows = eq.len() - 3 * n_fingers;
    rows - (model.n_coords() - dof_without_fingers(model))
}

#[test]
fn bennett_counts_assembly_one_dof_and_three_redundant_rows() {
    let m = bennett();
    // 4 × 5 joint rows + 3 norms + 3 finger rows.
    let (bodies, coords, eq, ineq, _) = counts(&m);
    assert_eq!((bodies, coords, eq, ineq), (4, 21, 26, 0));
    assert_eq!(count_kind(&m, ConstraintKind::Revolute), 4);
    assert!(
        initial_residual(&m) < 1e-15,
        "C(q0) = {:e}",
        initial_residual(&m)
    );
    assert_eq!(loops(&m), 1);
    // Spatial Grübler says 6·3 − 20 = −2; Bennett's linkage moves with 1.
    assert_eq!(dof_without_fingers(&m), 1);
    assert_eq!(redundant_rows(&m), 3);
}

#[test]
fn lattice_counts_assembly_and_planar_mobility() {
    // The 4 × 16 rank (1115 rows, dense) takes long unoptimised: the debug
    // run checks the 2 × 8 only.
    let sizes: &[(usize, usize)] = if cfg!(debug_assertions) {
        &[(2, 8)]
    } else {
        &[(4, 16), (2, 8)]
    };
    for &(rows, cols) in sizes {
        let m = lattice_sized(rows, cols).build().unwrap();
        let (bars, joints) = (rows * (2 * cols + 1), rows * (3 * cols + 1));
        assert_eq!(m.bodies().len(), bars + 1, "{rows}×{cols}");
        assert_eq!(count_kind(&m, ConstraintKind::Revolute), joints);
        assert!(
            initial_residual(&m) < 1e-15,
            "C(q0) = {:e}",
            initial_residual(&m)
        );
        assert_eq!(loops(&m), rows * cols, "one loop per cell");
        // Planar Grübler 3·bars − 2·joints, exact for this lattice: one shear
        // per row of cells.
        assert_eq!(3 * bars - 2 * joints, rows);
        assert_eq!(dof_without_fingers(&m), rows, "{rows}×{cols}");
        // Each planar loop makes 3 of its out-of-plane rows dependent.
        assert_eq!(redundant_rows(&m), 3 * rows * cols, "{rows}×{cols}");
    }
    assert_eq!(
        lattice().bodies().len(),
        133,
        "the issue's 132 bars + ground"
    );
    assert_eq!(lattice_shape(512).map(|(r, c)| r * (2 * c + 1)), Some(520));
}

#[test]
fn chain_counts_assembly_and_mobility() {
    for links in [64, 8] {
        let m = chain_sized(links).build().unwrap();
        assert_eq!(m.bodies().len(), links + 1);
        assert_eq!(count_kind(&m, ConstraintKind::Universal), links - 1);
        assert_eq!(count_kind(&m, ConstraintKind::Spherical), 2);
        assert!(
            initial_residual(&m) < 1e-15,
            "{links}: C(q0) = {:e}",
            initial_residual(&m)
        );
        assert_eq!(loops(&m), 1);
        // Spatial Grübler 6n − 4(n − 1) − 2·3, no redundant row.
        assert_eq!(dof_without_fingers(&m), 2 * links - 2, "{links}");
        assert_eq!(redundant_rows(&m), 0, "{links}");
    }
    assert_eq!(chain().bodies().len(), 65);
}
