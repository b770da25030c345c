//! Hand-made furniture: boxes with offer areas on top and binding areas
//! underneath, built as a model plus a semantic spec.
#![allow(dead_code)] // shared by the test modules; not every module uses every helper

use haptloop_solver::geometry::{Pose3, Shape};
use haptloop_solver::semantic::{
    AreaKind, AreaSpec, SemanticScene, SemanticSettings, SemanticSpec,
};
use haptloop_solver::{BodyId, BodySpec, Model, ModelBuilder};
use nalgebra::{Matrix3, Rotation3, Unit, Vector3};

/// A box body: name, fixed, centre, half extents.
#[derive(Debug, Clone)]
pub struct Obj {
    pub name: &'static str,
    pub fixed: bool,
    pub at: [f64; 3],
    pub half: [f64; 3],
}

pub fn obj(name: &'static str, fixed: bool, at: [f64; 3], half: [f64; 3]) -> Obj {
    Obj {
        name,
        fixed,
        at,
        half,
    }
}

/// A rectangle in the plane z = `z` of half sizes `hx`, `hy` about (cx, cy).
pub fn rect(cx: f64, cy: f64, hx: f64, hy: f64, z: f64) -> Vec<[f64; 3]> {
    vec![
        [cx - hx, cy - hy, z],
        [cx + hx, cy - hy, z],
        [cx + hx, cy + hy, z],
        [cx - hx, cy + hy, z],
    ]
}

/// The whole top face of `o` as an offer labelled `label`.
pub fn top(body: u32, o: &Obj, label: &str) -> AreaSpec {
    AreaSpec {
        body: BodyId(body),
        kind: AreaKind::Offer,
        label: label.into(),
        polygon_m: rect(0.0, 0.0, o.half[0], o.half[1], o.half[2]),
        normal: [0.0, 0.0, 1.0],
    }
}

/// The whole bottom face of `o` as a binding labelled `label`.
pub fn bottom(body: u32, o: &Obj, label: &str) -> AreaSpec {
    AreaSpec {
        body: BodyId(body),
        kind: AreaKind::Binding,
        label: label.into(),
        polygon_m: rect(0.0, 0.0, o.half[0], o.half[1], -o.half[2]),
        normal: [0.0, 0.0, -1.0],
    }
}

/// A binding on part of the bottom face of `o` (about (cx, cy), half sizes).
pub fn foot(body: u32, o: &Obj, label: &str, cx: f64, cy: f64, hx: f64, hy: f64) -> AreaSpec {
    AreaSpec {
        body: BodyId(body),
        kind: AreaKind::Binding,
        label: label.into(),
        polygon_m: rect(cx, cy, hx, hy, -o.half[2]),
        normal: [0.0, 0.0, -1.0],
    }
}

/// The model of `objs` (boxes at their centres) and the spec.
pub fn build(
    objs: &[Obj],
    areas: Vec<AreaSpec>,
    order: &[(&str, &str)],
    settings: SemanticSettings,
) -> (Model, SemanticSpec) {
    let mut b = ModelBuilder::new();
    for o in objs {
        let spec = if o.fixed {
            BodySpec::fixed(o.name)
        } else {
            BodySpec::new(o.name)
        };
        b.body(spec.at(o.at).shape(Shape::Box {
            half_extents_m: o.half,
        }));
    }
    let model = b.build().expect("model");
    let spec = SemanticSpec {
        areas,
        order: order
            .iter()
            .map(|(a, b)| ((*a).to_owned(), (*b).to_owned()))
            .collect(),
        labels: Vec::new(),
        settings,
    };
    (model, spec)
}

/// The semantic scene of `objs` at their initial poses, aligned bindings
/// satisfied, checked consistent.
pub fn scene(objs: &[Obj], areas: Vec<AreaSpec>, order: &[(&str, &str)]) -> SemanticScene {
    let (model, spec) = build(objs, areas, order, settings());
    let mut s = SemanticScene::from_model(&model, model.q0(), &spec).expect("scene");
    s.satisfy_aligned();
    s.consistent().expect("a consistent start");
    s
}

/// Tight tolerances for the discrete tests.
pub fn settings() -> SemanticSettings {
    SemanticSettings {
        collision_tolerance_m: 1e-9,
        align_tolerance: 1e-9,
        ..SemanticSettings::default()
    }
}

/// The body called `name`.
pub fn id(s: &SemanticScene, name: &str) -> BodyId {
    BodyId(
        s.objects()
            .iter()
            .position(|o| o.name == name)
            .unwrap_or_else(|| panic!("no {name}")) as u32,
    )
}

/// A pose at `r` rotated by `angle` about `axis`.
pub fn pose(r: [f64; 3], axis: [f64; 3], angle: f64) -> Pose3 {
    let rot = Rotation3::from_axis_angle(&Unit::new_normalize(Vector3::from(axis)), angle);
    Pose3 {
        r: Vector3::from(r),
        rot: rot.into_inner(),
    }
}

/// The identity pose at `r`.
pub fn at(r: [f64; 3]) -> Pose3 {
    Pose3 {
        r: Vector3::from(r),
        rot: Matrix3::identity(),
    }
}

/// The grouping graph by names.
pub fn graph(s: &SemanticScene) -> Vec<(String, String)> {
    let mut v: Vec<(String, String)> = s
        .edges()
        .into_iter()
        .map(|(a, b)| (s.name(a).to_owned(), s.name(b).to_owned()))
        .collect();
    v.sort();
    v
}

pub fn edges(list: &[(&str, &str)]) -> Vec<(String, String)> {
    let mut v: Vec<(String, String)> = list
        .iter()
        .map(|(a, b)| ((*a).to_owned(), (*b).to_owned()))
        .collect();
    v.sort();
    v
}
