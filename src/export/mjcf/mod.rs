//! A scene as a MuJoCo model (MJCF), built the way a MuJoCo user would build
//! it, for `haptloop export mjcf` and the peers comparison
//! (`benches/peers/`).
//!
//! | scene | MJCF |
//! |---|---|
//! | moving `[[body]]` | `<body>` with the same initial pose, `<inertial pos="0 0 0" mass diaginertia>` (haptloop's origin is the centre of mass); no geoms, contact off |
//! | fixed bodies | the world |
//! | tree joints ([`tree`]) | revolute → `hinge` (axis h_i, zero at q0 like haptloop's angle); universal → two `hinge`s in the child, the parent's axis first; prismatic → `slide`; spherical → `ball`; fixed → none |
//! | loop closures | spherical → `connect`; revolute → one `connect` when the tree keeps its axes parallel (a planar loop), else two on its axis one characteristic length apart; fixed → `weld` |
//! | a component without a fixed body | a `freejoint` at the root of its shallowest tree |
//! | `limits` | `range` on the hinge or slide, from q0 like haptloop's joint coordinate |
//! | finger | a mocap body per finger at its start, tied by a `connect` (point) or `weld` (rigid) with `solref` 0.02 s (soft, like the virtual coupling) |
//! | stiffness | loops and limits `solref` two timesteps, `solimp` 0.99 0.999 0.001 ([`Stiffness::Timesteps`]) or MuJoCo's defaults |
//! | damping | none unless asked for ([`Options::damping`]) |
//! | options | `timestep` one period of the scene's rate, `solver` Newton with its defaults, gravity as the scene's |
//!
//! What MJCF cannot say is refused with the reason: shapes and semantic
//! areas, design variables, contact fingers, scaled or rotated devices, hand
//! trace files, distance / perpendicular / point-on-plane joints, and loops
//! made only of universal and prismatic joints.

pub mod input;
pub mod meta;
pub mod tree;
pub mod xml;

use crate::scenes::Scene;
use anyhow::{Result, bail};
use input::Mechanism;
use tree::{Tree, TreeOptions};

/// How stiff the loop closures and limits are.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Stiffness {
    /// `solref` = this many timesteps (2: the stiffest MuJoCo recommends),
    /// `solimp` 0.99 0.999 0.001.
    Timesteps(f64),
    /// MuJoCo's defaults (`solref` 0.02 1, `solimp` 0.9 0.95 0.001).
    Default,
}

/// Export choices; the default is the model described in the module docs.
#[derive(Debug, Clone)]
pub struct Options {
    /// Joints (by name) kept out of the tree and closed as equalities.
    pub cut: Vec<String>,
    /// The root body of a component without a fixed body.
    pub root: Option<String>,
    /// Close every revolute loop with two `connect`s.
    pub two_connects: bool,
    /// Damping on every tree joint, N·m·s/rad or N·s/m (0: none).
    pub damping: f64,
    /// Loop and limit stiffness.
    pub stiffness: Stiffness,
    /// The timestep's rate instead of the scene's, Hz.
    pub rate_hz: Option<u32>,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            cut: Vec::new(),
            root: None,
            two_connects: false,
            damping: 0.0,
            stiffness: Stiffness::Timesteps(2.0),
            rate_hz: None,
        }
    }
}

/// The model and what was decided building it.
#[derive(Debug, Clone)]
pub struct Export {
    /// The MJCF text.
    pub xml: String,
    /// The tree, closures, joints and hands (JSON with `serde`).
    pub meta: meta::Meta,
}

/// `scene` as MJCF, or why it cannot be.
pub fn export(scene: &Scene, options: &Options) -> Result<Export> {
    let m = Mechanism::of(scene)?;
    let joint = |name: &str| match m.joints.iter().position(|j| j.name == name) {
        Some(k) => Ok(k),
        None => bail!("--cut {name}: no joint of that name in `{}`", m.name),
    };
    let cut = options
        .cut
        .iter()
        .map(|n| joint(n))
        .collect::<Result<Vec<_>>>()?;
    let root = match &options.root {
        None => None,
        Some(name) => match m.bodies.iter().position(|b| &b.name == name && !b.fixed) {
            Some(b) => Some(b),
            None => bail!("--root {name}: no moving body of that name in `{}`", m.name),
        },
    };
    if !(options.damping.is_finite() && options.damping >= 0.0) {
        bail!("--damping {}: must be a finite number ≥ 0", options.damping);
    }
    let tree = Tree::of(
        &m,
        &TreeOptions {
            cut,
            root,
            two_connects: options.two_connects,
        },
    )?;
    let rate = options.rate_hz.unwrap_or(m.rate_hz);
    Ok(Export {
        xml: xml::write(&m, &tree, options),
        meta: meta::of(&m, &tree, rate),
    })
}
