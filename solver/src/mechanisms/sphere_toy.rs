//! A closed-loop "sphere toy" of 132 bodies and 192 joints, after Nelson &
//! Cohen Fig. 1 ("a spherical toy with 132 bodies (graph nodes) and 192
//! constraints (graph edges) forms many closed loops").
//!
//! Construction: 132 small beads (all moving, no ground) on a sphere of radius
//! [`SPHERE_TOY_RADIUS_M`], in 11 latitude rings of 12 beads: ring k = 0..=10 at
//! polar angle 15°·(k + 1), bead m = 0..12 at longitude 30°·m. Each bead's body
//! frame has z radial (outward), x east, y = z × x.
//! - 120 meridian joints `m{k}.{m}`: universal between bead (k, m) and
//!   (k + 1, m) at their midpoint, cross axes east (on the upper bead) and along
//!   the meridian (on the lower bead); they allow bending both ways and forbid
//!   relative twist about the radial direction;
//! - 72 ring joints `r{k}.{m}`: spherical between bead (k, m) and (k, m + 1 mod
//!   12) at their midpoint, on the even rings k = 0, 2, …, 10 only (six closed
//!   rings; the odd rings are held only by their meridians).
//!
//! Counts: 132 bodies, 924 coordinates, 120·4 + 72·3 = 696 joint rows, 132
//! quaternion-norm rows, 3 finger rows: 831 rows; 10 293 stored nonzeros. The
//! joint graph is connected with 192 − 132 + 1 = 61 independent loops (the
//! cycle rank; as for a polyhedron with 62 faces). Mobility: 924 − 828 = 96
//! (Grübler, 6 of them rigid motion) and the Jacobian has full row rank at q0
//! (tested), so the structure is a floppy closed-loop toy, not overconstrained.
//! Finger `index`: point grasp on the outer surface of bead (0, 0). Gravity −z.

use std::f64::consts::PI;

use nalgebra::Vector3;

use super::{Assembly, from_columns};
use crate::{BodySpec, FingerSpec, JointKind as K, Model, ModelBuilder};

/// Radius of the sphere the bead centres lie on, metres.
pub const SPHERE_TOY_RADIUS_M: f64 = 0.1;

const RINGS: usize = 11;
const PER_RING: usize = 12;

fn bead(k: usize, m: usize) -> String {
    format!("bead{k}.{m}")
}

/// Unit radial, east and north-pointing meridian directions at polar angle
/// `phi`, longitude `lam`.
fn frame(phi: f64, lam: f64) -> [Vector3<f64>; 3] {
    let radial = Vector3::new(phi.sin() * lam.cos(), phi.sin() * lam.sin(), phi.cos());
    let east = Vector3::new(-lam.sin(), lam.cos(), 0.0);
    [radial, east, radial.cross(&east)]
}

/// The 132-body sphere toy, assembled at q0.
pub fn sphere_toy() -> Model {
    sphere_toy_builder()
        .build()
        .expect("the sphere toy is valid by construction")
}

/// The specs of [`sphere_toy`] before building (bodies, body-frame joints, fingers,
/// gravity), e.g. to write them as a scene file.
pub fn sphere_toy_builder() -> ModelBuilder {
    let polar = |k: usize| PI * (k + 1) as f64 / 12.0;
    let longitude = |m: usize| 2.0 * PI * m as f64 / PER_RING as f64;
    let mut t = Assembly::new();
    let centre = |k: usize, m: usize| frame(polar(k), longitude(m))[0] * SPHERE_TOY_RADIUS_M;
    for k in 0..RINGS {
        for m in 0..PER_RING {
            let [radial, east, north] = frame(polar(k), longitude(m));
            let spec = BodySpec::new(bead(k, m)).mass(0.01).inertia([4e-7; 3]);
            t.body(spec, centre(k, m), from_columns(east, north, radial));
        }
    }
    let mut joints = Vec::new();
    for k in 0..RINGS - 1 {
        for m in 0..PER_RING {
            let mid = (centre(k, m) + centre(k + 1, m)) / 2.0;
            let [_, east, north] = frame(polar(k) + PI / 24.0, longitude(m));
            let j = t.joint(
                K::Universal,
                &bead(k, m),
                &bead(k + 1, m),
                mid,
                Some([east, north]),
            );
            joints.push(j.named(format!("m{k}.{m}")));
        }
    }
    for k in (0..RINGS).step_by(2) {
        for m in 0..PER_RING {
            let n = (m + 1) % PER_RING;
            let mid = (centre(k, m) + centre(k, n)) / 2.0;
            let j = t.joint(K::Spherical, &bead(k, m), &bead(k, n), mid, None);
            joints.push(j.named(format!("r{k}.{m}")));
        }
    }
    for j in joints {
        t.builder.joint(j);
    }
    t.builder
        .finger(FingerSpec::point("index", bead(0, 0), [0.0, 0.0, 0.005]));
    t.builder
}
