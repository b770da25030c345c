//! Surface-contact test models: a ball on a surface of the ground, held at
//! its centre by a point finger.

use std::sync::Arc;
use std::time::Duration;

use haptloop_solver::parametric::{Surface, SurfaceKind};
use haptloop_solver::{
    BodySpec, ContactSurface, FingerSpec, JointKind, JointSpec, Model, ModelBuilder, Program,
    SolverSettings,
};
use nalgebra::{Matrix3, Vector3};

/// 1 kHz.
pub const DT: Duration = Duration::from_millis(1);

/// Ball radius, mass, and its solid-sphere inertia (2/5 m R²).
pub const R: f64 = 0.03;
pub const M: f64 = 0.1;
pub const I: f64 = 0.4 * M * R * R;

/// A ball of radius [`R`] on `kind` (its local frame at the ground's origin
/// turned by `tilt`), rolling or sliding, its contact starting at (u, v),
/// a point finger at its centre; gravity −z if `gravity`.
pub fn ball(
    kind: SurfaceKind,
    tilt: [f64; 4],
    uv: [f64; 2],
    rolling: bool,
    gravity: bool,
) -> Model {
    let surface = ContactSurface {
        kind,
        origin_m: [0.0; 3],
        orientation_wxyz: tilt,
    };
    let q = nalgebra::UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(
        tilt[0], tilt[1], tilt[2], tilt[3],
    ));
    let s = Surface::new(kind, Vector3::zeros(), q.to_rotation_matrix().into_inner());
    let c = s.offset(uv[0], uv[1], R).p;
    let mut b = ModelBuilder::new();
    if gravity {
        b.gravity([0.0, 0.0, -9.81]);
    }
    b.body(BodySpec::fixed("ground"));
    b.body(
        BodySpec::new("ball")
            .at([c.x, c.y, c.z])
            .mass(M)
            .inertia([I; 3]),
    );
    let kind = if rolling {
        JointKind::Rolling
    } else {
        JointKind::OnSurface
    };
    b.joint(
        JointSpec::new(kind, "ball", "ground")
            .named("contact")
            .surface(surface)
            .radius(R),
    );
    b.finger(FingerSpec::point("hand", "ball", [0.0; 3]));
    b.build().expect("ball builds")
}

/// A flat ground plane (local frame = world).
pub fn plane() -> SurfaceKind {
    SurfaceKind::Plane
}

/// A bowl of radius 0.2 m whose lowest point is the origin.
pub fn bowl() -> SurfaceKind {
    SurfaceKind::Sphere {
        radius_m: 0.2,
        concave: true,
    }
}

/// No tilt.
pub const LEVEL: [f64; 4] = [1.0, 0.0, 0.0, 0.0];

/// A program with a stiff finger (weight 1e4: the centre follows its
/// target to 1e-7 of the penalty's pull).
pub fn program(model: Model) -> Program {
    let settings = SolverSettings {
        finger_weight: 1e4,
        ..SolverSettings::default()
    };
    Program::new(Arc::new(model), settings).expect("program builds")
}

/// The rotation vector of R_b R_aᵀ (world).
pub fn turn(a: &Matrix3<f64>, b: &Matrix3<f64>) -> Vector3<f64> {
    haptloop_solver::parametric::rolling::log_rotation(&(b * a.transpose()))
}
