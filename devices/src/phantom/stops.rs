//! End stops of the simulated arm: the workspace box and the arm's reach.
//!
//! A stiff spring–damper acts on the tip once it leaves the workspace box or
//! comes within 3 % of full reach (the straight-arm singularity), standing in
//! for the mechanical stops of the real arm. Passive by construction.
//!
//! # Real-time
//! A few comparisons and one square root: no allocation, constant time.

use nalgebra::Vector3;

use super::PhantomModel;

/// End-stop spring, N/m: stiff enough to feel like a hard stop, soft enough for
/// the 4×-rate sub-steps (ω·h ≈ 0.2 at 1 kHz with the Omni's mass).
const STOP_STIFFNESS_N_PER_M: f64 = 20_000.0;
/// End-stop damper, N·s/m.
const STOP_DAMPING_N_S_PER_M: f64 = 20.0;
/// Fraction of full reach (l1 + l2) where the reach stop begins.
const REACH_STOP_FRACTION: f64 = 0.97;

pub(crate) fn end_stop_force(
    model: &PhantomModel,
    p: &Vector3<f64>,
    v: &Vector3<f64>,
) -> Vector3<f64> {
    let half = &model.workspace_half_extent_m;
    let mut f = Vector3::zeros();
    for i in 0..3 {
        let excess = p[i].abs() - half[i];
        if excess > 0.0 {
            f[i] = -p[i].signum() * STOP_STIFFNESS_N_PER_M * excess - STOP_DAMPING_N_S_PER_M * v[i];
        }
    }
    let g = &model.geometry;
    let reach = g.reach(p);
    let limit = REACH_STOP_FRACTION * (g.link1_m + g.link2_m);
    if reach > limit {
        let shoulder = Vector3::new(0.0, g.link2_m, -g.link1_m);
        let n = (p - shoulder) / reach;
        f -= n * (STOP_STIFFNESS_N_PER_M * (reach - limit) + STOP_DAMPING_N_S_PER_M * n.dot(v));
    }
    f
}
