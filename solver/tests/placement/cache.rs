//! Analyses are cached by structure; inputs that cannot be solved are errors,
//! not panics.

use haptloop_solver::mechanisms::{four_bar, stewart};
use haptloop_solver::placement::StructureKey;
use haptloop_solver::{
    EvalError, Placement, PlacementCache, PlacementError, PlacementOptions, PlaneOwner,
    PointPlaneSpec, SolveStatus,
};

fn contact(model: &haptloop_solver::Model) -> Vec<PointPlaneSpec> {
    vec![PointPlaneSpec {
        name: "floor".into(),
        body: model.body_id("platform").unwrap(),
        point_m: [0.0, 0.0, 0.0],
        plane: PlaneOwner::World,
        plane_point_m: [0.0, 0.0, 0.0],
        normal: [0.0, 0.0, 1.0],
    }]
}

#[test]
fn a_contact_set_that_changes_back_reuses_its_analysis() {
    let base = stewart();
    let touching = base.with_inequalities(&contact(&base)).unwrap();
    let base_again = base.with_inequalities(&[]).unwrap();
    let touching_again = base.with_inequalities(&contact(&base)).unwrap();
    assert_eq!(StructureKey::of(&base), StructureKey::of(&base_again));
    assert_eq!(
        StructureKey::of(&touching),
        StructureKey::of(&touching_again)
    );
    assert_ne!(StructureKey::of(&base), StructureKey::of(&touching));

    let mut cache = PlacementCache::new(PlacementOptions::default(), 4);
    for (model, analyses) in [
        (&base, 1),
        (&touching, 2),
        (&base_again, 2),
        (&touching_again, 2),
    ] {
        let p = cache.get(model).unwrap();
        let mut q = model.q0().to_vec();
        let info = p
            .solve(model, &mut q, model.q0(), &model.initial_targets())
            .unwrap();
        assert_eq!(info.status, SolveStatus::Converged);
        assert_eq!(cache.analyses(), analyses);
    }
    assert_eq!(cache.len(), 2);
    // Capacity 1: alternating structures re-analyse each time.
    let mut small = PlacementCache::new(PlacementOptions::default(), 1);
    for m in [&base, &touching, &base] {
        small.get(m).unwrap();
    }
    assert_eq!((small.analyses(), small.len()), (3, 1));
}

#[test]
fn bad_inputs_are_errors_and_leave_q_alone() {
    let model = stewart();
    let mut p = Placement::analyze(&model, &PlacementOptions::default()).unwrap();
    let targets = model.initial_targets();
    let other = four_bar();
    let mut q = model.q0().to_vec();
    let q_other = other.q0().to_vec();
    assert_eq!(
        p.solve(
            &other,
            &mut q_other.clone(),
            &q_other,
            &other.initial_targets()
        ),
        Err(PlacementError::StructureMismatch)
    );
    assert!(matches!(
        p.solve(&model, &mut q[..5].to_vec(), model.q0(), &targets),
        Err(PlacementError::CoordinateCount { .. })
    ));
    q[2] = f64::NAN;
    let before = q.clone();
    assert_eq!(
        p.solve(&model, &mut q, model.q0(), &targets),
        Err(PlacementError::Eval(EvalError::NonFiniteCoordinate {
            index: 2
        }))
    );
    assert!(q[2].is_nan() && q[..2] == before[..2]);
    let mut bad_ref = model.q0().to_vec();
    bad_ref[7] = f64::INFINITY;
    let mut q = model.q0().to_vec();
    assert_eq!(
        p.solve(&model, &mut q, &bad_ref, &targets),
        Err(PlacementError::NonFiniteReference { index: 7 })
    );
    let bad = PlacementOptions {
        weights: Some(vec![1.0; 3]),
        ..Default::default()
    };
    assert!(matches!(
        Placement::analyze(&model, &bad),
        Err(PlacementError::WeightCount {
            expected: 91,
            got: 3
        })
    ));
    let bad = PlacementOptions {
        damping: f64::NAN,
        ..Default::default()
    };
    assert_eq!(
        Placement::analyze(&model, &bad).unwrap_err(),
        PlacementError::InvalidOption { field: "damping" }
    );
}
