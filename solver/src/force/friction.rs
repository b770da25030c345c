//! Coulomb friction at contacts, as the force solve sees it.
//!
//! A fingertip pair with friction has two stick rows (see
//! `constraint/witness/friction.rs`). While they **stick** they are joint
//! rows of Eq. 7 like any other, and their multipliers λ_t (newtons) are the
//! friction force the contact must supply. The Coulomb cone
//! |λ_t| ≤ μ f_n is checked after the solve; a pair outside it **slips**: its
//! rows are released for this tick (the solve runs again without them) and
//! the program re-anchors them under the fingertip. A slipping pair tries to
//! stick again once its tangential slip per tick falls below
//! [`STICK_SPEED_M_S`] × dt.
//!
//! **Normal force.** The fingertip is driven by its device through a stiff
//! finger row, so the row's own multiplier measures the position servo, not
//! the user's grip. What the user presses with is the virtual coupling's
//! force, k (p − target) (the force rendered back to them), so
//! f_n = max(0, n · k (p − target)) with n the contact normal out of the
//! touched body: a pinch lifts an object when both fingertips press hard
//! enough for μ f_n to carry its share of the weight, as a real one does.

use nalgebra::Vector3;

use crate::constraint::witness::Witness;
use crate::{FingerTarget, Model};

/// Below this tangential speed (m/s) a slipping contact sticks again.
pub const STICK_SPEED_M_S: f64 = 2e-3;

/// One fingertip pair with friction rows.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct FrictionPair {
    /// The two stick rows (model row indices).
    pub rows: [usize; 2],
    /// The pair's witness (normal) rows: first, one past the last.
    pub normal_rows: [usize; 2],
    /// Their witness-table slots.
    pub slots: [usize; 2],
    /// The fingertip's finger (`None`: two bodies).
    pub finger: Option<usize>,
    /// Coulomb μ.
    pub mu: f64,
    /// The touched body (end 1).
    pub body: crate::BodyId,
    /// Two bodies' twist row and its slot (`constraint/witness/friction.rs`).
    pub twist: Option<(usize, usize)>,
}

impl FrictionPair {
    /// Every stick row: the two tangent rows and the twist row if any.
    pub fn all_rows(&self) -> impl Iterator<Item = usize> + use<> {
        self.rows.into_iter().chain(self.twist.map(|t| t.0))
    }

    /// Their witness-table slots, in the same order.
    pub fn all_slots(&self) -> impl Iterator<Item = usize> + use<> {
        self.slots.into_iter().chain(self.twist.map(|t| t.1))
    }
}

/// Every friction pair of `model`. Allocates.
pub(crate) fn pairs_of(model: &Model) -> Vec<FrictionPair> {
    model
        .contact()
        .pairs
        .iter()
        .filter_map(|p| {
            let f = p.friction?;
            let rows = model.constraints()[f.index()].rows.clone();
            let n_normal = model.constraints()[p.normal.index()].rows.len();
            let s0 = p.first_slot + n_normal;
            Some(FrictionPair {
                normal_rows: {
                    let r = &model.constraints()[p.normal.index()].rows;
                    [r.start, r.end]
                },
                rows: [rows.start, rows.start + 1],
                slots: [s0, s0 + 1],
                finger: p.finger.map(|f| f.index()),
                mu: p.mu,
                body: p.bodies[1],
                twist: (rows.len() > 2).then_some((rows.start + 2, s0 + 2)),
            })
        })
        .collect()
}

/// The contact normal (world, out of the touched body) of a friction pair
/// whose stick rows are set in `witnesses`; `None` while they are off.
pub(crate) fn normal(
    model: &Model,
    q: &[f64],
    witnesses: &[Witness],
    p: &FrictionPair,
) -> Option<Vector3<f64>> {
    let (Witness::Plane(t1), Witness::Plane(t2)) = (witnesses[p.slots[0]], witnesses[p.slots[1]])
    else {
        return None;
    };
    let frame = model.body_frame(q, p.body)?;
    Some(frame.rot * t1.normal.cross(&t2.normal))
}

/// The grip f_n (newtons) the user applies at a friction pair: the virtual
/// coupling's force along the contact normal, never negative.
pub(crate) fn grip(
    model: &Model,
    q: &[f64],
    witnesses: &[Witness],
    targets: &[FingerTarget],
    stiffness_n_per_m: f64,
    p: &FrictionPair,
) -> f64 {
    let Some(finger) = p.finger else {
        return 0.0;
    };
    let (Some(n), Some(tip), Some(t)) = (
        normal(model, q, witnesses, p),
        model.finger_point(q, crate::FingerId(finger as u32)),
        targets.get(finger),
    ) else {
        return 0.0;
    };
    (n.dot(&(tip - t.position_m)) * stiffness_n_per_m).max(0.0)
}
