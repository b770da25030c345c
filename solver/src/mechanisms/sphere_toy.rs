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
//!
//! [`sphere_toy_sized`] builds the same family with any number of rings and
//! beads per ring (ring k at polar angle 180°·(k + 1)/(rings + 1), ring
//! joints on the even rings): the scaling benchmarks' 33-, 132- and 400-body
//! structures (3 × 11, 11 × 12, 20 × 20).

use std::f64::consts::PI;

use nalgebra::Vector3;

use super::{Assembly, from_columns};
use crate::{BodySpec, FingerSpec, JointKind as K, Model, ModelBuilder};

/// Radius of the sphere the bead centres lie on, metres.
pub const SPHERE_TOY_RADIUS_M: f64 = 0.1;

const RINGS: usize = 11;
const PER_RING: usize = 12;

/// Rings and beads per ring of [`sphere_toy_sized`] for about `bodies`
/// bodies, as the scaling benchmarks use them: 33 → 3 × 11, 132 → 11 × 12,
/// 400 → 20 × 20.
pub fn sphere_toy_shape(bodies: usize) -> Option<(usize, usize)> {
    match bodies {
        33 => Some((3, 11)),
        132 => Some((RINGS, PER_RING)),
        400 => Some((20, 20)),
        _ => None,
    }
}

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
    sphere_toy_sized(RINGS, PER_RING)
}

/// The specs of a sphere toy of `rings` latitude rings of `per_ring` beads
/// (at least 1 and 3), built as [`sphere_toy`] (which is 11 × 12):
/// `rings · per_ring` bodies, universal meridian joints between rings,
/// spherical ring joints around the even rings, the finger on bead (0, 0).
/// Closed loops for `rings` ≥ 2 (and around each even ring).
pub fn sphere_toy_sized(rings: usize, per_ring: usize) -> ModelBuilder {
    let (rings, per_ring) = (rings.max(1), per_ring.max(3));
    let polar = |k: usize| PI * (k + 1) as f64 / (rings + 1) as f64;
    let half_gap = PI / (2.0 * (rings + 1) as f64);
    let longitude = |m: usize| 2.0 * PI * m as f64 / per_ring as f64;
    let mut t = Assembly::new();
    let centre = |k: usize, m: usize| frame(polar(k), longitude(m))[0] * SPHERE_TOY_RADIUS_M;
    for k in 0..rings {
        for m in 0..per_ring {
            let [radial, east, north] = frame(polar(k), longitude(m));
            let spec = BodySpec::new(bead(k, m)).mass(0.01).inertia([4e-7; 3]);
            t.body(spec, centre(k, m), from_columns(east, north, radial));
        }
    }
    let mut joints = Vec::new();
    for k in 0..rings - 1 {
        for m in 0..per_ring {
            let mid = (centre(k, m) + centre(k + 1, m)) / 2.0;
            let [_, east, north] = frame(polar(k) + half_gap, longitude(m));
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
    for k in (0..rings).step_by(2) {
        for m in 0..per_ring {
            let n = (m + 1) % per_ring;
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
