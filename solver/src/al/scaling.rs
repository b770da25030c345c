//! The K rule: per-row gains and per-column metric that put every row and every
//! column in metres, and the stability bound that sets h.
//!
//! With L the length scale ([`SolverSettings::length_scale_m`], by default the
//! model's largest lever arm):
//!
//! | row unit | ℓ_i | K_i | k₂_i |
//! |---|---|---|---|
//! | [`RowUnit::Length`] (m) | 1 | K | k₂ |
//! | [`RowUnit::Angle`] (rad) | L | K L² | k₂ L² |
//! | [`RowUnit::Dimensionless`] (eᵀe − 1) | L | K L² | k₂ L² |
//! | finger rows (any unit) | as above | × `finger_weight` | 0 (no multiplier) |
//! | redundant rows ([`Scaling::mask`]) | as above | 0 | 0 |
//!
//! and column c of q has metric weight W_c = 1 (r, design variables: metres) or
//! L² (Euler parameters: a change δe turns a point at lever L by about 2 L δe).
//! The update is Eq. 3 in the scaled coordinates q̃ = W^{1/2} q with scaled
//! rows ℓ_i C_i, i.e. Δq = −W⁻¹(f_qᵀ + C_qᵀ(λ + K C)) in q with the objective
//! ½‖q − q₀‖²_W. Why: an angle error θ displaces points at the lever arm by
//! L θ, so K L² θ² is the same penalty per metre as a position row; and
//! without the column metric the Euler-parameter columns (dimensionless, with
//! gradients ~2 L in position rows) converge at a different rate from r.
//!
//! Stability: the linearised iteration contracts every mode if
//! h (1 + K σ_max) < 2, σ_max the largest eigenvalue of D C_q W⁻¹ C_qᵀ D with
//! D = diag(ℓ_i √(K_i / (K ℓ_i²)))—the rows' relative weights. With the
//! multiplier integrated from the newest C (see [`super::update`]), a mode with
//! a = h K σ and β = h k₂ σ is stable iff 0 < a < 2 and 0 < β < 4 − 2a.

use crate::al::SolverSettings;
use crate::{ConstraintKind, Jacobian, Model, RowUnit, Sense};

/// What a row does in the update.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Role {
    /// C = 0 with a multiplier.
    Equality,
    /// A finger row: penalty only (a weighted objective term, no multiplier).
    Finger,
    /// A contact finger's row with inertial motion on: the virtual coupling
    /// (spring k, damper c) between the fingertip proxy and the device
    /// target. The projected step weighs it by k dt² + c dt (the implicit
    /// spring over one tick, not a stiff penalty), and the force solve takes
    /// its force as known: k (p − t) + c (ṗ − ṫ), felt by the user and
    /// pushing the fingertip, so the contact multipliers come out physical.
    Coupling,
    /// C ≥ 0 with a projected multiplier ν ≥ 0 (joint limits).
    Inequality,
    /// A contact witness row: C ≥ 0 like [`Role::Inequality`], but its
    /// violation is a penetration (reported apart from the joints').
    Contact,
    /// A friction stick row: C = 0 while its contact sticks, else free. Only
    /// the projected rule and the force solve use it (its gains are 0).
    Friction,
    /// A design-variable bound (C ≥ 0) on one design column, touching no
    /// body: the gradient rule treats it like [`Role::Inequality`]; Eq. 7
    /// never sees it and the projected rule enforces it as a box on its
    /// design step.
    DesignBound,
    /// A design-variable component held at lo = hi (C = 0), touching no
    /// body: the gradient rule treats it like [`Role::Equality`]; the
    /// projected rule keeps the component where it is.
    DesignPin,
    /// A row found linearly dependent on the kept rows at `Program::new`
    /// (`force::redundancy`): evaluated and its violation reported, but it
    /// takes part in no update and no force solve (gain 0, multiplier 0).
    Redundant,
}

/// Per-row gains and per-column metric of one model under one settings.
#[derive(Debug, Clone)]
pub(crate) struct Scaling {
    /// L, metres.
    pub length_m: f64,
    pub role: Vec<Role>,
    /// ℓ_i: metres per unit of row i.
    pub ell: Vec<f64>,
    /// K_i.
    pub penalty: Vec<f64>,
    /// k₂_i (0 for finger rows).
    pub integral: Vec<f64>,
    /// 1 / W_c per column.
    pub inv_metric: Vec<f64>,
    /// √W_c per column (1, or L on Euler parameters): a coordinate change
    /// times this is in metres.
    pub sqrt_metric: Vec<f64>,
    /// 1 / ℓ_i per row.
    pub inv_ell: Vec<f64>,
    /// d: the scaled finger error beyond which the pull stops growing, metres.
    pub finger_limit_m: f64,
}

impl Scaling {
    /// The gains of `model` under `s`. Allocates.
    pub fn new(model: &Model, s: &SolverSettings) -> Self {
        let l = s.length_scale_m.unwrap_or(model.characteristic_length_m());
        let n = model.n_rows();
        let (mut role, mut ell) = (Vec::with_capacity(n), Vec::with_capacity(n));
        let (mut penalty, mut integral) = (Vec::with_capacity(n), Vec::with_capacity(n));
        for row in model.rows() {
            let info = &model.constraints()[row.constraint.index()];
            let proxy = s.dynamics
                && s.update == crate::UpdateRule::Projected
                && info
                    .finger
                    .is_some_and(|f| model.fingers()[f.index()].tip.is_some());
            let r = match (info.finger.is_some(), row.sense) {
                (true, _) if proxy => Role::Coupling,
                _ if info.kind == ConstraintKind::DesignBound => Role::DesignBound,
                _ if info.kind == ConstraintKind::DesignPin => Role::DesignPin,
                (true, _) => Role::Finger,
                (false, Sense::Equality) => Role::Equality,
                (false, Sense::Inequality) if info.kind == ConstraintKind::Contact => Role::Contact,
                (false, Sense::Inequality) => Role::Inequality,
                (false, Sense::Friction) => Role::Friction,
            };
            let e = match row.unit {
                RowUnit::Length => 1.0,
                RowUnit::Angle | RowUnit::Dimensionless => l,
            };
            let w = if matches!(r, Role::Finger | Role::Coupling) {
                s.finger_weight
            } else {
                1.0
            };
            role.push(r);
            ell.push(e);
            let frozen = r == Role::Friction;
            penalty.push(if frozen { 0.0 } else { s.gain * w * e * e });
            integral.push(if matches!(r, Role::Finger | Role::Coupling) || frozen {
                0.0
            } else {
                s.multiplier_gain * e * e
            });
        }
        let mut inv_metric = vec![1.0; model.n_coords()];
        let mut sqrt_metric = vec![1.0; model.n_coords()];
        for (_, o) in model.layout().moving_bodies() {
            inv_metric[o + 3..o + 7].fill(1.0 / (l * l));
            sqrt_metric[o + 3..o + 7].fill(l);
        }
        Self {
            length_m: l,
            role,
            inv_ell: ell.iter().map(|e| 1.0 / e).collect(),
            ell,
            penalty,
            integral,
            inv_metric,
            sqrt_metric,
            finger_limit_m: s.finger_pull_limit_m,
        }
    }

    /// Masks `rows` (model row indices): their role becomes
    /// [`Role::Redundant`] and their gains 0, so they drop out of the gradient
    /// update, the projected step and the force solve alike.
    pub fn mask(&mut self, rows: &[usize]) {
        for &i in rows {
            self.role[i] = Role::Redundant;
            self.penalty[i] = 0.0;
            self.integral[i] = 0.0;
        }
    }

    /// σ_max of D C_q W⁻¹ C_qᵀ D (D² = K_i / K) at the Jacobian's current
    /// values, by 100 power iterations from a fixed start, plus 2 % for the
    /// estimate's shortfall. Allocates (construction only).
    pub fn sigma_max(&self, jac: &Jacobian, gain: f64) -> f64 {
        let d: Vec<f64> = self.penalty.iter().map(|k| (k / gain).sqrt()).collect();
        let mut v: Vec<f64> = (0..jac.nrows())
            .map(|i| 1.0 + (i % 7) as f64 * 0.1)
            .collect();
        let (mut x, mut y) = (vec![0.0; jac.ncols()], vec![0.0; jac.nrows()]);
        let mut sigma = 0.0;
        for _ in 0..100 {
            let norm = v.iter().map(|a| a * a).sum::<f64>().sqrt();
            if norm == 0.0 || !norm.is_finite() {
                break;
            }
            for (vi, di) in v.iter_mut().zip(&d) {
                *vi *= di / norm;
            }
            let _ = jac.mul_t_vec(&v, &mut x);
            for (xc, wc) in x.iter_mut().zip(&self.inv_metric) {
                *xc *= wc;
            }
            let _ = jac.mul_vec(&x, &mut y);
            // v was D u with |u| = 1: the Rayleigh quotient uᵀ(D J W⁻¹ Jᵀ D)u = xᵀ W x.
            sigma = x
                .iter()
                .zip(&self.inv_metric)
                .map(|(a, w)| a * a / w)
                .sum::<f64>();
            for ((vi, yi), di) in v.iter_mut().zip(&y).zip(&d) {
                *vi = yi * di;
            }
        }
        sigma * 1.02
    }
}

/// Checks the linearised stability conditions for the largest mode
/// (a = h K σ_max, β = h k₂ σ_max): `Err((a, β))` if violated.
pub(crate) fn check_stable(h: f64, gain: f64, k2: f64, sigma: f64) -> Result<(), (f64, f64)> {
    let (a, b) = (h * (1.0 + gain * sigma), h * k2 * sigma);
    if a < 2.0 && b < 4.0 - 2.0 * a {
        Ok(())
    } else {
        Err((a, b))
    }
}
