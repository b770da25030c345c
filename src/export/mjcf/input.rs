//! The part of a compiled scene that MJCF expresses, checked: bodies with
//! their initial poses and inertia, the joints in body frames, point and
//! rigid fingers, and the path each finger's hand follows.

use crate::scenes::Scene;
use anyhow::{Result, bail};
use haptloop_solver::scene::HandPath;
use haptloop_solver::{Grasp, JointKind};
use nalgebra::{UnitQuaternion, Vector3};

/// One body of the scene.
#[derive(Debug, Clone)]
pub struct BodyView {
    /// Unique name.
    pub name: String,
    /// Fixed bodies are MuJoCo's world.
    pub fixed: bool,
    /// Initial position, world frame, m.
    pub position: Vector3<f64>,
    /// Initial orientation, body → world.
    pub rotation: UnitQuaternion<f64>,
    /// kg.
    pub mass: f64,
    /// Principal moments about the body axes, kg·m².
    pub inertia: Vector3<f64>,
}

/// One joint, in body frames.
#[derive(Debug, Clone)]
pub struct JointView {
    /// The scene's name, `#k` (1-based) for an unnamed one.
    pub name: String,
    /// Its kind.
    pub kind: JointKind,
    /// Indices into [`Mechanism::bodies`] of bodies i and j.
    pub bodies: [usize; 2],
    /// k_i, k_j, m, body frames.
    pub anchors: [Vector3<f64>; 2],
    /// h_i, h_j, unit, body frames (kinds with axes).
    pub axes: Option<[Vector3<f64>; 2]>,
    /// `[lo, hi]` of the joint coordinate (rad or m).
    pub limits: Option<[f64; 2]>,
}

/// One finger.
#[derive(Debug, Clone)]
pub struct FingerView {
    /// Unique name.
    pub name: String,
    /// Index into [`Mechanism::bodies`].
    pub body: usize,
    /// Attachment point, body frame, m.
    pub point: Vector3<f64>,
    /// A rigid grasp (else a point grasp).
    pub rigid: bool,
    /// The path of the hand on its device.
    pub hand: HandPath,
}

/// A scene as MJCF sees it.
#[derive(Debug, Clone)]
pub struct Mechanism {
    /// `[scene] name`.
    pub name: String,
    /// The fast loop's rate (the scene's, else 1000 Hz): MuJoCo's timestep.
    pub rate_hz: u32,
    /// m/s².
    pub gravity: Vector3<f64>,
    /// The largest anchor or finger lever, m (the model's characteristic length).
    pub length_m: f64,
    /// In model order.
    pub bodies: Vec<BodyView>,
    /// In file order.
    pub joints: Vec<JointView>,
    /// In file order.
    pub fingers: Vec<FingerView>,
}

impl Mechanism {
    /// The view of `scene`, or what in it MJCF (as written here) cannot say.
    pub fn of(scene: &Scene) -> Result<Mechanism> {
        let c = &scene.compiled;
        let m = &c.model;
        let name = &c.name;
        if c.shaped_bodies > 0 || c.semantic_areas > 0 {
            bail!(
                "scene `{name}` has collision shapes or semantic areas: only mechanisms (bodies and joints) are exported"
            );
        }
        if !m.layout().design_vars().is_empty() {
            bail!("scene `{name}` has free design variables: MuJoCo has no counterpart");
        }
        let bodies: Vec<BodyView> = m
            .bodies()
            .iter()
            .map(|b| BodyView {
                name: b.name.clone(),
                fixed: b.fixed,
                position: b.position_m,
                rotation: b.orientation,
                mass: b.mass_kg,
                inertia: b.inertia_kg_m2,
            })
            .collect();
        let index = |n: &str| bodies.iter().position(|b| b.name == n);
        let mut joints = Vec::new();
        for (k, j) in scene.loaded.joint_specs().into_iter().enumerate() {
            let name = j.name.clone().unwrap_or_else(|| format!("#{}", k + 1));
            let (Some(bi), Some(bj)) = (index(&j.bodies[0]), index(&j.bodies[1])) else {
                bail!("joint `{name}`: unknown body");
            };
            let unit = |a: [f64; 3]| Vector3::from(a).normalize();
            joints.push(JointView {
                name,
                kind: j.kind,
                bodies: [bi, bj],
                anchors: [j.anchors_m[0].into(), j.anchors_m[1].into()],
                axes: j.axes.map(|[a, b]| [unit(a), unit(b)]),
                limits: j.limits,
            });
        }
        let mut fingers = Vec::new();
        for (decl, f) in c.fingers.iter().zip(m.fingers()) {
            let device = &c.devices[decl.device];
            if f.grasp == Grasp::Contact {
                bail!(
                    "finger `{}` is a contact finger: only point and rigid grasps are exported",
                    f.name
                );
            }
            if device.scale != 1.0 || device.orientation_wxyz != [1.0, 0.0, 0.0, 0.0] {
                bail!(
                    "device `{}` is scaled or rotated: the hand path is exported only in scene coordinates",
                    device.name
                );
            }
            if matches!(device.hand.path, HandPath::Trace { .. }) {
                bail!(
                    "device `{}` follows a hand trace file: only circle, line, waypoint and still paths are exported",
                    device.name
                );
            }
            fingers.push(FingerView {
                name: f.name.clone(),
                body: f.body.index(),
                point: f.point_m,
                rigid: f.grasp == Grasp::Rigid,
                hand: device.hand.path.clone(),
            });
        }
        Ok(Mechanism {
            name: name.clone(),
            rate_hz: c.settings.rate_hz.unwrap_or(1000),
            gravity: m.gravity_m_s2(),
            length_m: m.characteristic_length_m(),
            bodies,
            joints,
            fingers,
        })
    }

    /// Anchor `side` of `joint`, world frame at the initial configuration.
    pub fn world_point(&self, joint: &JointView, side: usize) -> Vector3<f64> {
        let b = &self.bodies[joint.bodies[side]];
        b.position + b.rotation * joint.anchors[side]
    }

    /// Axis `side` of `joint`, world frame at the initial configuration.
    pub fn world_axis(&self, joint: &JointView, side: usize) -> Option<Vector3<f64>> {
        let b = &self.bodies[joint.bodies[side]];
        joint.axes.map(|a| b.rotation * a[side])
    }
}
