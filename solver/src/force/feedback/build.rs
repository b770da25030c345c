//! `Feedback`'s construction: the pattern of A, the multiplier solve for
//! the chosen force solver, the finger rows and the buffers. Allocates;
//! runs once per program (the tick is in `feedback.rs`).

use super::*;

impl Feedback {
    /// Pattern, symbolic factor and buffers for `model` (whose Jacobian
    /// pattern `ev` holds). Allocates.
    pub fn new(
        model: &Model,
        ev: &Evaluation,
        settings: &SolverSettings,
        excluded: &[bool],
    ) -> Result<Self, faer::sparse::FaerError> {
        let jac = ev.jacobian();
        let masses = BodyMass::of_model(model);
        let n_bodies = masses.len();
        let decouple = settings.norm_rows_out && settings.force_solver == ForceSolver::Cholesky;
        let gram = Gram::with_norms(model, jac, &masses, excluded, decouple);
        let solve = solver_for(model, settings, &gram)?;
        let coupled = if decouple {
            norms::CoupledPattern::new(
                model,
                jac,
                &masses,
                excluded,
                &gram,
                &solve,
                crate::cholesky::DENSE_MAX,
            )?
        } else {
            None
        };
        // The spare keeps a second factor of this pattern; with the norm
        // rows out an assembly may swap in the coupled pattern (`norms`),
        // which it does not follow: no spare then.
        let spare = match coupled {
            Some(_) => None,
            None => spare::Spare::for_model(model, settings, &gram, &solve),
        };
        let torques = crate::force::torque::JointTorques::new(model, gram.n_j);
        let m_f = gram.m_f;
        let friction = crate::force::friction::pairs_of(model);
        let fingers = finger_rows(model, jac, settings);
        let tau = settings.velocity_filter.as_secs_f64();
        let mut feedback = Self {
            motion: Motion::new(
                model.q0(),
                masses.len(),
                model.n_coords() - model.layout().aux_coords(),
                tau,
            ),
            masses,
            gram,
            solve,
            coupled,
            prev_error: vec![Vector3::zeros(); fingers.len()],
            releases: 0,
            stick: vec![false; model.n_rows()],
            forced: vec![false; model.n_rows()],
            carry_forced: false,
            normal_force_n: vec![0.0; friction.len()],
            compliant: compliant_rows(model),
            friction,
            slips: 0,
            coupling: vec![(Vector3::zeros(), Vector3::zeros()); fingers.len()],
            known: vec![None; m_f],
            max_pull_n: 0.0,
            generation: 0,
            torques,
            flex_offsets: model
                .flexible
                .iter()
                .map(|f| model.layout().body_offset(f.body).unwrap_or(0))
                .collect(),
            applied: vec![(Vector3::zeros(), Vector3::zeros()); n_bodies],
            fingers,
            b: vec![0.0; model.n_coords()],
            contact_raw: vec![0.0; model.n_coords()],
            row_known_f: vec![0.0; model.n_rows()],
            row_known: vec![0.0; model.n_rows()],
            y: vec![0.0; model.n_coords()],
            cy: vec![0.0; model.n_rows()],
            scale: vec![0.0; model.n_rows()],
            spare,
            first_kept: 0,
        };
        feedback.enable_low_rank(settings);
        Ok(feedback)
    }
}

/// The multiplier solve of `gram` for the force solver `settings` names,
/// with its preconditioner for the iterative ones.
fn solver_for(
    model: &Model,
    settings: &SolverSettings,
    gram: &Gram,
) -> Result<MultiplierSolve, faer::sparse::FaerError> {
    let (cg, matvec) = match settings.force_solver {
        ForceSolver::Cholesky => (None, None),
        ForceSolver::ConjugateGradient { max_iterations } => (Some(max_iterations), None),
        ForceSolver::Matvec { max_iterations }
        | ForceSolver::Tree { max_iterations }
        | ForceSolver::Multilevel { max_iterations } => (None, Some(max_iterations)),
    };
    let mut solve = MultiplierSolve::new(gram, cg, matvec, &contact_groups(model, gram))?;
    if let ForceSolver::Tree { max_iterations } = settings.force_solver {
        let group: Vec<usize> = (gram.j_rows.iter())
            .map(|&r| model.rows()[r].constraint.index())
            .collect();
        let tree = crate::force::precond::tree::TreePrecond::new(gram, &group, 1 + gram.m_f)?;
        solve.set_tree(
            crate::force::precond::Precond::Tree(Box::new(tree)),
            max_iterations,
        );
    }
    if let ForceSolver::Multilevel { max_iterations } = settings.force_solver {
        solve.set_tree(
            crate::force::precond::multilevel::for_model(model, gram),
            max_iterations,
        );
    }
    Ok(solve)
}

/// Each finger's rows and where its body's columns sit in them (`jac`'s
/// pattern).
fn finger_rows(model: &Model, jac: &crate::Jacobian, settings: &SolverSettings) -> Vec<FingerRows> {
    model
        .fingers()
        .iter()
        .map(|f| {
            let rows = model.constraints()[f.constraint.index()].rows.clone();
            let offset = model.layout().body_offset(f.body).unwrap_or(0);
            let mut pos = [0; 6];
            for (k, r) in rows.clone().enumerate() {
                let span = jac.row_ptr()[r]..jac.row_ptr()[r + 1];
                pos[k] = span
                    .clone()
                    .find(|&p| jac.col_idx()[p] == offset)
                    .unwrap_or(span.start);
            }
            let proxy =
                settings.dynamics && settings.update == UpdateRule::Projected && f.tip.is_some();
            let flex = match model.geometry[f.constraint.index()].anchors()[0] {
                crate::constraint::block::Param3::Flex(i) => Some(model.flex_anchors[i as usize]),
                _ => None,
            };
            FingerRows {
                proxy,
                rigid: rows.len() == 6,
                rows,
                pos,
                offset,
                point: f.point_m,
                flex,
            }
        })
        .collect()
}

/// Per row: a contact or friction row (solved with [`CONTACT_COMPLIANCE`]).
fn compliant_rows(model: &Model) -> Vec<bool> {
    model
        .rows()
        .iter()
        .map(|r| {
            matches!(
                model.constraints()[r.constraint.index()].kind,
                crate::ConstraintKind::Contact | crate::ConstraintKind::ContactFriction
            )
        })
        .collect()
}
