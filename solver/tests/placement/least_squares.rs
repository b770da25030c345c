//! Conflicting goals: two fingers pull a rigid rod apart. The damped solve
//! returns the finite least-squares compromise with status `LeastSquares`.

use haptloop_solver::{
    BodySpec, FingerId, FingerSpec, FingerTarget, Model, ModelBuilder, Placement, PlacementOptions,
    SolveStatus,
};
use nalgebra::Vector3;

use super::common::finite;

/// A free 10 cm rod along x held by a point finger at each end.
fn rod() -> Model {
    let mut b = ModelBuilder::new();
    b.body(BodySpec::new("rod"));
    b.finger(FingerSpec::point("left", "rod", [-0.05, 0.0, 0.0]));
    b.finger(FingerSpec::point("right", "rod", [0.05, 0.0, 0.0]));
    b.build().unwrap()
}

#[test]
fn two_fingers_pulling_a_rod_apart_meet_half_way() {
    let model = rod();
    let targets = [
        FingerTarget::at(Vector3::new(-0.08, 0.0, 0.0)),
        FingerTarget::at(Vector3::new(0.08, 0.0, 0.0)),
    ];
    let mut p = Placement::analyze(&model, &PlacementOptions::default()).unwrap();
    let mut q = model.q0().to_vec();
    let info = p.solve(&model, &mut q, model.q0(), &targets).unwrap();
    assert_eq!(info.status, SolveStatus::LeastSquares, "{info:?}");
    assert!(finite(&q) && finite(p.multipliers()));
    assert!(info.residual.is_finite() && info.step.is_finite());
    // Each finger misses its target by (16 − 10)/2 = 3 cm, symmetrically.
    for (k, t) in targets.iter().enumerate() {
        let miss = (model.finger_point(&q, FingerId(k as u32)).unwrap() - t.position_m).norm();
        assert!((miss - 0.03).abs() <= 1e-6, "finger {k} misses by {miss}");
    }
    assert!(
        (info.residual - 0.03 * 2f64.sqrt()).abs() <= 1e-6,
        "{info:?}"
    );
    assert!(
        q[..3].iter().all(|x| x.abs() <= 1e-6),
        "centred: {:?}",
        &q[..3]
    );
}

#[test]
fn conflicting_fingers_from_a_skewed_start_stay_finite() {
    let model = rod();
    let targets = [
        FingerTarget::at(Vector3::new(-0.2, 0.03, 0.01)),
        FingerTarget::at(Vector3::new(0.1, -0.05, 0.02)),
    ];
    let mut p = Placement::analyze(&model, &PlacementOptions::default()).unwrap();
    let mut q = model.q0().to_vec();
    q[4] = 0.3; // a 35° turn, unnormalised quaternion
    let info = p.solve(&model, &mut q, model.q0(), &targets).unwrap();
    assert_eq!(info.status, SolveStatus::LeastSquares, "{info:?}");
    assert!(finite(&q) && finite(p.multipliers()));
    let span = (targets[1].position_m - targets[0].position_m).norm();
    let expect = (span - 0.1) / 2.0;
    for (k, t) in targets.iter().enumerate() {
        let miss = (model.finger_point(&q, FingerId(k as u32)).unwrap() - t.position_m).norm();
        assert!(
            (miss - expect).abs() <= 1e-6,
            "finger {k} misses by {miss}, not {expect}"
        );
    }
}
