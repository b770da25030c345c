//! Objectives in the fast loop: their gradient shifts the least-astonishment
//! anchor q₀ of each tick (DESIGN §4.3: "design objectives plug in as f").
//!
//! Both update rules minimise, per tick, ½ ‖q − q₀‖² in their metric (the
//! projected rule: the mass matrix M̂, with the design metric w_D on design
//! columns; the gradient rule: W scaled by the mean mass m̄) subject to the
//! joints. Adding the objectives' energy E(q) = Σ_k (w_k / w_la) m̄ F_k(q),
//! linearised at the tick's start q_s, gives the same problem with
//!
//! ```text
//! q₀ ← q₀ − M̂⁻¹ ∇E(q_s)
//! ```
//!
//! so objectives need nothing new from either rule or from contact: the
//! projection keeps the joints (never fought: an objective's pull is
//! projected onto the mechanism's free motions like the user's), and
//! inertial prediction, contacts and fingers keep working on the shifted q₀.
//! With E evaluated once per tick this is one projected gradient step of E
//! per tick.
//!
//! **A bounded pull.** The shift is scaled down, keeping its direction, so
//! no coordinate moves more than [`OBJECTIVE_STEP_LIMIT_M`] (scaled metres:
//! Euler parameters times L) per tick; a non-finite gradient (never produced
//! by the objectives' guards, but checked) shifts nothing. A dexterity term
//! near a singular pose or an obstacle term at its distance floor thus pulls
//! at most 0.1 m/s at 1 kHz.
//!
//! # Real-time
//! No allocation: the scratch is sized by `Program::new`. One objective
//! gradient (O(bodies + terms)), one M̂⁻¹ product, O(coordinates).

use super::Program;
use crate::UpdateRule;
use std::sync::Arc;

use crate::objective::{ObjectiveEval, Objectives};

/// Largest objective-induced move of any coordinate per tick, scaled metres.
pub const OBJECTIVE_STEP_LIMIT_M: f64 = 1e-4;

/// The scratch of the objectives' pull.
#[derive(Debug, Clone)]
pub(super) struct ObjectivePull {
    eval: ObjectiveEval,
    grad: Vec<f64>,
    shift: Vec<f64>,
    /// Reported value of each term after the last successful tick.
    reports: Vec<f64>,
    /// m̄ / w_la: energy per m² of F at weight 1, kg.
    energy_kg: f64,
    /// The design columns' metric, kg.
    design_kg: f64,
    /// The largest scaled coordinate change the last pull asked for, m
    /// (after the cap).
    last_step_m: f64,
    /// The shift applied to the columns of auxiliary blocks with rest 0
    /// (flexible deformations, the tail of q) at the last tick.
    static_shift: Vec<f64>,
}

impl ObjectivePull {
    /// The objectives' pull on a flexible body's deformation: with metric
    /// K_f and rest 0, q₀ = −K_f⁻¹ ∇E is the static shape of U + E
    /// linearised (the whole equilibrium in one tick, not a step per tick).
    /// So that it is approached like a motion, never jumped to, the shift
    /// moves by at most [`OBJECTIVE_STEP_LIMIT_M`] per tick toward it, in
    /// its direction; `goal` is q₀ on those columns (0 before the call).
    fn static_rest(&mut self, goal: &mut [f64]) {
        let moving = self.shift.len() - self.static_shift.len();
        let target = &self.shift[moving..];
        let change = target
            .iter()
            .zip(&self.static_shift)
            .map(|(t, p)| (t - p).abs())
            .fold(0.0, |a: f64, v| if v > a || v.is_nan() { v } else { a });
        if !change.is_finite() {
            return;
        }
        let f = if change > 0.0 {
            (OBJECTIVE_STEP_LIMIT_M / change).min(1.0)
        } else {
            0.0
        };
        for ((p, t), g) in self.static_shift.iter_mut().zip(target).zip(goal) {
            *p += f * (t - *p);
            *g -= *p;
        }
        self.last_step_m = self.last_step_m.max(f * change);
    }
}

impl ObjectivePull {
    /// For a program of `model` with mean body mass `mean_mass_kg`; `None`
    /// when the model has no design objective. Allocates.
    pub fn new(
        model: &crate::Model,
        objectives: &Arc<Objectives>,
        mean_mass_kg: f64,
    ) -> Option<Self> {
        let o = objectives;
        if o.is_empty() {
            return None;
        }
        let n = model.n_coords();
        Some(Self {
            eval: objectives.evaluation(model),
            grad: vec![0.0; n],
            shift: vec![0.0; n],
            reports: vec![f64::NAN; o.terms.len()],
            energy_kg: mean_mass_kg / o.least_astonishment,
            design_kg: design_metric_kg(objectives, mean_mass_kg),
            last_step_m: 0.0,
            static_shift: vec![0.0; static_columns(model)],
        })
    }
}

/// The number of trailing columns of q in auxiliary blocks whose rest is 0
/// (flexible deformations; `model::auxiliary`). They are the last blocks:
/// every flexible block precedes no other kind (checked here).
fn static_columns(model: &crate::Model) -> usize {
    let blocks = model.layout().aux_blocks();
    let tail = blocks
        .iter()
        .rev()
        .take_while(|b| b.rest == crate::model::Rest::Zero)
        .map(|b| b.width)
        .sum();
    debug_assert_eq!(
        tail,
        blocks
            .iter()
            .filter(|b| b.rest == crate::model::Rest::Zero)
            .map(|b| b.width)
            .sum::<usize>(),
        "rest-0 blocks must be the last ones"
    );
    tail
}

/// The least-astonishment metric of one design column, kg: the mean body
/// mass times the scene's `design_weight`.
pub(super) fn design_metric_kg(objectives: &Objectives, mean_mass_kg: f64) -> f64 {
    mean_mass_kg * objectives.design_weight
}

impl Program {
    /// Shifts this tick's q₀ by the objectives' pull (see the module docs).
    pub(super) fn pull_objectives(&mut self) {
        let Some(o) = &mut self.objective else {
            return;
        };
        o.last_step_m = 0.0;
        o.grad.fill(0.0);
        if o.eval.gradient(&self.model, &self.q, &mut o.grad).is_err() {
            return;
        }
        let design = self.model.layout().design_range();
        match self.settings.update {
            UpdateRule::Projected => {
                self.feedback.apply_inverse_mass(&o.grad, &mut o.shift);
                for (s, g) in o.shift[design.clone()]
                    .iter_mut()
                    .zip(&o.grad[design.clone()])
                {
                    *s = g / o.design_kg;
                }
                let k = o.energy_kg;
                o.shift.iter_mut().for_each(|s| *s *= k);
            }
            UpdateRule::Gradient => {
                // W⁻¹ ∇E / m̄ with E = (m̄ / w_la) Σ w F.
                let k = o.energy_kg / self.feedback.mean_mass_kg();
                for ((s, g), w) in o
                    .shift
                    .iter_mut()
                    .zip(&o.grad)
                    .zip(&self.scaling.inv_metric)
                {
                    *s = k * w * g;
                }
            }
        }
        // Switched-off design variables stay put.
        for (s, &off) in o.shift[design].iter_mut().zip(&self.design_off) {
            if off {
                *s = 0.0;
            }
        }
        // Flexible deformations (rest 0) are static: their shift is a
        // shape, not a step, and is rate-limited on its own (`static_rest`).
        let n_static = o.static_shift.len();
        let moving = o.shift.len() - n_static;
        let size = o.shift[..moving]
            .iter()
            .zip(&self.scaling.sqrt_metric)
            .map(|(s, w)| (s * w).abs())
            .fold(0.0, |a: f64, v| if v > a || v.is_nan() { v } else { a });
        if n_static > 0 {
            o.static_rest(&mut self.q_goal[moving..]);
        }
        if !size.is_finite() || size == 0.0 {
            return;
        }
        let f = (OBJECTIVE_STEP_LIMIT_M / size).min(1.0);
        for (g, s) in self.q_goal[..moving].iter_mut().zip(&o.shift) {
            *g -= f * s;
        }
        o.last_step_m = f * size;
    }

    /// Each term's reported value at the tick's final q.
    pub(super) fn measure_objectives(&mut self) {
        if let Some(o) = &mut self.objective
            && o.eval
                .reports(&self.model, &self.q, &mut o.reports)
                .is_err()
        {
            o.reports.fill(f64::NAN);
        }
    }

    /// The reported value of each of the model's objectives
    /// ([`Objectives::terms`](crate::Objectives::terms)) after the last
    /// successful tick (NaN before the first; empty without objectives).
    pub fn objective_reports(&self) -> &[f64] {
        self.objective.as_ref().map_or(&[], |o| &o.reports)
    }

    /// The objectives' pull on flexible deformations at the last tick (the
    /// state `ObjectivePull::static_rest` rate-limits; empty without).
    pub(super) fn static_shift(&self) -> &[f64] {
        self.objective.as_ref().map_or(&[], |o| &o.static_shift)
    }

    /// Replaces that state (a replayed tick; ignored on a length mismatch).
    pub(super) fn set_static_shift(&mut self, s: &[f64]) {
        if let Some(o) = &mut self.objective
            && o.static_shift.len() == s.len()
        {
            o.static_shift.copy_from_slice(s);
        }
    }

    /// The largest scaled coordinate change the objectives asked of the last
    /// tick (after the [`OBJECTIVE_STEP_LIMIT_M`] cap), metres.
    pub fn objective_step_m(&self) -> f64 {
        self.objective.as_ref().map_or(0.0, |o| o.last_step_m)
    }
}
