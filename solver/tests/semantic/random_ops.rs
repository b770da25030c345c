//! consistent(s) after every operation (§3.3): random sequences of moves
//! (checkMove then the allowed part), snaps (Algorithm 1), breaks and
//! exception-list updates on a small furnished scene keep it consistent,
//! whatever the order. Fixed seed; the operations are counted so a run that
//! never snapped or broke anything fails.

use std::cell::Cell;

use haptloop_solver::BodyId;
use haptloop_solver::semantic::{AreaId, Move, SemanticScene};
use nalgebra::Vector3;
use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed, TestRunner};

use crate::common::*;

fn furnished() -> SemanticScene {
    let objs = vec![
        obj("floor", true, [0.0, 0.0, -0.05], [2.0, 2.0, 0.05]),
        obj("wall", true, [0.0, -0.85, 0.5], [2.0, 0.05, 0.5]),
        obj("table", false, [0.0, 0.0, 0.2], [0.3, 0.2, 0.2]),
        obj("desk", false, [0.75, 0.0, 0.2], [0.2, 0.2, 0.2]),
        obj("cup", false, [0.1, 0.0, 0.43], [0.03, 0.03, 0.03]),
        obj("mug", false, [-0.1, 0.05, 0.435], [0.025, 0.025, 0.035]),
        obj("tray", false, [0.75, 0.0, 0.41], [0.1, 0.1, 0.01]),
        obj("picture", false, [-0.5, -0.785, 0.6], [0.1, 0.01, 0.08]),
    ];
    use haptloop_solver::semantic::{AreaKind, AreaSpec};
    let wall_face = AreaSpec {
        body: BodyId(1),
        kind: AreaKind::Offer,
        label: "on-wall".into(),
        polygon_m: vec![
            [-2.0, 0.05, -0.5],
            [2.0, 0.05, -0.5],
            [2.0, 0.05, 0.5],
            [-2.0, 0.05, 0.5],
        ],
        normal: [0.0, 1.0, 0.0],
    };
    let picture_back = AreaSpec {
        body: BodyId(7),
        kind: AreaKind::Binding,
        label: "on-wall".into(),
        polygon_m: vec![
            [-0.1, -0.01, -0.08],
            [0.1, -0.01, -0.08],
            [0.1, -0.01, 0.08],
            [-0.1, -0.01, 0.08],
        ],
        normal: [0.0, -1.0, 0.0],
    };
    let areas = vec![
        top(0, &objs[0], "on-floor"),
        wall_face,
        bottom(2, &objs[2], "on-floor"),
        top(2, &objs[2], "on-workspace"),
        bottom(3, &objs[3], "on-floor"),
        top(3, &objs[3], "on-workspace"),
        bottom(4, &objs[4], "on-workspace"),
        bottom(5, &objs[5], "on-workspace"),
        bottom(6, &objs[6], "on-workspace"),
        top(6, &objs[6], "on-workspace"),
        picture_back,
    ];
    scene(&objs, areas, &[("on-workspace", "on-floor")])
}

/// Counts of operations that changed something.
#[derive(Debug, Default, Clone, Copy)]
struct Done {
    moves: u32,
    snaps: u32,
    breaks: u32,
    releases: u32,
}

#[test]
fn random_operation_sequences_keep_the_scene_consistent() {
    let base = furnished();
    assert_eq!(
        graph(&base),
        edges(&[
            ("desk", "tray"),
            ("floor", "desk"),
            ("floor", "table"),
            ("table", "cup"),
            ("table", "mug"),
        ])
    );
    let done = Cell::new(Done::default());
    let config = Config {
        cases: 64,
        rng_seed: RngSeed::Fixed(0xc0_5157),
        failure_persistence: None,
        ..Config::default()
    };
    // Each step: (op, object, area, 6 numbers).
    let step = (
        0u8..10,
        0usize..8,
        0usize..11,
        prop::array::uniform6(-1.0f64..1.0),
    );
    TestRunner::new(config)
        .run(&prop::collection::vec(step, 40), |steps| {
            let mut s = base.clone();
            let mut d = done.get();
            for (k, (op, o, a, u)) in steps.into_iter().enumerate() {
                let o = BodyId(o as u32);
                let a = AreaId(a as u32);
                let what = match op {
                    // Moves dominate: 2 cm and 0.1 rad at most per step, up
                    // to 8 cm straight up (to lift things off).
                    0..=5 => {
                        let lift = if op == 5 { 0.08 * u[2].abs() } else { 0.0 };
                        let mv = Move {
                            center: s.pose(o).r,
                            t: Vector3::new(0.02 * u[0], 0.02 * u[1], 0.02 * u[2] + lift),
                            r: Vector3::new(0.1 * u[3], 0.1 * u[4], 0.1 * u[5]),
                        };
                        let m = s.move_object(o, mv);
                        d.moves += u32::from(!m.is_none());
                        "move"
                    }
                    6 | 7 => {
                        d.snaps += u32::from(s.satisfy(a, false).is_some());
                        "satisfy"
                    }
                    8 => {
                        d.breaks += u32::from(s.break_bond(a).is_some());
                        "break"
                    }
                    _ => {
                        d.releases += s.update_exceptions().len() as u32;
                        "update exceptions"
                    }
                };
                if let Err(e) = s.consistent() {
                    return Err(TestCaseError::fail(format!(
                        "step {k} ({what} of {}): {e}",
                        s.name(o)
                    )));
                }
            }
            done.set(d);
            Ok(())
        })
        .unwrap();
    let d = done.get();
    assert!(
        d.moves > 100 && d.snaps > 10 && d.breaks > 10 && d.releases > 3,
        "every kind of operation happened: {d:?}"
    );
}

/// A snap never makes two shapes collide: the cup dropped at random poses
/// within snap range of a table crowded with a mug and a tray (and a picture
/// near the wall); every snap that happens leaves no collision, and every
/// snap refused leaves the scene as it was.
#[test]
fn a_snap_never_makes_two_shapes_collide() {
    let base = furnished();
    let (cup, cup_b) = (BodyId(4), base.objects()[4].bindings[0]);
    let counts = Cell::new([0u32; 3]);
    let config = Config {
        cases: 400,
        rng_seed: RngSeed::Fixed(0x5a4b),
        failure_persistence: None,
        ..Config::default()
    };
    TestRunner::new(config)
        .run(&prop::array::uniform6(-1.0f64..1.0), |u| {
            let mut s = base.clone();
            s.break_bond(cup_b);
            s.update_exceptions();
            // Anywhere over the table or the desk's tray, the bottom's centre
            // 3.5–9.5 mm over the surface, tilted up to 0.1 rad about it.
            let (x, surface) = if u[0] > 0.0 {
                (0.75 + 0.1 * u[1], 0.42)
            } else {
                (0.3 * u[1], 0.4)
            };
            let bottom = Vector3::new(x, 0.2 * u[2], surface + 0.0035 + 0.006 * u[3].abs());
            let pose = Move {
                center: bottom,
                t: Vector3::zeros(),
                r: Vector3::new(0.07 * u[4], 0.07 * u[5], 0.0),
            }
            .apply(&at([bottom.x, bottom.y, bottom.z + 0.03]));
            s.set_pose(cup, pose);
            let mut c = counts.get();
            if !s.collisions().is_empty() {
                c[2] += 1; // a start that already collides says nothing
                counts.set(c);
                return Ok(());
            }
            let before = s.clone();
            match s.satisfy(cup_b, false) {
                Some(_) => {
                    c[0] += 1;
                    prop_assert!(s.collisions().is_empty(), "{:?}", s.collisions());
                    prop_assert!(s.consistent().is_ok());
                }
                None => {
                    c[1] += 1;
                    for (o, p) in s.objects().iter().zip(before.objects()) {
                        prop_assert_eq!(o.pose, p.pose);
                    }
                }
            }
            counts.set(c);
            Ok(())
        })
        .unwrap();
    // Measured: 62 snapped, 325 refused (mostly not close: over an edge),
    // 13 starts already colliding.
    let [snapped, refused, _] = counts.get();
    assert!(
        snapped > 30 && refused > 30,
        "snapped {snapped}, refused {refused}"
    );
}
