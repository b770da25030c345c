//! A long closed chain: `links` slender bars hanging between two fixed points,
//! joined end to end by universal joints, each end on a spherical joint to the
//! `ground`: one loop through the ground, as long as the chain.
//!
//! Construction ([`chain_sized`]; the built-in [`chain`] has 64 links): the
//! joint points p_k, k = 0..=links, lie on a half circle below the x axis in
//! the x–z plane, p_k = R·(−cos φ_k, 0, −sin φ_k) with φ_k = π·k / links, so
//! every bar has the same length [`CHAIN_LINK_M`] (R = ℓ / (2 sin(π / 2·links)))
//! and the two ends are the fixed points (∓R, 0, 0). Bars `link{k}` run from p_k
//! to p_{k+1} along their body z ([`CHAIN_LINK_KG`] each). Joints:
//! - `end0`: spherical ground–`link0` at p_0; `end1`: spherical
//!   `link{links−1}`–ground at p_links;
//! - `u{k}`, k = 1..links: universal `link{k−1}`–`link{k}` at p_k, the cross
//!   axes y on `link{k−1}` (bending in the plane) and, on `link{k}`, the
//!   in-plane normal of `link{k}` (bending out of it); no relative twist.
//!
//! Counts: `links` bodies, 7·links coordinates, 4·(links − 1) + 6 joint rows,
//! one loop. Mobility 6·links − 4·(links − 1) − 6 = 2·links − 2 (rank-tested:
//! no row is redundant). Finger `index`: point grasp at the middle of the
//! middle bar, `link{links/2}`. Gravity −z: the chain hangs from its ends.

use std::f64::consts::PI;

use nalgebra::{UnitQuaternion, Vector3};

use super::{Assembly, rod_inertia, z_to};
use crate::{BodySpec, FingerSpec, JointKind as K, Model, ModelBuilder};

/// Length of every link (the chord between its joints), metres.
pub const CHAIN_LINK_M: f64 = 0.01;
/// Mass of every link, kilograms.
pub const CHAIN_LINK_KG: f64 = 0.005;

const LINKS: usize = 64;

/// The 64-link closed chain, assembled at q0.
pub fn chain() -> Model {
    chain_builder()
        .build()
        .expect("the chain is valid by construction")
}

/// The specs of [`chain`] before building (bodies, body-frame joints,
/// fingers, gravity), e.g. to write them as a scene file.
pub fn chain_builder() -> ModelBuilder {
    chain_sized(LINKS)
}

/// The specs of a closed chain of `links` bars (at least 2), built as
/// [`chain`] (which has 64).
pub fn chain_sized(links: usize) -> ModelBuilder {
    let links = links.max(2);
    let point = |k: usize| joint_point(links, k);
    let name = |k: usize| format!("link{k}");
    let mut t = Assembly::new();
    t.body(
        BodySpec::fixed("ground"),
        Vector3::zeros(),
        UnitQuaternion::identity(),
    );
    for k in 0..links {
        let (a, b) = (point(k), point(k + 1));
        let spec = BodySpec::new(name(k))
            .mass(CHAIN_LINK_KG)
            .inertia(rod_inertia(CHAIN_LINK_KG, CHAIN_LINK_M));
        t.body(spec, (a + b) / 2.0, z_to(&(b - a).normalize()));
    }
    let mut joints = vec![
        t.joint(K::Spherical, "ground", &name(0), point(0), None)
            .named("end0"),
    ];
    for k in 1..links {
        let along = (point(k + 1) - point(k)).normalize();
        let normal = Vector3::y().cross(&along);
        joints.push(
            t.joint(
                K::Universal,
                &name(k - 1),
                &name(k),
                point(k),
                Some([Vector3::y(), normal]),
            )
            .named(format!("u{k}")),
        );
    }
    joints.push(
        t.joint(K::Spherical, &name(links - 1), "ground", point(links), None)
            .named("end1"),
    );
    for j in joints {
        t.builder.joint(j);
    }
    t.builder
        .finger(FingerSpec::point("index", name(links / 2), [0.0; 3]));
    t.builder
}

/// p_k of a chain of `links` bars (the module's construction).
fn joint_point(links: usize, k: usize) -> Vector3<f64> {
    let radius = CHAIN_LINK_M / (2.0 * (PI / (2.0 * links as f64)).sin());
    let phi = PI * k as f64 / links as f64;
    Vector3::new(-phi.cos(), 0.0, -phi.sin()) * radius
}

/// How far inside the chain's reach a hand path must stay: 1 mm. Nearer,
/// the arms between the grasp and the fixed ends are pulled almost straight
/// and the fast loop's rows lose rank together (BENCHMARKS.md, "Issue 23 —
/// the chain family at its extremes").
pub const CHAIN_REACH_MARGIN_M: f64 = 1e-3;

/// How far inside its reach the grasp of a chain of `links` bars stays, at
/// worst, while it follows the scene's horizontal circle of `radius` metres
/// from the grasp, r((cos θ − 1)·x + sin θ·y): the least, over θ and both
/// arms, of the arm's length (its bars up to the grasp, taut) less the
/// grasp's distance to the arm's fixed end (sampled every half degree).
/// Negative: the path leaves the reach.
pub fn chain_circle_reach_margin(links: usize, radius: f64) -> f64 {
    let links = links.max(2);
    let half = links / 2;
    let grasp = (joint_point(links, half) + joint_point(links, half + 1)) / 2.0;
    let arms = [
        (joint_point(links, 0), (half as f64 + 0.5) * CHAIN_LINK_M),
        (
            joint_point(links, links),
            ((links - half) as f64 - 0.5) * CHAIN_LINK_M,
        ),
    ];
    (0..720)
        .map(|i| {
            let theta = PI * i as f64 / 360.0;
            let hand = grasp + Vector3::new(theta.cos() - 1.0, theta.sin(), 0.0) * radius;
            arms.iter()
                .map(|(end, length)| length - (hand - end).norm())
                .fold(f64::INFINITY, f64::min)
        })
        .fold(f64::INFINITY, f64::min)
}

/// The largest radius, at most `radius`, of the scene's hand circle (see
/// [`chain_circle_reach_margin`]) that keeps the grasp
/// [`CHAIN_REACH_MARGIN_M`] inside the reach of a chain of `links` bars
/// (bisection to 1 µm; 0 when even the grasp's start is nearer than that).
pub fn chain_hand_radius(links: usize, radius: f64) -> f64 {
    let inside = |r: f64| chain_circle_reach_margin(links, r) >= CHAIN_REACH_MARGIN_M;
    if inside(radius) {
        return radius;
    }
    if !inside(0.0) {
        return 0.0;
    }
    let (mut lo, mut hi) = (0.0, radius);
    while hi - lo > 1e-6 {
        let mid = 0.5 * (lo + hi);
        if inside(mid) { lo = mid } else { hi = mid }
    }
    lo
}
