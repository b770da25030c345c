//! The program the fast loop starts with: the scene assembled, then the
//! semantic rows aligned at the assembled configuration, then the contact
//! rows of the pairs in reach.

use super::*;

/// The program the fast loop starts with, and what building it produced.
pub(super) struct Start {
    /// The scene's model (its q layout is every snapshot's).
    pub(super) model: Arc<Model>,
    /// The model with the semantic rows of the start (the scene's without).
    pub(super) mechanism: Arc<Model>,
    pub(super) objectives: Arc<Objectives>,
    pub(super) program: Program,
    /// The assembled configuration.
    pub(super) q: Vec<f64>,
    pub(super) assembly: Option<SolveInfo>,
    pub(super) options: PlacementOptions,
    pub(super) semantic: Option<SemanticLoop>,
    pub(super) contact: Option<ContactLoop>,
    pub(super) inbox: Option<WitnessInbox>,
}

/// The fast-loop program of the scene's model, at the configuration the
/// initial assembly (Newton-KKT placement from q0 onto the constraints and
/// the fingers' initial positions) finds, or at q0 (`--no-assembly`).
pub(super) fn assemble(scene: &Scene, plan: &Plan) -> Result<Start> {
    let model = Arc::new(scene.compiled.model.clone());
    let objectives = scene.compiled.objectives.clone();
    let mut program = Program::with_objectives(model.clone(), objectives.clone(), plan.solver)
        .context("building the fast-loop program")?;
    let options = PlacementOptions::from_scene(
        Some(plan.assembly_tolerance_m),
        scene.compiled.settings.damping,
    );
    let mut placement =
        Placement::analyze(&model, &options).context("analysing the scene for placement")?;
    let mut q = model.q0().to_vec();
    let assembly = if plan.assemble {
        let info = placement
            .solve(&model, &mut q, model.q0(), &model.initial_targets())
            .context("assembling the scene")?;
        program
            .set_q(&q)
            .context("starting from the assembled configuration")?;
        Some(info)
    } else {
        None
    };
    Ok(Start {
        mechanism: model.clone(),
        model,
        objectives,
        program,
        q,
        assembly,
        options,
        semantic: None,
        contact: None,
        inbox: None,
    })
}

/// Semantic constraints: those aligned at the assembled configuration are
/// satisfied, and their rows are part of the mechanism from the start.
pub(super) fn with_semantic(start: &mut Start, scene: &Scene, plan: &Plan) -> Result<()> {
    start.semantic = SemanticLoop::new(
        start.model.clone(),
        scene.compiled.semantic.as_ref(),
        &scene.compiled.holds,
        &SemanticPlan {
            ops: scene.compiled.schedule.clone(),
            absent: scene.compiled.absent.clone(),
            mode: plan.semantic_mode,
        },
        &start.q,
    )?;
    if let Some(s) = &start.semantic {
        start.mechanism = s.current_model().clone();
        start.program = Program::with_objectives(
            start.mechanism.clone(),
            start.objectives.clone(),
            plan.solver,
        )
        .context("building the fast-loop program with the semantic rows")?;
        start
            .program
            .set_q(&start.q)
            .context("starting from the assembled configuration")?;
    }
    Ok(())
}

/// Contact: the active set at the assembled configuration decides the model
/// (the mechanism plus the contact rows of the pairs in reach) the fast loop
/// starts with.
pub(super) fn with_contact(start: &mut Start, scene: &Scene, plan: &Plan) -> Result<()> {
    let (frames_tx, frames_rx) = mailbox(WitnessFrame::default);
    start.contact = ContactLoop::new(
        start.mechanism.clone(),
        plan.solver,
        plan.contact,
        frames_tx,
        start.objectives.clone(),
    );
    if let Some(c) = &mut start.contact {
        let absent: Vec<u32> = scene.compiled.absent.iter().map(|b| b.0).collect();
        c.set_absent(&absent);
        start.program = c.initial(&start.q).context("building the contact rows")?;
        start
            .program
            .set_q(&start.q)
            .context("starting from the assembled configuration")?;
        start.inbox = Some(WitnessInbox::new(frames_rx));
    }
    Ok(())
}
