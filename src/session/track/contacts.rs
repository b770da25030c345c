//! The contact points a viewer draws: each witness primitive of each
//! tracked pair that is within [`ACTIVE_GAP_M`] of touching, with its world
//! point and the normal along which body A separates from body B.
//!
//! The normal is the gradient of the primitive's row value with respect to
//! a translation of body A (central differences, 1 µm): the same for every
//! witness kind (vertex–face, vertex–edge, vertex–vertex, edge–edge), from
//! the very function the solver's rows are evaluated with, so a drawn
//! normal is the direction the contact force acts in.

use haptloop_solver::contact::ContactManager;
use haptloop_solver::geometry::Pose3;
use haptloop_solver::geometry::primitives::value_at;
use nalgebra::Vector3;

/// A primitive whose row value (gap) is at most this is drawn as a
/// contact, m: touching, within the solver's tolerances.
pub const ACTIVE_GAP_M: f64 = 5e-4;

/// One contact point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactPoint {
    /// Model body indices (A, B).
    pub bodies: [u32; 2],
    /// The witness point, m, world frame.
    pub point_m: [f64; 3],
    /// Unit normal, world frame: the direction A separates from B along.
    pub normal: [f64; 3],
    /// The row value: distance (negative: penetration), m.
    pub gap_m: f64,
}

/// The active contact points of the manager's last cycle, appended to `out`.
pub fn contact_points(manager: &ContactManager, out: &mut Vec<ContactPoint>) {
    let poses = manager.poses();
    let set = manager.active_set();
    for pair in set.pairs() {
        let [a, b] = pair.bodies;
        let (Some(pa), Some(pb)) = (poses.get(a as usize), poses.get(b as usize)) else {
            continue;
        };
        for w in set.witnesses(pair.bodies).iter().filter(|w| w.is_on()) {
            let (gap, point) = value_at(w, pa, pb);
            if gap.is_nan() || gap > ACTIVE_GAP_M {
                continue;
            }
            let Some(n) = normal(w, pa, pb) else { continue };
            out.push(ContactPoint {
                bodies: pair.bodies,
                point_m: point.into(),
                normal: n.into(),
                gap_m: gap,
            });
        }
    }
}

/// ∂(row value)/∂(translation of A), normalised.
fn normal(
    w: &haptloop_solver::constraint::witness::Witness,
    pa: &Pose3,
    pb: &Pose3,
) -> Option<Vector3<f64>> {
    let h = 1e-6;
    let mut g = Vector3::zeros();
    for k in 0..3 {
        let mut plus = *pa;
        let mut minus = *pa;
        plus.r[k] += h;
        minus.r[k] -= h;
        g[k] = (value_at(w, &plus, pb).0 - value_at(w, &minus, pb).0) / (2.0 * h);
    }
    let n = g.norm();
    (n.is_finite() && n > 1e-9).then(|| g / n)
}
