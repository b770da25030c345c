//! Built-in mechanisms, each returned assembled (C(q0) = 0 to rounding) with at
//! least one finger and gravity.
//!
//! | builder | moving bodies | joints | fingers | DOF (without fingers) |
//! |---|---|---|---|---|
//! | [`four_bar`] | 3 (+ ground) | R, S, U, R | point on the coupler | 1 |
//! | [`stewart`] | 13 (+ base) | 6 × (U, P, S) | rigid on the platform | 6 |
//! | [`sphere_toy`] | 132 | 120 U + 72 S | point on a top bead | see [`sphere_toy`] |
//! | [`cluttered_builder`] | n + 1 (+ table) | none: contact only | rigid on the dragged box | 6 (n + 1) |
//! | [`stewart_3rsu`] (Figs. 2/3) | 8 (+ floor) | weld, 3 × (R, U, S) | rigid on the platform | 6 |
//! | [`quarter_torus`] (Figs. 6/7) | 4 | 4 R in a loop | point on a part | 7 (floating) |
//! | [`four_bar_cardan`] (Fig. 11) | 4 (+ ground) | 3 R, S, 2 U | point on the crank | 1 |
//! | [`piston`] (Fig. 12) | 11 (+ ground) | 7 R, 4 S, 4 P, 2 gears | point on the flywheel | 1 |
//! | [`bennett`] | 3 (+ ground) | 4 R (3 rows redundant) | point on the link opposite the ground | 1 |
//! | [`lattice`] | 132 bars (+ ground) | 196 R, planar (192 rows redundant) | point on a top corner bar | 4 |
//! | [`chain`] | 64 (+ ground) | 63 U + 2 S, one long loop | point on the middle link | 126 |
//!
//! All are written in world coordinates first (joint points and axes) and
//! converted to body-frame anchors and axes by a private `Assembly` helper, which makes
//! the initial configuration exact.

mod bennett;
mod cardan;
mod chain;
mod cluttered;
mod four_bar;
mod lattice;
mod piston;
mod quarter_torus;
mod sphere_toy;
mod stewart;
mod stewart_3rsu;

pub use bennett::{BENNETT_A_M, BENNETT_B_M, bennett, bennett_builder};
pub use chain::{
    CHAIN_LINK_KG, CHAIN_LINK_M, CHAIN_REACH_MARGIN_M, chain, chain_builder,
    chain_circle_reach_margin, chain_hand_radius, chain_sized,
};
pub use cluttered::{CLUTTER_SPACING_M, DRAGGED_HALF_M, clutter_side, cluttered_builder};
pub use four_bar::{four_bar, four_bar_builder};
pub use lattice::{
    LATTICE_BAR_KG, LATTICE_BAR_M, lattice, lattice_builder, lattice_shape, lattice_sized,
};
pub use sphere_toy::{
    SPHERE_TOY_RADIUS_M, sphere_toy, sphere_toy_builder, sphere_toy_shape, sphere_toy_sized,
};
pub use stewart::{STROKE_M as STEWART_STROKE_M, stewart, stewart_builder};

pub use cardan::{
    CARDAN_BETA, CARDAN_CRANK0, CARDAN_LINKS_M, CARDAN_RISE_M, cardan_coupler_point,
    cardan_rocker_pivot, four_bar_cardan, four_bar_cardan_builder,
};
pub use piston::{
    BORE_X_M, CAM_RATIO, CRANK_M, FLYWHEEL_M, PISTON_PHASES, ROD_M, piston, piston_builder,
    piston_height_m,
};
pub use quarter_torus::{
    TORUS_GAP_M, TORUS_RADIUS_M, quarter_torus, quarter_torus_builder, torus_part_centroid,
    torus_part_rotation,
};
pub use stewart_3rsu::{
    RSU_BASE_M, RSU_CRANK_M, RSU_PLATFORM_M, RSU_ROD_M, rsu_azimuth, rsu_height_m, stewart_3rsu,
    stewart_3rsu_builder,
};

use nalgebra::{Rotation3, UnitQuaternion, Vector3};

use crate::{BodySpec, JointKind, JointSpec, ModelBuilder};

/// Earth gravity, m/s², world −z.
pub const GRAVITY_M_S2: [f64; 3] = [0.0, 0.0, -9.81];

/// A builder that remembers each body's pose, so joints can be given at world
/// points along world axes.
struct Assembly {
    builder: ModelBuilder,
    poses: Vec<(String, Vector3<f64>, UnitQuaternion<f64>)>,
}

impl Assembly {
    fn new() -> Self {
        let mut builder = ModelBuilder::new();
        builder.gravity(GRAVITY_M_S2);
        Self {
            builder,
            poses: Vec::new(),
        }
    }

    /// Adds `spec` placed at `position` with `rotation` (body → world).
    fn body(&mut self, spec: BodySpec, position: Vector3<f64>, rotation: UnitQuaternion<f64>) {
        let q = rotation.quaternion();
        self.poses.push((spec.name.clone(), position, rotation));
        self.builder
            .body(spec.at(position.into()).oriented([q.w, q.i, q.j, q.k]));
    }

    fn pose(&self, name: &str) -> (&Vector3<f64>, &UnitQuaternion<f64>) {
        let (_, p, r) = self
            .poses
            .iter()
            .find(|(n, ..)| n == name)
            .expect("body placed before use");
        (p, r)
    }

    /// A joint between `i` and `j` at world point `at`, with world axes `axes`.
    fn joint(
        &self,
        kind: JointKind,
        i: &str,
        j: &str,
        at: Vector3<f64>,
        axes: Option<[Vector3<f64>; 2]>,
    ) -> JointSpec {
        let local_point = |b: &str| {
            let (p, r) = self.pose(b);
            (r.inverse() * (at - p)).into()
        };
        let local_axis = |b: &str, a: &Vector3<f64>| (self.pose(b).1.inverse() * a).into();
        let mut spec = JointSpec::new(kind, i, j).anchors(local_point(i), local_point(j));
        if let Some([a, b]) = axes {
            spec = spec.axes(local_axis(i, &a), local_axis(j, &b));
        }
        spec
    }
}

/// The rotation taking body z to the unit direction `dir` (shortest arc; a half
/// turn about x when `dir` = −z).
fn z_to(dir: &Vector3<f64>) -> UnitQuaternion<f64> {
    UnitQuaternion::rotation_between(&Vector3::z(), dir).unwrap_or_else(|| {
        UnitQuaternion::from_axis_angle(&Vector3::x_axis(), std::f64::consts::PI)
    })
}

/// Principal inertia of a slender rod of mass `m` (kg) and length `l` (m) along
/// body z, with a small axial moment so the triangle inequality holds.
fn rod_inertia(m: f64, l: f64) -> [f64; 3] {
    let t = m * l * l / 12.0;
    [t, t, t * 0.01]
}

/// A rotation from three orthonormal world columns (body x, y, z).
fn from_columns(x: Vector3<f64>, y: Vector3<f64>, z: Vector3<f64>) -> UnitQuaternion<f64> {
    UnitQuaternion::from_rotation_matrix(&Rotation3::from_basis_unchecked(&[x, y, z]))
}
