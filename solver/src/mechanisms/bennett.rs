//! A Bennett linkage: the spatial four-revolute (4R) loop that moves with one
//! degree of freedom although the spatial Grübler count gives 6·3 − 4·5 = −2,
//! so three of its 20 joint rows are redundant at every configuration.
//!
//! Geometry (Denavit–Hartenberg, frames 0–3 at the joints, no offsets along
//! the axes): link lengths a = [`BENNETT_A_M`] (links 1 and 3) and b =
//! [`BENNETT_B_M`] (links 2 and 4), twists α = 30° and β with a / sin α = b /
//! sin β (Bennett's condition: β = asin 0.8), joint angles θ1 = 70°, θ3 = −θ1,
//! θ4 = θ2 = 2 atan(K / tan(θ1/2)) with K = sin((β + α)/2) / sin((β − α)/2),
//! for which the four transforms Rz(θ)·Tx(a)·Rx(α) multiply to the identity.
//! Link 4 is the `ground` (fixed, frame 0 at the origin, the first axis
//! world z); `link1`–`link3` are slender rods from joint to joint along their
//! body z. Joints, in order, all revolute about the DH z axes:
//! - `j1`: ground–link1 at the origin, axis z0;
//! - `j2`: link1–link2; `j3`: link2–link3;
//! - `j4`: link3–ground, closing the loop.
//!
//! The Jacobian's rank confirms one degree of freedom (21 coordinates − 20
//! independent rows of 23; tested). Finger `index`: point grasp at the middle
//! of `link2` (the link opposite the ground). Gravity −z.

use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};

use super::{Assembly, rod_inertia, z_to};
use crate::{BodySpec, FingerSpec, JointKind as K, Model, ModelBuilder};

/// Length of links 1 and 3 (the common normal between their axes), metres.
pub const BENNETT_A_M: f64 = 0.05;
/// Length of links 2 and 4, metres.
pub const BENNETT_B_M: f64 = 0.08;

/// The joint frames 0–3 of the loop (frame k on joint k + 1's axis, its z
/// along that axis) and the fourth frame, which returns to frame 0.
fn frames() -> [Isometry3<f64>; 5] {
    let alpha = 30f64.to_radians();
    let beta = (BENNETT_B_M / BENNETT_A_M * alpha.sin()).asin();
    let k = ((beta + alpha) / 2.0).sin() / ((beta - alpha) / 2.0).sin();
    let t1 = 70f64.to_radians();
    let t2 = 2.0 * (k / (t1 / 2.0).tan()).atan();
    let dh = |theta: f64, a: f64, twist: f64| {
        Isometry3::from_parts(
            Translation3::identity(),
            UnitQuaternion::from_axis_angle(&Vector3::z_axis(), theta),
        ) * Isometry3::from_parts(
            Translation3::new(a, 0.0, 0.0),
            UnitQuaternion::from_axis_angle(&Vector3::x_axis(), twist),
        )
    };
    let steps = [
        dh(t1, BENNETT_A_M, alpha),
        dh(t2, BENNETT_B_M, beta),
        dh(-t1, BENNETT_A_M, alpha),
        dh(-t2, BENNETT_B_M, beta),
    ];
    let mut out = [Isometry3::identity(); 5];
    for (i, s) in steps.iter().enumerate() {
        out[i + 1] = out[i] * s;
    }
    out
}

/// The Bennett linkage, assembled at q0.
pub fn bennett() -> Model {
    bennett_builder()
        .build()
        .expect("the Bennett linkage is valid by construction")
}

/// The specs of [`bennett`] before building (bodies, body-frame joints,
/// fingers, gravity), e.g. to write them as a scene file.
pub fn bennett_builder() -> ModelBuilder {
    let f = frames();
    let point = |k: usize| f[k].translation.vector;
    let axis = |k: usize| f[k].rotation * Vector3::z();
    let mut m = Assembly::new();
    m.body(
        BodySpec::fixed("ground"),
        Vector3::zeros(),
        UnitQuaternion::identity(),
    );
    for (k, mass) in [(1, 0.05), (2, 0.08), (3, 0.05)] {
        let (p, q) = (point(k - 1), point(k));
        let len = (q - p).norm();
        let spec = BodySpec::new(format!("link{k}"))
            .mass(mass)
            .inertia(rod_inertia(mass, len));
        m.body(spec, (p + q) / 2.0, z_to(&((q - p) / len)));
    }
    let pairs = [
        ("ground", "link1"),
        ("link1", "link2"),
        ("link2", "link3"),
        ("link3", "ground"),
    ];
    let joints: Vec<_> = pairs
        .iter()
        .enumerate()
        .map(|(k, (i, j))| {
            m.joint(K::Revolute, i, j, point(k), Some([axis(k); 2]))
                .named(format!("j{}", k + 1))
        })
        .collect();
    for j in joints {
        m.builder.joint(j);
    }
    m.builder
        .finger(FingerSpec::point("index", "link2", [0.0; 3]));
    m.builder
}
