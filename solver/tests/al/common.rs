//! Shared helpers: programs of the built-in mechanisms, deterministic
//! perturbations, 1 kHz tick periods.

use std::sync::Arc;
use std::time::Duration;

use haptloop_solver::{Model, Program, SolverSettings};

/// 1 kHz.
pub const DT: Duration = Duration::from_millis(1);

/// A program of `model` with `settings`.
pub fn program(model: Model, settings: SolverSettings) -> Program {
    Program::new(Arc::new(model), settings).expect("program builds")
}

/// A deterministic pseudo-random number in [−1, 1) (64-bit LCG, fixed seed).
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

/// q0 of `model` with every coordinate moved by up to `size` (fixed seed).
pub fn perturbed(model: &Model, size: f64, seed: u64) -> Vec<f64> {
    let mut rng = Lcg(seed);
    model.q0().iter().map(|v| v + size * rng.next()).collect()
}

use haptloop_solver::{BodySpec, FingerSpec, FingerTarget, JointKind, JointSpec, ModelBuilder};

/// Standard gravity of the built-in mechanisms, m/s², world −z.
pub const G: [f64; 3] = [0.0, 0.0, -9.81];

/// A free body `box` (0.5 kg, principal inertia 2, 3, 4 g·m², tilted) held by
/// one finger at `point` (body frame), point or rigid grasp.
pub fn free_body(point: [f64; 3], rigid: bool) -> Model {
    let mut b = ModelBuilder::new();
    b.gravity(G);
    b.body(
        BodySpec::new("box")
            .at([0.1, 0.2, 0.3])
            .oriented([0.9, 0.2, -0.3, 0.1])
            .mass(0.5)
            .inertia([2e-3, 3e-3, 4e-3]),
    );
    b.finger(if rigid {
        FingerSpec::rigid("hand", "box", point)
    } else {
        FingerSpec::point("hand", "box", point)
    });
    b.build().expect("free body builds")
}

/// Pendulum geometry: pivot at the origin, hinge axis world y, the arm at
/// angle θ from hanging straight down (towards +x), centre of mass `L_C`
/// from the pivot, a point finger at the tip `L_F` from the pivot.
pub const L_C: f64 = 0.1;
/// Pivot to finger, metres.
pub const L_F: f64 = 0.15;
/// Arm mass, kilograms.
pub const ARM_KG: f64 = 0.2;

/// Unit direction from the pivot along the arm at angle `theta`.
pub fn arm_dir(theta: f64) -> nalgebra::Vector3<f64> {
    nalgebra::Vector3::new(theta.sin(), 0.0, -theta.cos())
}

/// The pendulum at angle `theta`, with optional hinge limits (radians,
/// relative to `theta`).
pub fn pendulum(theta: f64, limits: Option<(f64, f64)>) -> Model {
    let d = arm_dir(theta);
    let rot = nalgebra::UnitQuaternion::from_axis_angle(&nalgebra::Vector3::y_axis(), -theta);
    let q = rot.quaternion();
    let mut b = ModelBuilder::new();
    b.gravity(G);
    b.body(BodySpec::fixed("ground"));
    b.body(
        BodySpec::new("arm")
            .at((d * L_C).into())
            .oriented([q.w, q.i, q.j, q.k])
            .mass(ARM_KG)
            .inertia([ARM_KG * 0.04 / 12.0, ARM_KG * 0.04 / 12.0, 1e-6]),
    );
    let mut hinge = JointSpec::new(JointKind::Revolute, "ground", "arm")
        .named("hinge")
        .anchors([0.0; 3], [0.0, 0.0, L_C])
        .axes([0.0, 1.0, 0.0], [0.0, 1.0, 0.0]);
    if let Some((lo, hi)) = limits {
        hinge = hinge.limits(lo, hi);
    }
    b.joint(hinge);
    b.finger(FingerSpec::point("tip", "arm", [0.0, 0.0, -(L_F - L_C)]));
    b.build().expect("pendulum builds")
}

/// `n` ticks at 1 kHz with the same targets; panics on a failed tick.
pub fn hold(p: &mut Program, targets: &[FingerTarget], n: usize) {
    for k in 0..n {
        let r = p.tick(targets, DT);
        assert_eq!(
            r.status,
            haptloop_solver::TickOutcome::Ok,
            "tick {k}: {r:?}"
        );
    }
}

/// |a − b| / |b|.
pub fn rel(a: &nalgebra::Vector3<f64>, b: &nalgebra::Vector3<f64>) -> f64 {
    (a - b).norm() / b.norm()
}
