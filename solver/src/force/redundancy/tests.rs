use super::*;
use crate::{BodySpec, JointKind, JointSpec, ModelBuilder, SolverSettings};

/// A beam welded to the ground at one end and pinned (spherical) at the
/// other: 9 rows on a rigid body's 6 motions, so a rigid beam's three
/// pin rows depend on the weld's; a flexible beam's two transverse ones
/// do not (they hold its bending), its axial one still does (the beam
/// bends, it does not stretch). The dense QR and the sparse ordered
/// test must both see the deformation columns.
fn clamped_pinned(flexible: bool) -> Model {
    let mut b = ModelBuilder::new();
    b.body(BodySpec::fixed("ground"));
    let mut beam = BodySpec::new("beam").mass(0.05).inertia([1e-6, 2e-4, 2e-4]);
    if flexible {
        beam = beam.flexible(crate::flexible::BeamSpec::new([0.0, 0.2], 0.05, 3));
    }
    b.body(beam);
    b.joint(JointSpec::new(JointKind::Fixed, "ground", "beam").named("clamp"));
    b.joint(
        JointSpec::new(JointKind::Spherical, "beam", "ground")
            .named("pin")
            .anchors([0.2, 0.0, 0.0], [0.2, 0.0, 0.0]),
    );
    b.build().unwrap()
}

#[test]
fn deformation_columns_make_a_clamped_pinned_beam_independent() {
    for (flexible, masked) in [(false, 3), (true, 1)] {
        let model = clamped_pinned(flexible);
        let mut ev = model.evaluation();
        ev.evaluate(&model, model.q0(), &[]).unwrap();
        let s = Scaling::new(&model, &SolverSettings::default());
        let masses = BodyMass::of_model(&model);
        let rows: Vec<usize> = (0..model.n_rows())
            .filter(|&i| s.role[i] == Role::Equality)
            .collect();
        let dense = dependent_in_order(&model, &ev, &masses, &s.ell, &rows);
        assert_eq!(dense.len(), masked, "flexible {flexible}: dense {dense:?}");
        let p = crate::Program::new(
            std::sync::Arc::new(model),
            SolverSettings {
                redundancy: RedundancyCheck::Dense,
                ..SolverSettings::default()
            },
        )
        .unwrap();
        assert_eq!(p.redundancy().rows.len(), masked, "flexible {flexible}");
    }
}
