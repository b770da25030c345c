//! Nelson & Cohen Figs. 6 and 7: a quarter torus with two revolute joint
//! features (located by ū₁, ū₂ at the ends of its centre arc, directions v̄₁,
//! v̄₂ both along the torus's axis), four of them joined end to end into one
//! closed loop, "the assembled mechanism, or satisfaction of the geometric
//! constraints".
//!
//! Part k (`torus{k}`, k = 0…3) is the same body turned 90° k about z: its
//! centre arc of radius [`TORUS_RADIUS_M`] runs from angle 90° k to
//! 90° (k + 1), its origin at the arc's centroid (2R/π)(1, 1, 0) in its own
//! frame. Joint `joint{k}` is a revolute about z from part k's end ū₂ to
//! part k+1's ū₁. With `gap_m` > 0 every part starts moved that far outward
//! along its bisector: disassembled, as Fig. 6's parts before the constraints
//! are satisfied. By the loop's four-fold and mirror symmetry, the nearest
//! assembled configuration (equal weights on every part) is the ring itself,
//! `gap_m` = 0: that is the closed form the assembly is tested against.
//!
//! Assembled, the loop is a rhombus four-bar in the plane floating in space:
//! 4 moving bodies, 28 coordinates, 20 joint rows of which 3 repeat (a
//! planar loop), 6 + 1 = 7 degrees of freedom (rank-tested); opposite parts
//! stay parallel (a parallelogram). Finger `index`: a point at the middle of
//! part 0's arc. Gravity −z.

use std::f64::consts::{FRAC_PI_2, FRAC_PI_4, PI};

use nalgebra::{UnitQuaternion, Vector3};

use super::Assembly;
use crate::{BodySpec, FingerSpec, JointKind as K, Model, ModelBuilder};

/// Radius of the torus's centre circle, m.
pub const TORUS_RADIUS_M: f64 = 0.05;
/// How far the scene's parts start outside the ring, m.
pub const TORUS_GAP_M: f64 = 0.005;

/// Part k's rotation about z.
pub fn torus_part_rotation(k: usize) -> UnitQuaternion<f64> {
    UnitQuaternion::from_axis_angle(&Vector3::z_axis(), FRAC_PI_2 * k as f64)
}

/// Part k's centroid on the assembled ring, world frame.
pub fn torus_part_centroid(k: usize) -> Vector3<f64> {
    torus_part_rotation(k) * Vector3::new(1.0, 1.0, 0.0) * (2.0 * TORUS_RADIUS_M / PI)
}

/// The ring, assembled at q0.
pub fn quarter_torus() -> Model {
    quarter_torus_builder(0.0)
        .build()
        .expect("the quarter-torus loop is valid by construction")
}

/// The four parts `gap_m` outside the ring (0: assembled), with their
/// joint features in their own frames.
pub fn quarter_torus_builder(gap_m: f64) -> ModelBuilder {
    let r = TORUS_RADIUS_M;
    let c = Vector3::new(1.0, 1.0, 0.0) * (2.0 * r / PI);
    // Fig. 6's features, part frame.
    let u1 = Vector3::new(r, 0.0, 0.0) - c;
    let u2 = Vector3::new(0.0, r, 0.0) - c;
    let v = [0.0, 0.0, 1.0];
    let mass = 0.05;
    let mut m = Assembly::new();
    for k in 0..4 {
        let rot = torus_part_rotation(k);
        let out = rot * Vector3::new(FRAC_PI_4.cos(), FRAC_PI_4.sin(), 0.0);
        // A thin arc's moments about its centroid, roughly; each ≤ the sum
        // of the other two.
        let i = mass * r * r;
        m.body(
            BodySpec::new(format!("torus{k}"))
                .mass(mass)
                .inertia([0.15 * i, 0.2 * i, 0.3 * i]),
            torus_part_centroid(k) + out * gap_m,
            rot,
        );
    }
    for k in 0..4 {
        let next = (k + 1) % 4;
        m.builder.joint(
            crate::JointSpec::new(K::Revolute, format!("torus{k}"), format!("torus{next}"))
                .named(format!("joint{k}"))
                .anchors(u2.into(), u1.into())
                .axes(v, v),
        );
    }
    let middle = Vector3::new(FRAC_PI_4.cos(), FRAC_PI_4.sin(), 0.0) * r - c;
    m.builder
        .finger(FingerSpec::point("index", "torus0", middle.into()));
    m.builder
}
