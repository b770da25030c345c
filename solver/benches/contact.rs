//! Criterion benches of contact (BENCHMARKS.md, contact section), one run
//! for every figure:
//!
//! - `witness/query_warm/hull20`: the narrow phase of one separated pair of
//!   20-vertex hulls, warm-started from the last answer (GJK on the cores,
//!   the support-set feature classifier);
//! - `witness/pair_update/{hull20,box_on_table}`: one active-set cycle of a
//!   single tracked pair: broad phase, narrow phase, primitives, guards,
//!   slot choice (the whole per-pair witness update);
//! - `cycle/cluttered/{25,100,400}`: one active-set cycle of the cluttered
//!   table (n objects resting on it, the dragged box among them), the slow
//!   loop's contact work per cycle;
//! - `tick/contacts/{rows}_rows_{n}_boxes`: one fast tick (projected
//!   update, 4 steps, Eq. 7–8) of boxes on a table with inertial motion: a
//!   box in the air (no contact row), one box resting on it, eight, sixteen; the
//!   label says how many contact rows the tick had active.
//!
//! Run: `CARGO_TARGET_DIR=target/contact cargo bench -p haptloop-solver --bench contact`

use std::hint::black_box;
use std::sync::Arc;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use haptloop_solver::contact::{ContactManager, contact_bodies};
use haptloop_solver::geometry::narrow::{PairCache, query_pair};
use haptloop_solver::geometry::{ActiveSet, ContactSettings, Pose3, Shape};
use haptloop_solver::mechanisms::cluttered_builder;
use haptloop_solver::{BodyId, BodySpec, FingerSpec, FingerTarget, ModelBuilder, SolverSettings};
use nalgebra::{Matrix3, Rotation3, Vector3};

/// A 20-vertex convex hull (a jittered icosahedron-like point set), 2 cm.
fn hull20() -> Shape {
    let mut pts = Vec::new();
    let golden = (1.0 + 5f64.sqrt()) / 2.0;
    for k in 0..20 {
        let z = 1.0 - 2.0 * (k as f64 + 0.5) / 20.0;
        let r = (1.0 - z * z).sqrt();
        let a = std::f64::consts::TAU * k as f64 / golden;
        pts.push([0.02 * r * a.cos(), 0.02 * r * a.sin(), 0.02 * z]);
    }
    Shape::Convex { points_m: pts }
}

fn pose(r: [f64; 3], axis: [f64; 3], angle: f64) -> Pose3 {
    Pose3 {
        r: Vector3::from(r),
        rot: Rotation3::from_axis_angle(&nalgebra::Unit::new_normalize(Vector3::from(axis)), angle)
            .into_inner(),
    }
}

fn witness(c: &mut Criterion) {
    let mut g = c.benchmark_group("witness");
    let a = hull20().collider().unwrap();
    let b = hull20().collider().unwrap();
    let (pa, pb) = (
        pose([0.0, 0.0, 0.0], [0.3, 1.0, 0.2], 0.7),
        pose([0.003, 0.001, 0.043], [1.0, -0.4, 0.1], 1.9),
    );
    let mut cache = PairCache::default();
    query_pair(&a, &pa, &b, &pb, 0.02, &mut cache).expect("close");
    g.bench_function("query_warm/hull20", |bch| {
        bch.iter(|| black_box(query_pair(&a, &pa, &b, &pb, 0.02, &mut cache)))
    });
    // One tracked pair through the whole cycle, poses moving a hair each
    // cycle (as under a hand) so nothing is skipped.
    for (name, sa, sb, pb0) in [
        (
            "hull20",
            hull20(),
            hull20(),
            pose([0.003, 0.001, 0.043], [1.0, -0.4, 0.1], 1.9),
        ),
        (
            "box_on_table",
            Shape::Box {
                half_extents_m: [0.03; 3],
            },
            Shape::Box {
                half_extents_m: [0.2, 0.2, 0.02],
            },
            pose([0.0, 0.0, -0.05], [0.0, 0.0, 1.0], 0.0),
        ),
    ] {
        let body = |s: Shape, fixed: bool| {
            Some(haptloop_solver::geometry::ContactBody {
                collider: s.collider().unwrap(),
                fixed,
                fingertip: false,
                friction: 0.0,
            })
        };
        let mut set = ActiveSet::new(
            vec![body(sa, false), body(sb, true)],
            Vec::new(),
            ContactSettings::default(),
        );
        let mut poses = [Pose3::IDENTITY, pb0];
        set.update(&poses);
        let mut k = 0u64;
        g.bench_function(format!("pair_update/{name}"), |bch| {
            bch.iter(|| {
                k += 1;
                poses[0].r.x = 1e-6 * (k % 7) as f64;
                black_box(set.update(&poses))
            })
        });
    }
    g.finish();
}

fn cycle(c: &mut Criterion) {
    let mut g = c.benchmark_group("cycle");
    g.sample_size(20).measurement_time(Duration::from_secs(4));
    for n in [25usize, 100, 400] {
        let model = cluttered_builder(n).build().unwrap();
        let bodies = contact_bodies(&model, false);
        let mut set = ActiveSet::new(bodies, Vec::new(), ContactSettings::default());
        let q = model.q0();
        let mut poses: Vec<Pose3> = (0..model.bodies().len())
            .map(|i| {
                let id = BodyId(i as u32);
                Pose3 {
                    r: model.body_position(q, id).unwrap(),
                    rot: model.body_rotation(q, id).unwrap_or(Matrix3::identity()),
                }
            })
            .collect();
        set.update(&poses);
        let dragged = poses.len() - 1;
        let mut k = 0u64;
        g.bench_function(format!("cluttered/{n}"), |bch| {
            bch.iter(|| {
                k += 1;
                poses[dragged].r.x += if k.is_multiple_of(2) { 1e-4 } else { -1e-4 };
                black_box(set.update(&poses))
            })
        });
    }
    g.finish();
}

/// `boxes` 4 cm boxes on a table (or one in the air for `boxes = 0`), a
/// contact finger beside them, inertial motion: the program the session
/// would start with, and its targets.
fn resting(boxes: usize) -> (haptloop_solver::Program, Vec<FingerTarget>) {
    let mut b = ModelBuilder::new();
    b.gravity([0.0, 0.0, -9.81]);
    b.body(
        BodySpec::fixed("table")
            .at([0.0, 0.0, -0.02])
            .shape(Shape::Box {
                half_extents_m: [0.3, 0.3, 0.02],
            }),
    );
    let n = boxes.max(1);
    for k in 0..n {
        let z = if boxes == 0 { 0.1 } else { 0.02 };
        b.body(
            BodySpec::new(format!("box{k}"))
                .at([0.06 * (k % 4) as f64, 0.06 * (k / 4) as f64 - 0.1, z])
                .shape(Shape::Box {
                    half_extents_m: [0.02; 3],
                }),
        );
    }
    b.finger(FingerSpec::contact("index", [-0.1, 0.0, 0.05], 0.008, 0.0));
    let model = Arc::new(b.build().unwrap());
    let settings = SolverSettings {
        dynamics: true,
        contact_step_m: 1e-3,
        ..SolverSettings::default()
    };
    let mut m = ContactManager::new(model.clone(), settings, ContactSettings::default()).unwrap();
    let (_, mut p) = m.initial(model.q0()).unwrap();
    let t = model.initial_targets();
    // Settle: resting contacts active.
    for _ in 0..50 {
        p.tick(&t, Duration::from_millis(1));
    }
    (p, t)
}

fn tick(c: &mut Criterion) {
    let mut g = c.benchmark_group("tick");
    // Resting boxes share their weight over their corners: which rows carry
    // it (are active) is the solve's choice, so the label is the count
    // measured, not the boxes' corners.
    for boxes in [0usize, 1, 8, 16] {
        let (mut p, t) = resting(boxes);
        let active = p.last_report().active_contacts;
        g.bench_function(format!("contacts/{active}_rows_{boxes}_boxes"), |bch| {
            bch.iter(|| black_box(p.tick(&t, Duration::from_millis(1))))
        });
    }
    g.finish();
}

criterion_group!(benches, witness, cycle, tick);
criterion_main!(benches);
