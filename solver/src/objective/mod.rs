//! Design objectives f of Nelson & Cohen §2–4 (minimise f subject to C = 0):
//! what the fast update optimises besides keeping the mechanism assembled.
//!
//! | file | kind | F (m²) | reported value |
//! |---|---|---|---|
//! | `dexterity.rs` | `dexterity`, Eq. 12–14 | −½ R² ln(det J̃J̃ᵀ + ε) | Eq. 14's f |
//! | `obstacle.rs` | `obstacle`, Eq. 15 | D² ‖½ (D/d − 1)²‖₄ | nearest distance, m |
//! | `straight_line.rs` | `straight_line`, Fig. 10 | ½ \|P(x − a)\|² | distance from the line, m |
//! | `joint_limit.rs` | `joint_limit_distance`, App. D | L² ½ Σ ((s − m)/h)² | RMS \|s − m\|/h |
//! | `inverse_distance.rs` | `inverse_distance`, Eq. 15 as written | L³ / d_min | nearest distance, m |
//! | `workspace.rs` | `workspace_volume`, App. D | −(L²/3) ln(V / V₀) | reachable volume V, m³ |
//!
//! `sym6.rs` holds the dexterity's 6 × 6 symmetric algebra. `grad.rs`
//! holds the shared algebra (frames at q; point and direction
//! gradients per body, mapped once into q's columns); `spec.rs` the
//! builder's vocabulary, `compile.rs` its compilation against a built model.
//!
//! Two more objectives exist already in the fast update and are made
//! explicit here as weights, not terms: `finger` (the finger rows' penalty,
//! Nelson & Cohen §4: [`Objectives::finger_weight`]) and
//! `least_astonishment` (½‖q − q₀‖ in the update's metric, §4.3:
//! [`Objectives::least_astonishment`], with the metric of design variables
//! relative to a body of mean mass, [`Objectives::design_weight`]).
//!
//! **Units and weights.** Every term's F is in m², and the fast update
//! minimises, per tick, ½ Δᵀ M Δ (least astonishment, mass metric) plus
//! Σ_k (w_k / w_la) m̄ F_k (m̄ the mean body mass): a weight of 1 pulls a
//! body of mean mass halfway to a term's minimum in one tick where nothing
//! else holds it. `Program` applies it as a shift of the least-astonishment
//! anchor (see `program::objective`).
//!
//! **Gradients** are analytic and checked against central differences at
//! random states (`solver/tests/objective/`). [`ObjectiveEval`] evaluates
//! values and gradients with zero allocation.

mod compile;
mod compile_chain;
mod dexterity;
mod dexterity_loop;
mod grad;
mod inverse_distance;
mod joint_limit;
mod obstacle;
mod spec;
mod straight_line;
mod sym6;
mod workspace;

use compile::compile;
pub(crate) use compile::display_name;
pub use dexterity::DET_FLOOR;
pub use obstacle::MIN_DISTANCE_FRACTION;
pub use spec::{ObjectiveKind, ObjectiveSpec, ObstacleSpec};

use std::sync::Arc;

use crate::model::BuildError;
use crate::{EvalError, Model};
use grad::BodyGrad;

/// One compiled design term.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Term {
    Dexterity(dexterity::Dexterity),
    Obstacle(obstacle::Avoid),
    StraightLine(straight_line::StraightLine),
    JointLimits(joint_limit::Centred),
    InverseDistance(inverse_distance::InverseDistance),
    Workspace(workspace::Workspace),
}

/// One design objective of a model.
#[derive(Debug, Clone, PartialEq)]
pub struct Objective {
    /// Its name (`name` in the scene, else the kind, `#k` appended if the
    /// kind repeats).
    pub name: String,
    /// What it measures.
    pub kind: ObjectiveKind,
    /// Its weight w (relative to least astonishment, dimensionless).
    pub weight: f64,
    pub(crate) term: Term,
}

/// A model's objectives: the design terms and the weights of the two
/// built-in ones. `Default`: no terms, every weight 1 (the fast update as
/// it was before objectives were explicit).
#[derive(Debug, Clone, PartialEq)]
pub struct Objectives {
    /// The design terms, in scene order.
    pub terms: Vec<Objective>,
    /// Weight of the finger penalty rows, relative to least astonishment
    /// (multiplies [`SolverSettings::finger_weight`](crate::SolverSettings::finger_weight)).
    pub finger_weight: f64,
    /// Weight of least astonishment; every other weight is divided by it.
    pub least_astonishment: f64,
    /// The least-astonishment metric of a design variable, relative to a
    /// body of mean mass: larger, and design variables move more reluctantly
    /// than the bodies.
    pub design_weight: f64,
}

impl Default for Objectives {
    fn default() -> Self {
        Self {
            terms: Vec::new(),
            finger_weight: 1.0,
            least_astonishment: 1.0,
            design_weight: 1.0,
        }
    }
}

impl Objectives {
    /// True when there is no design term.
    pub fn is_empty(&self) -> bool {
        self.terms.is_empty()
    }
}

impl Objectives {
    /// Compiles `specs` (`[[objective]]`, in scene order) against `model`
    /// (bodies, joints and their geometry, q0). The error names the
    /// objective and what is wrong. Allocates; build time only.
    pub fn compile(specs: &[ObjectiveSpec], model: &Model) -> Result<Objectives, BuildError> {
        compile(specs, model)
    }

    /// The scratch to evaluate these objectives on `model` (the model they
    /// were compiled against, or one with its layout). Allocates.
    pub fn evaluation(self: &Arc<Self>, model: &Model) -> ObjectiveEval {
        ObjectiveEval::new(Arc::clone(self), model)
    }
}

/// Scratch for evaluating a model's objectives, allocated once.
#[derive(Debug, Clone)]
pub struct ObjectiveEval {
    objectives: Arc<Objectives>,
    model_id: u64,
    grad: BodyGrad,
    dex: dexterity::DexScratch,
}

impl ObjectiveEval {
    /// Buffers for `objectives` on `model`. Allocates.
    pub fn new(objectives: Arc<Objectives>, model: &Model) -> Self {
        let columns = objectives
            .terms
            .iter()
            .map(|t| match &t.term {
                Term::Dexterity(d) => d.columns.len(),
                _ => 0,
            })
            .max()
            .unwrap_or(0);
        Self {
            objectives,
            model_id: model.id,
            grad: BodyGrad::new(model),
            dex: dexterity::DexScratch::new(columns),
        }
    }

    fn prepare(&mut self, model: &Model, q: &[f64]) -> Result<(), EvalError> {
        if model.id != self.model_id {
            return Err(EvalError::ModelMismatch);
        }
        self.grad.frames(model, q)
    }

    /// Each term's F (m²) at `q`, into `out` (one per term).
    ///
    /// # Real-time
    /// No allocation; O(bodies + terms' sizes).
    pub fn values(&mut self, model: &Model, q: &[f64], out: &mut [f64]) -> Result<(), EvalError> {
        self.prepare(model, q)?;
        for (o, t) in out.iter_mut().zip(&self.objectives.terms) {
            *o = match &t.term {
                Term::Dexterity(d) => d.value(&self.grad, q, &mut self.dex),
                Term::Obstacle(a) => a.value(&self.grad),
                Term::StraightLine(s) => s.value(&self.grad),
                Term::JointLimits(j) => j.value(q, &self.grad),
                Term::InverseDistance(d) => d.value(&self.grad),
                Term::Workspace(v) => v.value(q),
            };
        }
        Ok(())
    }

    /// Each term's reported value at `q` (see the module table), into `out`.
    ///
    /// # Real-time
    /// No allocation; O(bodies + terms' sizes).
    pub fn reports(&mut self, model: &Model, q: &[f64], out: &mut [f64]) -> Result<(), EvalError> {
        self.prepare(model, q)?;
        for (o, t) in out.iter_mut().zip(&self.objectives.terms) {
            *o = match &t.term {
                Term::Dexterity(d) => d.report(&self.grad, q, &mut self.dex),
                Term::Obstacle(a) => a.report(&self.grad),
                Term::StraightLine(s) => s.report(&self.grad),
                Term::JointLimits(j) => j.report(q, &self.grad),
                Term::InverseDistance(d) => d.report(&self.grad),
                Term::Workspace(v) => v.volume(q),
            };
        }
        Ok(())
    }

    /// Σ_k w_k F_k at `q`, and its gradient added into `grad` (one entry per
    /// coordinate; an obstacle's own body excepted, see `obstacle.rs`).
    ///
    /// # Real-time
    /// No allocation; O(bodies + terms' sizes).
    pub fn gradient(
        &mut self,
        model: &Model,
        q: &[f64],
        grad: &mut [f64],
    ) -> Result<f64, EvalError> {
        self.prepare(model, q)?;
        if grad.len() != model.n_coords() {
            return Err(EvalError::CoordinateCount {
                expected: model.n_coords(),
                got: grad.len(),
            });
        }
        let mut total = 0.0;
        for t in &self.objectives.terms {
            let w = t.weight;
            total += w * match &t.term {
                Term::Dexterity(d) => d.gradient(&mut self.grad, q, &mut self.dex, w, grad),
                Term::Obstacle(a) => a.gradient(&mut self.grad, w),
                Term::StraightLine(s) => s.gradient(&mut self.grad, w),
                Term::JointLimits(j) => j.gradient(q, &mut self.grad, w, grad),
                Term::InverseDistance(d) => d.gradient(&mut self.grad, w),
                Term::Workspace(v) => v.gradient(q, w, grad),
            };
        }
        self.grad.flush(model, grad);
        Ok(total)
    }
}
