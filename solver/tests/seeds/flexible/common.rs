//! Flexible test models and helpers.

use std::sync::Arc;
use std::time::Duration;

use haptloop_solver::flexible::BeamSpec;
use haptloop_solver::{
    BodySpec, FingerSpec, JointKind, JointSpec, Model, ModelBuilder, Program, SolverSettings,
};

/// 1 kHz.
pub const DT: Duration = Duration::from_millis(1);

/// Cantilever length, metres.
pub const L: f64 = 0.2;

/// Bending stiffness giving a 20 N/m tip (3 EI / L³), N·m².
pub const EI: f64 = 20.0 * L * L * L / 3.0;

/// A cantilever along world x: body `beam` (50 g) welded to the ground at
/// its frame (x = 0), bending with `modes` shape functions per direction
/// (EI in y, 2 EI in z), a point finger at its tip, no gravity.
pub fn cantilever(modes: usize) -> Model {
    let mut b = ModelBuilder::new();
    b.body(BodySpec::fixed("ground"));
    b.body(
        BodySpec::new("beam")
            .mass(0.05)
            .inertia([1e-6, 2e-4, 2e-4])
            .flexible(BeamSpec {
                span_m: [0.0, L],
                clamp_m: 0.0,
                stiffness_n_m2: [EI, 2.0 * EI],
                modes,
            }),
    );
    b.joint(JointSpec::new(JointKind::Fixed, "ground", "beam").named("clamp"));
    b.finger(FingerSpec::point("tip", "beam", [L, 0.0, 0.0]));
    b.build().expect("cantilever builds")
}

/// A flexible "belly" (free, span [−0.08, 0.08] m along x, tilted) with a
/// spherical leg off its neutral axis, a distance strut to the ground, a
/// point-on-plane skid and a point finger: every row kind that reaches
/// deformation columns. Assembled at q0 (undeformed).
pub fn belly(gravity: bool) -> Model {
    let r = nalgebra::Vector3::new(0.01, 0.02, 0.1);
    let e =
        nalgebra::UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(0.95, 0.1, -0.2, 0.15));
    let world = |k: [f64; 3]| {
        let p = r + e * nalgebra::Vector3::from(k);
        [p.x, p.y, p.z]
    };
    let (hip, skid) = ([0.06, 0.01, -0.01], [-0.03, 0.0, 0.005]);
    let mut b = ModelBuilder::new();
    if gravity {
        b.gravity([0.0, 0.0, -9.81]);
    }
    b.body(BodySpec::fixed("ground"));
    b.body(
        BodySpec::new("belly")
            .at([r.x, r.y, r.z])
            .oriented([e.w, e.i, e.j, e.k])
            .mass(0.1)
            .inertia([2e-5, 2e-4, 2e-4])
            .flexible(BeamSpec {
                span_m: [-0.08, 0.08],
                clamp_m: 0.0,
                stiffness_n_m2: [0.02, 0.03],
                modes: 3,
            }),
    );
    let hip_w = world(hip);
    b.body(
        BodySpec::new("leg")
            .at([hip_w[0], hip_w[1], hip_w[2] - 0.03])
            .mass(0.02),
    );
    b.joint(
        JointSpec::new(JointKind::Spherical, "belly", "leg")
            .named("hip")
            .anchors(hip, [0.0, 0.0, 0.03]),
    );
    b.joint(
        JointSpec::new(JointKind::Distance, "belly", "ground")
            .named("strut")
            .anchors([-0.07, -0.01, 0.0], [-0.1, 0.0, 0.0]),
    );
    b.joint(
        JointSpec::new(JointKind::PointOnPlane, "belly", "ground")
            .named("skid")
            .anchors(skid, world(skid))
            .axes([0.0, 0.0, 1.0], [0.0, 0.0, 1.0]),
    );
    b.finger(FingerSpec::point("hand", "belly", [0.08, 0.0, 0.0]));
    b.build().expect("belly builds")
}

/// A projected program of `model` with `settings`.
pub fn program(model: Model, settings: SolverSettings) -> Program {
    Program::new(Arc::new(model), settings).expect("program builds")
}

/// A deterministic pseudo-random number in [−1, 1) (64-bit LCG).
pub struct Lcg(pub u64);

impl Lcg {
    pub fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((self.0 >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    }
}
