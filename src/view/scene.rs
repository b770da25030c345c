//! `scene.json`: what a run's scene looks like, written once per run: every
//! body (shape, or the links a shape-less body is drawn with, fixed or
//! moving, initial pose), every finger and every device with its force
//! limits. The viewer draws from it; `bodies.csv` and `fingers.csv` move it.

use crate::scenes::Scene;
use haptloop_devices::{PhantomModel, VIRTUAL_MODEL, VirtualParams};
use haptloop_solver::geometry::Shape;
use serde::{Deserialize, Serialize};

/// The file's contents (see the module docs and `docs/run-files.md`).
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct SceneInfo {
    /// `[scene] name`.
    pub scene: String,
    /// `[scene] description`.
    pub description: String,
    /// Gravity, m/s², scene frame.
    pub gravity_m_s2: [f64; 3],
    /// A length that frames the mechanism, m (the camera's distance).
    pub size_m: f64,
    /// `[[joint]]` tables: a scene without any has no violation to plot.
    pub joints: usize,
    /// Every body, model order.
    pub bodies: Vec<BodyInfo>,
    /// Every finger, model order.
    pub fingers: Vec<FingerInfo>,
    /// Every device, scene order.
    pub devices: Vec<DeviceInfo>,
}

/// One body.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct BodyInfo {
    /// Name.
    pub name: String,
    /// Fixed bodies never move (`bodies.csv` lists them once).
    pub fixed: bool,
    /// Collision shape, body frame (`null`: drawn by its links).
    pub shape: Option<ShapeInfo>,
    /// Points the body is drawn through when it has no shape, m, body frame:
    /// its joints' anchors and its fingers' points (the origin when it has
    /// fewer than two); a link joins each to their centre.
    pub links: Vec<[f64; 3]>,
    /// A contact finger's fingertip ball.
    pub fingertip: bool,
    /// Initial position, m, scene frame.
    pub position_m: [f64; 3],
    /// Initial orientation `[w, x, y, z]`.
    pub orientation: [f64; 4],
    /// Declared but not in the scene at the start (a semantic scene's
    /// `[[schedule]] add` brings it in): not drawn until its `add` event.
    #[serde(default)]
    pub absent: bool,
}

/// A collision shape, as the scene file writes it.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(rename_all = "snake_case")]
pub enum ShapeInfo {
    /// Half extents, m.
    Box([f64; 3]),
    /// Radius, m.
    Sphere(f64),
    /// Along the body's z axis.
    Capsule {
        /// Half the distance between the caps' centres, m.
        half_height: f64,
        /// Radius, m.
        radius: f64,
    },
    /// The convex hull of these points, m, body frame.
    Convex(Vec<[f64; 3]>),
}

impl From<&Shape> for ShapeInfo {
    fn from(s: &Shape) -> Self {
        match s {
            Shape::Box { half_extents_m } => ShapeInfo::Box(*half_extents_m),
            Shape::Sphere { radius_m } => ShapeInfo::Sphere(*radius_m),
            Shape::Capsule {
                half_height_m,
                radius_m,
            } => ShapeInfo::Capsule {
                half_height: *half_height_m,
                radius: *radius_m,
            },
            Shape::Convex { points_m } => ShapeInfo::Convex(points_m.clone()),
        }
    }
}

/// One finger.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct FingerInfo {
    /// Name.
    pub name: String,
    /// Its device's name.
    pub device: String,
    /// The body it holds.
    pub body: String,
    /// `point`, `rigid` or `contact`.
    pub grasp: String,
}

/// One device.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct DeviceInfo {
    /// Name.
    pub name: String,
    /// Model (`phantom-premium-1.5`, …, `virtual`).
    pub model: String,
    /// Peak force, N.
    pub peak_force_n: f64,
    /// Continuous force, N.
    pub continuous_force_n: f64,
}

impl SceneInfo {
    /// The description of `scene`.
    pub fn of(scene: &Scene) -> SceneInfo {
        let c = &scene.compiled;
        let model = &c.model;
        let mut links: Vec<Vec<[f64; 3]>> = vec![Vec::new(); model.bodies().len()];
        let mut add = |name: &str, p: [f64; 3]| {
            if let Some(id) = model.body_id(name) {
                let l = &mut links[id.index()];
                if !l.iter().any(|q| (0..3).all(|k| (q[k] - p[k]).abs() < 1e-9)) {
                    l.push(p);
                }
            }
        };
        for j in &scene.loaded.spec.joints {
            let [a, b] = &j.bodies.get_ref().0;
            let anchors = j
                .anchors
                .as_ref()
                .map_or([[0.0; 3]; 2], |a| a.get_ref().nested());
            add(a.get_ref(), anchors[0]);
            add(b.get_ref(), anchors[1]);
        }
        for f in model.fingers() {
            add(&model.bodies()[f.body.index()].name, f.point_m.into());
        }
        let mut absent = vec![false; model.bodies().len()];
        for b in &c.absent {
            absent[b.index()] = true;
        }
        let bodies = model
            .bodies()
            .iter()
            .zip(links)
            .zip(absent)
            .map(|((b, mut l), absent)| {
                if b.shape.is_none() && l.len() < 2 && !l.iter().any(|p| p == &[0.0; 3]) {
                    l.push([0.0; 3]);
                }
                let o = b.orientation.quaternion();
                BodyInfo {
                    name: b.name.clone(),
                    fixed: b.fixed,
                    shape: b.shape.as_ref().map(ShapeInfo::from),
                    links: if b.shape.is_some() { Vec::new() } else { l },
                    fingertip: b.fingertip,
                    position_m: b.position_m.into(),
                    orientation: [o.w, o.i, o.j, o.k],
                    absent,
                }
            })
            .collect();
        let fingers = c
            .fingers
            .iter()
            .map(|f| {
                let mf = &model.fingers()[f.finger.index()];
                FingerInfo {
                    name: f.name.clone(),
                    device: c.devices[f.device].name.clone(),
                    body: model.bodies()[mf.body.index()].name.clone(),
                    grasp: format!("{:?}", mf.grasp).to_lowercase(),
                }
            })
            .collect();
        let devices = c
            .devices
            .iter()
            .map(|d| {
                let (peak, continuous) = if d.model == VIRTUAL_MODEL {
                    let p = VirtualParams::default();
                    (p.peak_force_n, p.peak_force_n)
                } else {
                    PhantomModel::by_name(&d.model).map_or((f64::NAN, f64::NAN), |m| {
                        (m.peak_force_n, m.continuous_force_n)
                    })
                };
                DeviceInfo {
                    name: d.name.clone(),
                    model: d.model.clone(),
                    peak_force_n: peak,
                    continuous_force_n: continuous,
                }
            })
            .collect();
        SceneInfo {
            scene: c.name.clone(),
            description: c.description.clone(),
            gravity_m_s2: model.gravity_m_s2().into(),
            size_m: model.characteristic_length_m().max(moving_extent_m(model)),
            joints: scene.loaded.spec.joints.len(),
            bodies,
            fingers,
            devices,
        }
    }
}

/// Half the diagonal of the box around the moving bodies (their initial
/// positions and shapes), m: a scene without joints has no mechanism
/// length, but its bodies still need framing.
fn moving_extent_m(model: &haptloop_solver::Model) -> f64 {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for b in model.bodies().iter().filter(|b| !b.fixed) {
        let r = match &b.shape {
            Some(Shape::Box { half_extents_m: h }) => {
                (h[0] * h[0] + h[1] * h[1] + h[2] * h[2]).sqrt()
            }
            Some(Shape::Sphere { radius_m }) => *radius_m,
            Some(Shape::Capsule {
                half_height_m,
                radius_m,
            }) => half_height_m + radius_m,
            Some(Shape::Convex { points_m }) => points_m
                .iter()
                .map(|p| (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt())
                .fold(0.0, f64::max),
            None => 0.0,
        };
        for k in 0..3 {
            lo[k] = lo[k].min(b.position_m[k] - r);
            hi[k] = hi[k].max(b.position_m[k] + r);
        }
    }
    let d2: f64 = (0..3).map(|k| (hi[k] - lo[k]).powi(2)).sum();
    if d2.is_finite() { d2.sqrt() / 2.0 } else { 0.0 }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scenes::resolve;

    /// The four-bar has no shapes: every body is drawn through its joints'
    /// anchors, two or more per moving link, each anchor as the scene file
    /// writes it.
    #[test]
    fn shape_less_bodies_are_drawn_through_their_joint_anchors() {
        let scene = resolve("four-bar").unwrap();
        let info = SceneInfo::of(&scene);
        assert_eq!(info.bodies.len(), scene.compiled.model.bodies().len());
        for b in &info.bodies {
            assert!(b.shape.is_none());
            assert!(b.links.len() >= 2, "{}: {:?}", b.name, b.links);
        }
        for j in &scene.loaded.spec.joints {
            let [a, _] = &j.bodies.get_ref().0;
            let anchor = j.anchors.as_ref().unwrap().get_ref().nested()[0];
            let body = info.bodies.iter().find(|b| &b.name == a.get_ref()).unwrap();
            assert!(body.links.contains(&anchor), "{}: {anchor:?}", body.name);
        }
        let shaped = SceneInfo::of(&resolve("pinch-lift").unwrap());
        assert!(
            shaped
                .bodies
                .iter()
                .any(|b| b.shape.is_some() && b.links.is_empty())
        );
        assert_eq!(shaped.devices[0].peak_force_n, 8.5);
    }
}
