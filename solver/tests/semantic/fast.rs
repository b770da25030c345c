//! Semantic rows in the fast loop (`program/semantic.rs`): a snap is a
//! bounded pull (its offsets shrink at the snap speed, and pause while the
//! finger's force has moved by the snap force limit), a dragged table
//! carries the cup on it, the inclusion rows stop a cup at the table's
//! edge, and a tick with all of it allocates nothing.

use std::sync::Arc;
use std::time::Duration;

use haptloop_rt::alloc::count;
use haptloop_solver::geometry::Shape;
use haptloop_solver::semantic::{SemanticScene, relation};
use haptloop_solver::{
    BodyId, BodySpec, FingerSpec, FingerTarget, Model, ModelBuilder, Program, SnapSettings,
    SolverSettings, TickOutcome,
};
use nalgebra::{UnitQuaternion, Vector3};

use crate::common::*;

const DT: Duration = Duration::from_millis(1);

/// Floor (fixed), a table (fixed or not), a cup held at its top centre by
/// a point finger, at `cup` (the cup's centre) turned `tilt` about x.
fn setup(table_fixed: bool, cup: [f64; 3], tilt: f64) -> (Model, SemanticScene, Vec<f64>) {
    let objs = vec![
        obj("floor", true, [0.0, 0.0, -0.05], [1.0, 1.0, 0.05]),
        obj("table", table_fixed, [0.0, 0.0, 0.2], [0.3, 0.2, 0.2]),
        obj("cup", false, [0.1, 0.0, 0.5], [0.03, 0.03, 0.03]),
    ];
    let areas = vec![
        top(0, &objs[0], "on-floor"),
        bottom(1, &objs[1], "on-floor"),
        top(1, &objs[1], "on-workspace"),
        bottom(2, &objs[2], "on-workspace"),
    ];
    let mut b = ModelBuilder::new();
    for o in &objs {
        let s = if o.fixed {
            BodySpec::fixed(o.name)
        } else {
            BodySpec::new(o.name)
        };
        b.body(s.at(o.at).shape(Shape::Box {
            half_extents_m: o.half,
        }));
    }
    b.finger(FingerSpec::point("hand", "cup", [0.0, 0.0, 0.03]));
    let base = b.build().unwrap();
    let (_, spec) = build(&objs, areas, &[], settings());
    let mut s = SemanticScene::from_model(&base, base.q0(), &spec).unwrap();
    s.satisfy_aligned();
    let mut q = base.q0().to_vec();
    let o = base.layout().body_offset(BodyId(2)).unwrap();
    let e = UnitQuaternion::from_scaled_axis(Vector3::x() * tilt);
    q[o..o + 3].copy_from_slice(&cup);
    q[o + 3..o + 7].copy_from_slice(&[e.w, e.i, e.j, e.k]);
    s.set_pose(BodyId(2), pose(cup, [1.0, 0.0, 0.0], tilt));
    (base, s, q)
}

fn target(model: &Model, q: &[f64]) -> Vec<FingerTarget> {
    vec![FingerTarget {
        position_m: model.finger_point(q, haptloop_solver::FingerId(0)).unwrap(),
        orientation: UnitQuaternion::identity(),
    }]
}

/// The program of `base` plus the scene's satisfied constraints, taken over
/// from a program of `base` that ran at `q`.
fn snapped(base: &Model, s: &SemanticScene, q: &[f64], snap: SnapSettings) -> (Model, Program) {
    let settings = SolverSettings::default();
    let mut before = Program::new(Arc::new(base.clone()), settings).unwrap();
    before.set_q(q).unwrap();
    let t = target(base, q);
    for _ in 0..5 {
        assert_eq!(before.tick(&t, DT).status, TickOutcome::Ok);
    }
    let model = base.with_semantic(&s.surface_specs(), &[], snap).unwrap();
    let mut p = Program::new(Arc::new(model.clone()), settings).unwrap();
    p.adopt_state(&before);
    (model, p)
}

/// The cup's binding area against the table's top at the program's q.
fn rel(model: &Model, s: &SemanticScene, q: &[f64]) -> haptloop_solver::semantic::Relation {
    let pose = |b: u32| haptloop_solver::geometry::Pose3 {
        r: model.body_position(q, BodyId(b)).unwrap(),
        rot: model.body_rotation(q, BodyId(b)).unwrap(),
    };
    relation(
        s.area(s.objects()[2].bindings[0]),
        &pose(2),
        s.area(s.objects()[1].offers[0]),
        &pose(1),
    )
}

#[test]
fn a_snap_closes_at_the_snap_speed_and_its_pull_stays_under_the_limit() {
    // Cup bottom 6 mm over the fixed table, tilted 0.1 rad; the hand stays.
    let (base, mut s, q) = setup(true, [0.1, -0.003, 0.436], 0.1);
    let b = s.objects()[2].bindings[0];
    let before = s.search_close(b)[0].relation;
    assert!(s.satisfy(b, true).is_some());
    let snap = SnapSettings {
        speed_m_per_s: 0.02,
        force_limit_n: 1.5,
    };
    let (model, mut p) = snapped(&base, &s, &q, snap);
    let t = target(&base, &q);
    assert_eq!(p.snaps_ramping(), 1);
    let r0 = rel(&model, &s, p.q());
    assert!(
        (r0.off_plane_m - before.off_plane_m).abs() < 1e-9,
        "no jump at the hand-over"
    );
    let f0 = p.finger_outputs()[0].force_n;
    let (mut last_f, mut max_df, mut max_pull): (Vector3<f64>, f64, f64) = (f0, 0.0, 0.0);
    let mut last_off = r0.off_plane_m;
    for k in 0..2000 {
        assert_eq!(p.tick(&t, DT).status, TickOutcome::Ok, "tick {k}");
        let f = p.finger_outputs()[0].force_n;
        max_df = max_df.max((f - last_f).norm());
        max_pull = max_pull.max((f - f0).norm());
        last_f = f;
        let r = rel(&model, &s, p.q());
        // Never faster than the snap speed (the largest offset leads).
        assert!(
            last_off - r.off_plane_m <= snap.speed_m_per_s * 1e-3 * 1.05 + 1e-9,
            "tick {k}: moved {} m",
            last_off - r.off_plane_m
        );
        last_off = r.off_plane_m;
    }
    // The hand held still: the coupling stretched until the limit paused it.
    assert!(p.snap_paused_ticks() > 100, "{}", p.snap_paused_ticks());
    assert_eq!(p.snaps_ramping(), 1, "still arriving");
    assert!(
        max_pull <= snap.force_limit_n + 0.05,
        "the snap pulled {max_pull} N (limit {} N)",
        snap.force_limit_n
    );
    assert!(
        max_pull > 0.8 * snap.force_limit_n,
        "it did pull: {max_pull} N"
    );
    // Per tick: one tick's ramp through the coupling (k v dt = 8 mN) plus the
    // cup's inertia switching from accelerating to braking (2 m a, 0.17 N
    // at most, here mostly across the finger's line): small against the
    // safety layer's 2 N per tick, and no jump.
    assert!(max_df < 0.1, "largest per-tick change {max_df} N");
}

#[test]
fn a_yielding_hand_lets_the_snap_arrive() {
    let (base, mut s, q) = setup(true, [0.1, -0.003, 0.436], 0.1);
    let b = s.objects()[2].bindings[0];
    assert!(s.satisfy(b, true).is_some());
    let snapped_pose = s.pose(BodyId(2));
    let snap = SnapSettings {
        speed_m_per_s: 0.02,
        force_limit_n: 1.5,
    };
    let (model, mut p) = snapped(&base, &s, &q, snap);
    // The hand follows the cup: each tick's target is where its finger point
    // went (the user gives way).
    for _ in 0..1500 {
        let t = target(&model, p.q());
        assert_eq!(p.tick(&t, DT).status, TickOutcome::Ok);
    }
    assert_eq!(p.snaps_ramping(), 0);
    let r = rel(&model, &s, p.q());
    assert!(r.off_plane_m < 1e-6 && r.angle_rad < 1e-5, "{r:?}");
    // Where the discrete snap put it: its position differs only by what the
    // finger's pull did in the plane.
    let z = model.body_position(p.q(), BodyId(2)).unwrap().z;
    assert!(
        (z - snapped_pose.r.z).abs() < 1e-5,
        "{z} vs {}",
        snapped_pose.r.z
    );
}

/// A model of `objs` (boxes) with a point finger on `held` at `point`, and
/// the scene's aligned constraints as rows.
fn held_model(objs: &[Obj], held: &str, point: [f64; 3]) -> (Arc<Model>, SemanticScene) {
    let areas = vec![
        top(0, &objs[0], "on-floor"),
        bottom(1, &objs[1], "on-floor"),
        top(1, &objs[1], "on-workspace"),
        bottom(2, &objs[2], "on-workspace"),
    ];
    let mut b = ModelBuilder::new();
    for o in objs {
        let sp = if o.fixed {
            BodySpec::fixed(o.name)
        } else {
            BodySpec::new(o.name)
        };
        b.body(sp.at(o.at).shape(Shape::Box {
            half_extents_m: o.half,
        }));
    }
    b.finger(FingerSpec::point("hand", held, point));
    let base = b.build().unwrap();
    let (_, spec) = build(objs, areas, &[], settings());
    let mut s = SemanticScene::from_model(&base, base.q0(), &spec).unwrap();
    s.satisfy_aligned();
    let model = base
        .with_semantic(&s.surface_specs(), &[], SnapSettings::default())
        .unwrap();
    (Arc::new(model), s)
}

/// The hand's target moves by `by` over `ticks`, then holds for 200 ticks.
fn drag(p: &mut Program, start: Vector3<f64>, by: Vector3<f64>, ticks: u32) {
    for k in 1..=ticks + 200 {
        let f = (f64::from(k) / f64::from(ticks)).min(1.0);
        let t = vec![FingerTarget {
            position_m: start + by * f,
            orientation: UnitQuaternion::identity(),
        }];
        assert_eq!(p.tick(&t, DT).status, TickOutcome::Ok, "tick {k}");
    }
}

#[test]
fn dragging_the_table_carries_the_cup() {
    let objs = vec![
        obj("floor", true, [0.0, 0.0, -0.05], [1.0, 1.0, 0.05]),
        obj("table", false, [0.0, 0.0, 0.2], [0.3, 0.2, 0.2]),
        obj("cup", false, [0.1, 0.05, 0.43], [0.03, 0.03, 0.03]),
    ];
    let (model, s) = held_model(&objs, "table", [-0.3, 0.0, 0.2]);
    assert_eq!(model.semantic().surfaces.len(), 2);
    let mut p = Program::new(model.clone(), SolverSettings::default()).unwrap();
    let start = target(&model, model.q0())[0].position_m;
    let cup0 = model.body_position(model.q0(), BodyId(2)).unwrap();
    drag(&mut p, start, Vector3::new(0.1, 0.04, 0.0), 1000);
    let q = p.q();
    let grip = model.finger_point(q, haptloop_solver::FingerId(0)).unwrap();
    assert!(
        (grip - start - Vector3::new(0.1, 0.04, 0.0)).norm() < 2e-3,
        "the table's grip followed the hand: {grip:?}"
    );
    // The cup's pose in the table's frame is what it was (the table also
    // turned: it was pulled sideways by its end).
    let in_table = |q: &[f64]| {
        let (rt, at) = (
            model.body_position(q, BodyId(1)).unwrap(),
            model.body_rotation(q, BodyId(1)).unwrap(),
        );
        let (rc, ac) = (
            model.body_position(q, BodyId(2)).unwrap(),
            model.body_rotation(q, BodyId(2)).unwrap(),
        );
        (at.transpose() * (rc - rt), at.transpose() * ac)
    };
    let (p0, a0) = in_table(model.q0());
    let (p1, a1) = in_table(q);
    let turned = model.body_rotation(q, BodyId(1)).unwrap();
    assert!(
        (turned - nalgebra::Matrix3::identity()).norm() > 0.01,
        "the table turned"
    );
    assert!(
        (p1 - p0).norm() < 1e-4,
        "the cup rode on the table: {:?}",
        p1 - p0
    );
    assert!((a1 - a0).norm() < 1e-4);
    let _ = cup0;
    let r = rel(&model, &s, q);
    assert!(r.off_plane_m < 1e-7 && r.outside_m < 0.0, "{r:?}");
}

#[test]
fn the_table_edge_stops_a_cup_slid_off_it_and_the_hand_feels_it() {
    let objs = vec![
        obj("floor", true, [0.0, 0.0, -0.05], [1.0, 1.0, 0.05]),
        obj("table", true, [0.0, 0.0, 0.2], [0.3, 0.2, 0.2]),
        obj("cup", false, [0.1, 0.05, 0.43], [0.03, 0.03, 0.03]),
    ];
    let (model, s) = held_model(&objs, "cup", [0.0, 0.0, 0.03]);
    let mut p = Program::new(model.clone(), SolverSettings::default()).unwrap();
    let start = target(&model, model.q0())[0].position_m;
    // 30 cm toward +x: the cup's far face reaches the edge (x = 0.3) after 17 cm.
    drag(&mut p, start, Vector3::new(0.3, 0.0, 0.0), 500);
    let r = rel(&model, &s, p.q());
    assert!(r.outside_m.abs() < 1e-6, "at the edge: {r:?}");
    assert!(r.off_plane_m < 1e-7, "still on the table: {r:?}");
    let f = p.finger_outputs()[0].force_n;
    assert!(f.x < -1.0, "the edge pushes the hand back: {f}");
}

#[test]
fn a_tick_with_ramping_and_carried_semantic_rows_allocates_nothing() {
    let (base, mut s, q) = setup(false, [0.1, -0.003, 0.436], 0.1);
    let b = s.objects()[2].bindings[0];
    assert!(s.satisfy(b, true).is_some());
    let (_, mut p) = snapped(&base, &s, &q, SnapSettings::default());
    assert_eq!(p.snaps_ramping(), 1);
    let t = target(&base, &q);
    p.tick(&t, DT);
    let (_, stats) = count(|| {
        for _ in 0..50 {
            p.tick(&t, DT);
        }
    });
    assert_eq!(stats.total(), 0, "{stats:?}");
}
