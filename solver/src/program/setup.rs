//! The steps of [`Program::with_objectives`](super::Program::with_objectives)
//! that build its parts: what the settings cannot cover, the factor with its
//! redundant rows masked, the friction bookkeeping, the projected update and
//! the inertial state. All allocate; the slow thread calls them.

use super::{ProgramError, objective};
use crate::al::projected::Projected;
use crate::al::scaling::{Role, Scaling};
use crate::al::{RedundancyCheck, SolverSettings};
use crate::force::Redundancy;
use crate::force::feedback::Feedback;
use crate::{Evaluation, Model, Objectives, UpdateRule};

/// Refuses the settings whose tick does not cover something `model` has
/// (contact rows, design variables, flexible bodies), naming the fix.
pub(super) fn check_supported(
    model: &Model,
    settings: &SolverSettings,
) -> Result<(), ProgramError> {
    // The fused gradient pass holds at most six rows per constraint; a
    // contact pair's witness rows are one constraint of many rows.
    if matches!(
        settings.force_solver,
        crate::ForceSolver::Matvec { .. }
            | crate::ForceSolver::Tree { .. }
            | crate::ForceSolver::Multilevel { .. }
    ) {
        if model.contact().slots > 0 {
            return Err(ProgramError::Unsupported(
                "the conjugate-gradient tick (`--force-solver matvec`, `tree` or `multilevel`) does not cover contact \
                 rows: this scene needs the Cholesky force solver",
            ));
        }
        if !model.layout().design_vars().is_empty() {
            return Err(ProgramError::Unsupported(
                "the conjugate-gradient tick (`--force-solver matvec`, `tree` or `multilevel`) does not cover design \
                 variables: this scene needs the Cholesky force solver",
            ));
        }
    }
    if settings.update == UpdateRule::Gradient && model.contact().slots > 0 {
        return Err(ProgramError::Unsupported(
            "the gradient update (Eq. 3) does not cover contact rows: this scene needs \
             the projected update (the default; drop `--update gradient`)",
        ));
    }
    if settings.update == UpdateRule::Gradient && !model.layout().aux_blocks().is_empty() {
        return Err(ProgramError::Unsupported(
            "the gradient update (Eq. 3) does not cover flexible bodies or surface \
             contacts: this scene needs `update = \"projected\"`",
        ));
    }
    Ok(())
}

/// The evaluation of `model` at q0, with its bookkeeping of resting bodies
/// set for the settings' dynamics.
pub(super) fn initial_evaluation(
    model: &Model,
    settings: &SolverSettings,
) -> Result<Evaluation, ProgramError> {
    let mut ev = model.evaluation();
    // Quasi-static programs leave resting bodies' contact rows alone
    // (`evaluate::since`); under inertial motion every body on a
    // support creeps a few ulps a tick, so every row would be written
    // anyway and the bookkeeping is overhead (`stack` 2.0 → 2.5 µs).
    ev.track_unmoved(model, !settings.dynamics);
    ev.anchor_rolling(model, model.q0());
    ev.evaluate(model, model.q0(), &model.initial_targets())?;
    Ok(ev)
}

/// The force solve's factor with the rows redundant at q0 (`ev` evaluated
/// there) found and masked in `scaling` and left out of A's pattern; design
/// bounds are never part of A.
pub(super) fn masked_feedback(
    model: &Model,
    ev: &Evaluation,
    settings: &SolverSettings,
    scaling: &mut Scaling,
) -> Result<(Feedback, Redundancy), ProgramError> {
    // Rows dependent within their body pair never enter A's pattern.
    let local = match settings.redundancy {
        RedundancyCheck::Off => Vec::new(),
        _ => Feedback::locally_dependent(model, ev, scaling),
    };
    scaling.mask(&local);
    let mut excluded = vec![false; model.n_rows()];
    for &i in &local {
        excluded[i] = true;
    }
    // Design bounds touch no body: never part of A (the projected update
    // keeps them as a box on its design step).
    for (e, role) in excluded.iter_mut().zip(&scaling.role) {
        *e |= matches!(role, Role::DesignBound | Role::DesignPin);
    }
    let factor = |excluded: &[bool]| {
        Feedback::new(model, ev, settings, excluded)
            .map_err(|e| ProgramError::Factorization(format!("{e:?}")))
    };
    let mut feedback = factor(&excluded)?;
    let mut redundancy = feedback.find_redundant(model, ev, scaling, settings.redundancy);
    redundancy.local = local.len();
    redundancy.rows.extend_from_slice(&local);
    redundancy.rows.sort_unstable();
    scaling.mask(&redundancy.rows);
    // The rows the ordered check masked leave A's pattern too: kept as
    // decoupled unit rows they cost factorisation and solve work on
    // explicit zeros (a planar lattice: 196 of its 1213 joint rows).
    if redundancy.rows.len() > local.len() {
        for &i in &redundancy.rows {
            excluded[i] = true;
        }
        feedback = factor(&excluded)?;
    }
    Ok((feedback, redundancy))
}

/// The projected update's state, with the design step's metric and the
/// masked equality rows of design variables.
pub(super) fn projected(
    model: &Model,
    scaling: &Scaling,
    settings: &SolverSettings,
    objectives: &Objectives,
    feedback: &Feedback,
    redundancy: &Redundancy,
) -> Projected {
    Projected::new(
        model,
        scaling,
        settings.gain,
        settings.finger_weight,
        feedback.mean_mass_kg(),
    )
    .with_design(
        model,
        objective::design_metric_kg(objectives, feedback.mean_mass_kg()),
        &super::masked_equalities(model, scaling, &redundancy.rows),
    )
}

/// Where the friction rows of `model`'s contact pairs are.
pub(super) struct Friction {
    /// Per witness-table slot: a friction stick row.
    pub slot: Vec<bool>,
    /// Index in the model's contact pairs of each pair with friction.
    pub pair: Vec<usize>,
    /// For each of `pair`, the indices in `feedback.masses` of its two
    /// bodies (`None`: fixed).
    pub bodies: Vec<[Option<usize>; 2]>,
}

impl Friction {
    /// The friction rows of `model` and their bodies in `feedback`.
    pub(super) fn new(model: &Model, feedback: &Feedback) -> Self {
        let mut slot = vec![false; model.contact().slots];
        let mut pair = Vec::new();
        for (k, p) in model.contact().pairs.iter().enumerate() {
            if let Some(f) = p.friction {
                let n = model.constraints()[p.normal.index()].rows.len();
                let rows = model.constraints()[f.index()].rows.len();
                slot[p.first_slot + n..p.first_slot + n + rows].fill(true);
                pair.push(k);
            }
        }
        let bodies = pair
            .iter()
            .map(|&k| {
                model.contact().pairs[k].bodies.map(|b| {
                    let o = model.layout().body_offset(b)?;
                    feedback.masses.iter().position(|m| m.offset == o)
                })
            })
            .collect();
        Self { slot, pair, bodies }
    }
}
