//! What the export decided, as JSON beside the MJCF: the tree and closures,
//! every scene joint in the frames a violation is measured in, and each
//! finger's start and hand path (the peers comparison drives the mocap
//! bodies with it and measures MuJoCo's joints as haptloop measures its own).

use super::input::Mechanism;
use super::tree::Tree;
use super::xml::hand_body;
use haptloop_solver::scene::HandPath;
use serde::Serialize;

/// One side of a joint: a moving body's frame, or the world for a fixed body
/// (its anchor and axis then given in world coordinates).
#[derive(Debug, Clone, Serialize)]
pub struct Side {
    /// The MuJoCo body, `None` for the world.
    pub body: Option<String>,
    /// The anchor, m.
    pub anchor: [f64; 3],
    /// The axis (unit), for kinds with axes.
    pub axis: Option<[f64; 3]>,
}

/// A scene joint.
#[derive(Debug, Clone, Serialize)]
pub struct Joint {
    /// Name (`#k` when unnamed).
    pub name: String,
    /// `revolute`, `spherical`, …
    pub kind: &'static str,
    /// Sides i and j.
    pub sides: [Side; 2],
    /// The closure's style (`connect`, `two_connects`, `weld`), `None` for a
    /// tree joint.
    pub closure: Option<&'static str>,
}

/// The hand's path, offsets from the finger's start (scene frame).
#[derive(Debug, Clone, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Hand {
    /// No motion.
    Still,
    /// r((cos ωt − 1)u + sin ωt v), ω = 2π·hz.
    Circle {
        /// m.
        radius_m: f64,
        /// Revolutions per second.
        hz: f64,
        /// Unit.
        u: [f64; 3],
        /// Unit.
        v: [f64; 3],
    },
    /// `to_m` × min(t / seconds, 1).
    Line {
        /// m.
        to_m: [f64; 3],
        /// s.
        seconds: f64,
    },
    /// `[t, dx, dy, dz]`, linearly interpolated, held after the last.
    Waypoints(Vec<[f64; 4]>),
}

/// A finger and its mocap hand.
#[derive(Debug, Clone, Serialize)]
pub struct Finger {
    /// Name.
    pub name: String,
    /// The body it holds.
    pub body: String,
    /// The mocap body that follows the hand.
    pub mocap: String,
    /// World position of the finger point at q0, m.
    pub start: [f64; 3],
    /// The hand's path.
    pub hand: Hand,
}

/// Everything beside the XML.
#[derive(Debug, Clone, Serialize)]
pub struct Meta {
    /// Scene name.
    pub scene: String,
    /// 1 / timestep.
    pub rate_hz: u32,
    /// The second `connect` of a spatial revolute closure sits this far along its axis, m.
    pub length_m: f64,
    /// MuJoCo's `nv` for this tree.
    pub dof: usize,
    /// Equality rows of the loop closures (without the fingers').
    pub closure_rows: usize,
    /// Bodies on a `freejoint`.
    pub roots: Vec<String>,
    /// Every scene joint, tree joints and closures.
    pub joints: Vec<Joint>,
    /// The fingers.
    pub fingers: Vec<Finger>,
}

fn arr(v: &nalgebra::Vector3<f64>) -> [f64; 3] {
    [v.x, v.y, v.z]
}

fn hand(path: &HandPath) -> Hand {
    match path {
        HandPath::Still | HandPath::Trace { .. } => Hand::Still,
        HandPath::Circle { radius_m, hz, u, v } => {
            let unit = |a: &[f64; 3]| arr(&nalgebra::Vector3::from(*a).normalize());
            Hand::Circle {
                radius_m: *radius_m,
                hz: *hz,
                u: unit(u),
                v: unit(v),
            }
        }
        HandPath::Line { to_m, seconds } => Hand::Line {
            to_m: *to_m,
            seconds: *seconds,
        },
        HandPath::Waypoints { points } => Hand::Waypoints(points.clone()),
    }
}

/// The metadata of `m` exported with `tree`.
pub fn of(m: &Mechanism, tree: &Tree, rate_hz: u32) -> Meta {
    let joints = m
        .joints
        .iter()
        .enumerate()
        .map(|(k, j)| {
            let side = |s: usize| {
                let b = &m.bodies[j.bodies[s]];
                if b.fixed {
                    Side {
                        body: None,
                        anchor: arr(&m.world_point(j, s)),
                        axis: m.world_axis(j, s).map(|a| arr(&a)),
                    }
                } else {
                    Side {
                        body: Some(b.name.clone()),
                        anchor: arr(&j.anchors[s]),
                        axis: j.axes.map(|a| arr(&a[s])),
                    }
                }
            };
            Joint {
                name: j.name.clone(),
                kind: j.kind.as_str(),
                sides: [side(0), side(1)],
                closure: tree
                    .closures
                    .iter()
                    .find(|(c, _)| *c == k)
                    .map(|(_, how)| how.as_str()),
            }
        })
        .collect();
    let fingers = m
        .fingers
        .iter()
        .map(|f| {
            let b = &m.bodies[f.body];
            Finger {
                name: f.name.clone(),
                body: b.name.clone(),
                mocap: hand_body(&f.name),
                start: arr(&(b.position + b.rotation * f.point)),
                hand: hand(&f.hand),
            }
        })
        .collect();
    Meta {
        scene: m.name.clone(),
        rate_hz,
        length_m: m.length_m,
        dof: tree.dof(m),
        closure_rows: tree.closures.iter().map(|(_, how)| how.rows()).sum(),
        roots: tree
            .roots
            .iter()
            .map(|&b| m.bodies[b].name.clone())
            .collect(),
        joints,
        fingers,
    }
}
