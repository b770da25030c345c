//! Every constraint kind's analytic Jacobian (design-variable and finger
//! columns included) against central finite differences at random states with
//! non-unit quaternions. Fixed seed; see `fd.rs` for the tolerance.

use haptloop_solver::{ConstraintKind, Model};
use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed, TestRunner};

use crate::common::{self, state, state_len};
use crate::fd::{analytic, check_against_fd};

const CASES: u32 = 48;

fn run(model: Model, must_have: &[ConstraintKind]) {
    for kind in must_have {
        assert!(
            model.constraints().iter().any(|c| c.kind == *kind),
            "test model lacks a {kind} constraint"
        );
    }
    let config = Config {
        cases: CASES,
        rng_seed: RngSeed::Fixed(0x5eed_4a7c),
        failure_persistence: None,
        ..Config::default()
    };
    let n = state_len(&model);
    TestRunner::new(config)
        .run(&prop::collection::vec(-1.0f64..1.0, n), |u| {
            let (q, targets) = state(&model, &u);
            let a = analytic(&model, &q, &targets);
            check_against_fd(&model, &q, &targets, &a).map_err(TestCaseError::fail)
        })
        .unwrap();
}

macro_rules! fd_test {
    ($name:ident, $kinds:expr) => {
        #[test]
        fn $name() {
            run(common::$name(), &$kinds);
        }
    };
}

use ConstraintKind as C;
fd_test!(spherical, [C::Spherical, C::QuaternionNorm]);
fd_test!(perpendicular, [C::Perpendicular]);
fd_test!(universal, [C::Universal]);
fd_test!(revolute, [C::Revolute, C::RevoluteLimit]);
fd_test!(prismatic, [C::Prismatic, C::PrismaticLimit]);
fd_test!(fixed, [C::Fixed]);
fd_test!(distance, [C::Distance, C::DistanceLimit]);
fd_test!(point_on_plane, [C::PointOnPlane]);
fd_test!(fingers, [C::PointFinger, C::RigidFinger]);
fd_test!(point_plane_inequalities, [C::PointPlaneInequality]);
fd_test!(gears, [C::Gear, C::RackPinion]);
fd_test!(
    free_positions,
    [
        C::Spherical,
        C::Revolute,
        C::Distance,
        C::Prismatic,
        C::DesignBound,
        C::DesignPin
    ]
);

/// The checker itself can fail: corrupting one analytic entry by 1e-4 is caught.
#[test]
fn checker_detects_a_wrong_entry() {
    let model = common::revolute();
    let u: Vec<f64> = (0..state_len(&model))
        .map(|k| ((k * 37 % 19) as f64 / 9.5) - 1.0)
        .collect();
    let (q, targets) = state(&model, &u);
    let mut a = analytic(&model, &q, &targets);
    check_against_fd(&model, &q, &targets, &a).expect("unmodified Jacobian passes");
    let row = model.constraints()[0].rows.start + 3;
    let col = model
        .layout()
        .body_offset(model.body_id("b").unwrap())
        .unwrap()
        + 4;
    a[(row, col)] += 1e-4;
    assert!(check_against_fd(&model, &q, &targets, &a).is_err());
}
