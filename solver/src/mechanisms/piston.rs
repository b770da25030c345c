//! The piston assembly of Nelson & Cohen Fig. 12: "the mechanism moves with
//! 1 DOF due to constraints from gears and four slider-crank subassemblies".
//!
//! An inline four: a `crankshaft` turning about world x on one main bearing,
//! four slider-cranks (crank throws of radius [`CRANK_M`] at x = 0, 0.05,
//! 0.10, 0.15 m, phased 0, π, π, 0 as in a four-cylinder engine; connecting
//! rods `rod{k}` of length [`ROD_M`]; `piston{k}` sliding along world z in its
//! bore), and two gear trains off the crankshaft: an overhead `camshaft`
//! 0.15 m above it at [`CAM_RATIO`] (20 teeth driving 40, pitch radii 5 and
//! 10 cm) and an oil `pump` 0.075 m below at −1. At crank angle θ (right-
//! handed about +x, zero with piston 0 at top dead centre) piston k's wrist
//! pin stands at
//!
//! ```text
//! z_k = r cos α + √(l² − r² sin² α),   α = θ + phase_k
//! ```
//!
//! Joints per cylinder: `crankpin{k}` revolute crankshaft–rod about x,
//! `wrist{k}` spherical rod–piston, `bore{k}` prismatic ground–piston along
//! z; `main` (ground–crankshaft), `cam` and `pump` revolutes about x; gears
//! `timing` (main → cam) and `oil` (main → pump).
//!
//! 11 moving bodies, 77 coordinates; 69 joint rows and 11 norms. Each slider
//! crank repeats one row (its loop is planar), so the rank is 76 and the
//! mechanism has 1 degree of freedom (rank-tested); the fast loop masks the
//! four repeated rows. Finger `index`: a point on the flywheel rim, 4 cm from
//! the axis, 3 cm in front of cylinder 0. Gravity −z. The main bearing
//! reports its motor torque (§5.2): what a starter motor on the crankshaft
//! would need to turn the engine as the hand does.

use std::f64::consts::PI;

use nalgebra::{UnitQuaternion, Vector3};

use super::{Assembly, rod_inertia, z_to};
use crate::{BodySpec, FingerSpec, GearSpec, JointKind as K, Model, ModelBuilder};

/// Crank throw r, metres.
pub const CRANK_M: f64 = 0.025;
/// Connecting rod length l, metres.
pub const ROD_M: f64 = 0.08;
/// Crank phase of each cylinder, radians.
pub const PISTON_PHASES: [f64; 4] = [0.0, PI, PI, 0.0];
/// x of each cylinder's bore, metres.
pub const BORE_X_M: [f64; 4] = [0.0, 0.05, 0.10, 0.15];
/// The camshaft's turns per crankshaft turn (external mesh: opposite sense).
pub const CAM_RATIO: f64 = -0.5;
/// The flywheel rim's radius at the finger, metres.
pub const FLYWHEEL_M: f64 = 0.04;

/// Wrist-pin height of a piston at crank angle `alpha` (its own phase
/// included), metres above the crank axis.
pub fn piston_height_m(alpha: f64) -> f64 {
    let s = CRANK_M * alpha.sin();
    CRANK_M * alpha.cos() + (ROD_M * ROD_M - s * s).sqrt()
}

/// The piston assembly, assembled at q0.
pub fn piston() -> Model {
    piston_builder()
        .build()
        .expect("the piston assembly is valid by construction")
}

/// The specs of [`piston`] before building.
pub fn piston_builder() -> ModelBuilder {
    let mid = Vector3::new(0.075, 0.0, 0.0);
    let x = Vector3::x();
    let mut m = Assembly::new();
    let id = UnitQuaternion::identity();
    m.body(BodySpec::fixed("ground"), Vector3::zeros(), id);
    m.body(
        BodySpec::new("crankshaft")
            .mass(1.2)
            .inertia([1.5e-3, 3e-3, 3e-3]),
        mid,
        id,
    );
    let cam_at = mid + Vector3::new(0.0, 0.0, 0.15);
    let pump_at = mid - Vector3::new(0.0, 0.0, 0.075);
    m.body(
        BodySpec::new("camshaft")
            .mass(0.4)
            .inertia([2e-4, 8e-4, 8e-4]),
        cam_at,
        id,
    );
    m.body(
        BodySpec::new("pump").mass(0.1).inertia([4e-5, 3e-5, 3e-5]),
        pump_at,
        id,
    );
    let mut joints = vec![
        m.joint(K::Revolute, "ground", "crankshaft", mid, Some([x; 2]))
            .named("main")
            .report_torque(),
        m.joint(K::Revolute, "ground", "camshaft", cam_at, Some([x; 2]))
            .named("cam"),
        m.joint(K::Revolute, "ground", "pump", pump_at, Some([x; 2]))
            .named("pump"),
    ];
    for k in 0..4 {
        let a = PISTON_PHASES[k];
        let pin = Vector3::new(BORE_X_M[k], -CRANK_M * a.sin(), CRANK_M * a.cos());
        let wrist = Vector3::new(BORE_X_M[k], 0.0, piston_height_m(a));
        let (rod, piston) = (format!("rod{k}"), format!("piston{k}"));
        m.body(
            BodySpec::new(&rod)
                .mass(0.12)
                .inertia(rod_inertia(0.12, ROD_M)),
            (pin + wrist) / 2.0,
            z_to(&(wrist - pin).normalize()),
        );
        m.body(
            BodySpec::new(&piston).mass(0.2).inertia([8e-5, 8e-5, 6e-5]),
            wrist,
            id,
        );
        joints.push(
            m.joint(K::Revolute, "crankshaft", &rod, pin, Some([x; 2]))
                .named(format!("crankpin{k}")),
        );
        joints.push(
            m.joint(K::Spherical, &rod, &piston, wrist, None)
                .named(format!("wrist{k}")),
        );
        joints.push(
            m.joint(
                K::Prismatic,
                "ground",
                &piston,
                wrist,
                Some([Vector3::z(); 2]),
            )
            .named(format!("bore{k}")),
        );
    }
    for j in joints {
        m.builder.joint(j);
    }
    m.builder
        .gear(GearSpec::gear("timing", "main", "cam", CAM_RATIO));
    m.builder.gear(GearSpec::gear("oil", "main", "pump", -1.0));
    let finger = Vector3::new(-0.03, 0.0, FLYWHEEL_M) - mid;
    m.builder
        .finger(FingerSpec::point("index", "crankshaft", finger.into()));
    m.builder
}
