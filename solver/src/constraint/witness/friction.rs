//! Friction stick rows at a finger contact. A fingertip (a ball: its centre
//! P on end 0) touching body B at the point P₀ of B (frame of B) with contact
//! normal n gets two rows
//!
//! ```text
//! C_k = t_k·(P − P₀) = 0,   k = 1, 2,   t_1, t_2 ⊥ n unit, fixed in B's frame
//! ```
//!
//! zero where they are set (P − P₀ is along n): while the contact sticks they
//! hold the fingertip's tangential position on B (static friction, no creep);
//! when the Coulomb cone |λ_t| ≤ μ f_n is violated the fast loop releases
//! them (slip) and re-anchors P₀ under the fingertip. The rows are
//! [`PlaneWitness`]es with `origin` [`WitnessType::Friction`]; the ball's
//! centre is its body origin, so rolling the fingertip does not move P.
//!
//! Two bodies touching over a patch get a third row, the **twist** row
//! ([`twist_row`]): the second row again, at a point an arm's length along
//! the first tangent. The three hold the patch's relative twist about the
//! normal as well (a point contact would let a stuck box pivot about it).

use nalgebra::Vector3;

use super::{PlaneWitness, WitnessType};

/// The two stick rows of a contact with normal `normal` (B's frame) holding
/// A's point `anchor_a` (A's frame; a fingertip's centre is its origin) at
/// `contact_b` (B's frame).
pub fn stick_rows(
    anchor_a: Vector3<f64>,
    contact_b: Vector3<f64>,
    normal: Vector3<f64>,
) -> [PlaneWitness; 2] {
    let n = normal.normalize();
    let seed = if n.x.abs() < 0.9 {
        Vector3::x()
    } else {
        Vector3::y()
    };
    let t1 = n.cross(&seed).normalize();
    let t2 = n.cross(&t1);
    [t1, t2].map(|t| PlaneWitness {
        origin: WitnessType::Friction,
        features: [0, 0],
        point_end: 0,
        point: anchor_a,
        plane_point: contact_b,
        normal: t,
        margin: 0.0,
    })
}

/// The twist row of two bodies' stick rows `rows` (A's point and B's point
/// at the contact's centre): the second row's tangent, at the point
/// `arm_a` / `arm_b` (the same world point, `arm` along the first tangent
/// from the centre, in A's and B's frames).
pub fn twist_row(
    rows: &[PlaneWitness; 2],
    arm_a: Vector3<f64>,
    arm_b: Vector3<f64>,
) -> PlaneWitness {
    PlaneWitness {
        point: arm_a,
        plane_point: arm_b,
        ..rows[1]
    }
}
