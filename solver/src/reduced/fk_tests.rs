//! Forward kinematics (`kinematics::displace`) keeps every tree joint for a
//! finite motion, not only to first order: at θ of a few hundredths of a
//! radian on every joint coordinate, each tree joint's rows from an
//! independent augmented evaluation stay at the round-off of the start.
//! The chain's tree has universals whose child is end i (the branch from
//! the second fixed point) and both orders of a universal's axes; before
//! issue 23's chain fix they drifted by the second order of the motion.

use super::{JointSpace, displace};

/// Largest |C| over `rows` at q.
fn worst(model: &crate::Model, q: &[f64], rows: &[usize]) -> f64 {
    let ev = super::tests::evaluation(model, q);
    rows.iter()
        .map(|&r| ev.values()[r].abs())
        .fold(0.0, f64::max)
}

#[test]
fn forward_kinematics_keeps_every_tree_joint() {
    for name in ["chain", "four-bar", "bennett", "peaucellier"] {
        let (model, q) = super::tests::state(name, 0);
        let ev = super::tests::evaluation(&model, &q);
        let mut js = JointSpace::new(&model, &q, &ev).unwrap();
        js.kin.update(&model, &js.tree, &q).unwrap();
        let n = js.tree.dofs();
        let theta: Vec<f64> = (0..n)
            .map(|d| 0.03 * (1.3 * d as f64 + 0.4).sin())
            .collect();
        let mut out = q.clone();
        displace(&model, &js.tree, &js.kin, &q, &theta, &mut out);
        let tree = js.tree.tree_rows().to_vec();
        let (before, after) = (worst(&model, &q, &tree), worst(&model, &out, &tree));
        let norms = worst(&model, &out, js.tree.norm_rows());
        let moved = q
            .iter()
            .zip(&out)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(moved > 1e-3, "{name}: it moved {moved:.2e}");
        assert!(
            after < 4.0 * before + 1e-13,
            "{name}: tree rows {after:.2e} from {before:.2e}"
        );
        assert!(norms < 1e-13, "{name}: quaternion norms {norms:.2e}");
    }
}
