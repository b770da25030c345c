//! The joint-coordinate tick (`reduced::JointTick`, measurement only)
//! allocates nothing over 100 ticks (counting global allocator).

use std::sync::Arc;

use haptloop_rt::alloc::{count, is_installed};
use haptloop_solver::SolverSettings;
use haptloop_solver::reduced::JointTick;
use nalgebra::Vector3;

#[test]
fn the_joint_tick_allocates_nothing() {
    assert!(is_installed());
    for name in ["four-bar", "bennett", "peaucellier"] {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../scenes")
            .join(format!("{name}.toml"));
        let compiled = haptloop_solver::scene::load(&path)
            .unwrap()
            .compile()
            .unwrap();
        let settings = super::common::step_and_iterations(
            &compiled.settings,
            SolverSettings::default().coordinates,
        );
        let model = Arc::new(compiled.model);
        let t0 = model.initial_targets();
        let mut jt = JointTick::new(model.clone(), settings, model.q0(), &t0).unwrap();
        let mut t = t0.clone();
        let (result, stats) = count(|| {
            for k in 0..100 {
                let a = 2.0 * std::f64::consts::PI * k as f64 / 500.0;
                t[0].position_m =
                    t0[0].position_m + Vector3::new(a.cos() - 1.0, a.sin(), 0.0) * 0.002;
                jt.tick(&t, 1e-3)?;
            }
            Ok::<(), haptloop_solver::reduced::ReducedError>(())
        });
        result.unwrap();
        assert_eq!(stats.total(), 0, "{name}: allocations {stats:?}");
        // It ticked: the finger feels the linkage's weight.
        assert!(jt.outputs[0].force_n.norm() > 1e-3, "{name}");
    }
}
