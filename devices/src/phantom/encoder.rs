//! Encoder quantisation: joint angle ↔ integer counts.
//!
//! A count is `round(θ / Δ)` with Δ = 2π / counts-per-revolution, so the angle
//! recovered from a count, `count · Δ`, is within half a count (Δ/2) of the true
//! angle. Counts are zero at the home pose (calibrated arm).
//!
//! # Real-time
//! Pure arithmetic on stack values: no allocation, constant time.

use nalgebra::Vector3;

use crate::device::ARM_JOINTS;

/// Quantises joint angles the way an incremental encoder behind a capstan
/// reduction does (after homing).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Encoder {
    radians_per_count: f64,
}

impl Encoder {
    /// An encoder with `counts_per_rev` counts per joint revolution (> 0).
    pub fn new(counts_per_rev: u32) -> Self {
        Self {
            radians_per_count: std::f64::consts::TAU / f64::from(counts_per_rev.max(1)),
        }
    }

    /// Angle of one count, radians.
    pub fn radians_per_count(&self) -> f64 {
        self.radians_per_count
    }

    /// Counts for true joint angles (radians). Non-finite angles give count 0;
    /// angles beyond ±i32 range saturate (impossible for a real arm).
    pub fn counts(&self, theta_rad: &Vector3<f64>) -> [i32; ARM_JOINTS] {
        let mut c = [0i32; ARM_JOINTS];
        for (j, out) in c.iter_mut().enumerate() {
            let v = (theta_rad[j] / self.radians_per_count).round();
            // `as` saturates and maps NaN to 0.
            *out = v as i32;
        }
        c
    }

    /// Joint angles (radians) read back from counts.
    pub fn angles(&self, counts: &[i32; ARM_JOINTS]) -> Vector3<f64> {
        Vector3::new(
            f64::from(counts[0]) * self.radians_per_count,
            f64::from(counts[1]) * self.radians_per_count,
            f64::from(counts[2]) * self.radians_per_count,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::phantom::{OMNI, PREMIUM_1_5};
    use proptest::prelude::*;

    proptest! {
        #![proptest_config(ProptestConfig { cases: 128, rng_seed: proptest::test_runner::RngSeed::Fixed(11), ..ProptestConfig::default() })]

        /// Joint error ≤ Δ/2 and tip error ≤ Σ_j |J_j|·Δ/2 (first order) plus the
        /// second-order remainder ≤ ½·(l1+l2)·(3Δ/2)² (< 1e-9 m for these models).
        #[test]
        fn quantisation_error_bounded_by_half_a_count_at_the_tip(
            a in -0.9..0.9f64, b in -0.6..0.8f64, c in -0.5..0.7f64
        ) {
            for m in [PREMIUM_1_5, OMNI] {
                let enc = Encoder::new(m.counts_per_rev);
                let theta = Vector3::new(a, b, c);
                let back = enc.angles(&enc.counts(&theta));
                let half = enc.radians_per_count() / 2.0;
                for j in 0..3 {
                    prop_assert!((back[j] - theta[j]).abs() <= half * (1.0 + 1e-9));
                }
                let g = m.geometry;
                let jac = g.jacobian(&theta);
                let bound: f64 = (0..3).map(|j| jac.column(j).norm() * half).sum::<f64>()
                    + 0.5 * (g.link1_m + g.link2_m) * (3.0 * half).powi(2);
                let err = (g.forward(&back) - g.forward(&theta)).norm();
                prop_assert!(err <= bound, "{} err {err} > bound {bound}", m.name);
                // And the bound itself is of the order of the published resolution.
                prop_assert!(bound < 2.0 * m.nominal_resolution_m());
            }
        }
    }
}
