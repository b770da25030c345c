//! The paper's special cases: a binding close to two fitting offers
//! (Algorithm 1 tries them nearest first and satisfies one), undirected
//! cycles (§4.1, Fig. 5–6: only successors move with an object), and an
//! object on two supports.

use haptloop_solver::BodyId;
use haptloop_solver::semantic::{AreaKind, AreaSpec, Move};
use nalgebra::Vector3;

use crate::common::*;

fn area(body: u32, kind: AreaKind, label: &str, poly: Vec<[f64; 3]>, n: [f64; 3]) -> AreaSpec {
    AreaSpec {
        body: BodyId(body),
        kind,
        label: label.into(),
        polygon_m: poly,
        normal: n,
    }
}

/// A sideboard (fixed, its front face at y = 0) with two offers for a box's
/// back: the front face itself, and a panel area tilted 0.02 rad drawn in
/// front of it, 2 mm from the box's back at its centre. The box's back is
/// 5 mm in front of the face (the box stands on the floor when `on_floor`).
/// The panel is the nearer: 2 mm + 0.02 rad × 7 cm against 5 mm.
fn two_offers(on_floor: bool) -> haptloop_solver::semantic::SemanticScene {
    let objs = vec![
        obj("floor", true, [0.0, 0.0, -0.05], [1.0, 1.0, 0.05]),
        obj("sideboard", true, [0.0, -0.2, 0.4], [0.5, 0.2, 0.4]),
        obj(
            "box",
            false,
            [0.0, 0.105, if on_floor { 0.1 } else { 0.12 }],
            [0.1, 0.1, 0.1],
        ),
    ];
    let th = 0.02f64;
    let zc = objs[2].at[2];
    // The tilted area: about the point (0, 0.003, zc) (world), turned about x.
    let tilted: Vec<[f64; 3]> = [[-0.2, -0.2], [0.2, -0.2], [0.2, 0.2], [-0.2, 0.2]]
        .iter()
        .map(|[x, z]| {
            // In the plane spanned by x and (0, sin θ, cos θ) through the point.
            let p = [*x, 0.003 + z * th.sin(), zc + z * th.cos()];
            [p[0], p[1] + 0.2, p[2] - 0.4] // sideboard frame
        })
        .collect();
    let areas = vec![
        top(0, &objs[0], "on-floor"),
        area(
            1,
            AreaKind::Offer,
            "on-wall",
            vec![
                [-0.5, 0.2, -0.4],
                [0.5, 0.2, -0.4],
                [0.5, 0.2, 0.4],
                [-0.5, 0.2, 0.4],
            ],
            [0.0, 1.0, 0.0],
        ),
        area(
            1,
            AreaKind::Offer,
            "on-wall",
            tilted,
            [0.0, th.cos(), -th.sin()],
        ),
        bottom(2, &objs[2], "on-floor"),
        area(
            2,
            AreaKind::Binding,
            "on-wall",
            vec![
                [-0.05, -0.1, -0.05],
                [0.05, -0.1, -0.05],
                [0.05, -0.1, 0.05],
                [-0.05, -0.1, 0.05],
            ],
            [0.0, -1.0, 0.0],
        ),
    ];
    scene(&objs, areas, &[])
}

#[test]
fn a_binding_close_to_two_offers_is_satisfied_with_the_nearest_that_checkmove_allows() {
    // Floating: nothing restricts the box; the tilted panel is nearer, so
    // the box turns onto it.
    let mut s = two_offers(false);
    let back = s.objects()[2].bindings[1];
    let (face, panel) = (s.objects()[1].offers[0], s.objects()[1].offers[1]);
    let c = s.search_close(back);
    assert_eq!(
        c.iter().map(|x| x.offer).collect::<Vec<_>>(),
        vec![panel, face]
    );
    let snap = s.satisfy(back, false).unwrap();
    assert_eq!(snap.offer, panel);
    assert!(
        s.satisfy(back, false).is_none(),
        "one binding, one constraint"
    );
    s.consistent().unwrap();

    // Standing on the floor: turning about x would lift it off (checkMove
    // keeps only the rotation about the floor's normal), so the panel is
    // rejected and the face, a pure translation along y, is taken.
    let mut s = two_offers(true);
    let back = s.objects()[2].bindings[1];
    let face = s.objects()[1].offers[0];
    assert!(s.bond(s.objects()[2].bindings[0]).is_some(), "on the floor");
    assert_eq!(s.search_close(back).len(), 2);
    let before = s.pose(BodyId(2));
    let snap = s.satisfy(back, false).unwrap();
    assert_eq!(snap.offer, face);
    let after = s.pose(BodyId(2));
    assert!((after.r - before.r - Vector3::new(0.0, -0.005, 0.0)).norm() < 1e-12);
    assert!((after.rot - before.rot).norm() < 1e-12);
    assert_eq!(graph(&s), edges(&[("floor", "box"), ("sideboard", "box")]));
    s.consistent().unwrap();
}

/// Fig. 5–6: a board bound to a partition (its back) and to a table (its
/// bottom); partition and table both stand on the floor. There is no order
/// between partition and table: each moves its successors only.
fn undirected() -> haptloop_solver::semantic::SemanticScene {
    let objs = vec![
        obj("floor", true, [0.0, 0.0, -0.05], [2.0, 2.0, 0.05]),
        obj("partition", false, [0.0, -0.35, 0.5], [0.5, 0.05, 0.5]),
        obj("table", false, [0.0, 0.0, 0.2], [0.3, 0.3, 0.2]),
        obj("board", false, [0.0, -0.2, 0.41], [0.2, 0.1, 0.01]),
    ];
    let areas = vec![
        top(0, &objs[0], "on-floor"),
        bottom(1, &objs[1], "on-floor"),
        area(
            1,
            AreaKind::Offer,
            "on-wall",
            vec![
                [-0.5, 0.05, -0.5],
                [0.5, 0.05, -0.5],
                [0.5, 0.05, 0.5],
                [-0.5, 0.05, 0.5],
            ],
            [0.0, 1.0, 0.0],
        ),
        bottom(2, &objs[2], "on-floor"),
        top(2, &objs[2], "on-workspace"),
        bottom(3, &objs[3], "on-workspace"),
        area(
            3,
            AreaKind::Binding,
            "on-wall",
            vec![
                [-0.2, -0.1, -0.01],
                [0.2, -0.1, -0.01],
                [0.2, -0.1, 0.01],
                [-0.2, -0.1, 0.01],
            ],
            [0.0, -1.0, 0.0],
        ),
    ];
    scene(&objs, areas, &[])
}

#[test]
fn an_undirected_cycle_moves_only_successors() {
    let mut s = undirected();
    assert_eq!(
        graph(&s),
        edges(&[
            ("floor", "partition"),
            ("floor", "table"),
            ("partition", "board"),
            ("table", "board"),
        ])
    );
    let (partition, table, board) = (BodyId(1), BodyId(2), BodyId(3));
    // The table's group is table + board; the board's back binding keeps it
    // on the partition (y), the table's bottom on the floor (z): it slides
    // along x only, carrying the board; the partition stays.
    assert_eq!(s.group(table), vec![table, board]);
    let (p0, b0, t0) = (s.pose(partition), s.pose(board), s.pose(table));
    let m = s.move_object(
        table,
        Move {
            center: t0.r,
            t: Vector3::new(0.05, 0.03, 0.02),
            r: Vector3::new(0.0, 0.0, 0.1),
        },
    );
    assert!((m.t - Vector3::new(0.05, 0.0, 0.0)).norm() < 1e-12, "{m:?}");
    assert_eq!(m.r, Vector3::zeros());
    assert_eq!(s.pose(partition), p0);
    assert!((s.pose(board).r - b0.r - Vector3::new(0.05, 0.0, 0.0)).norm() < 1e-12);
    s.consistent().unwrap();
    // Moving the partition moves the board too, not the table. The board's
    // bottom on the table allows x only as well.
    let t1 = s.pose(table);
    let b1 = s.pose(board);
    let m = s.move_object(
        partition,
        Move {
            center: s.pose(partition).r,
            t: Vector3::new(-0.04, 0.0, 0.0),
            r: Vector3::zeros(),
        },
    );
    assert!(
        (m.t - Vector3::new(-0.04, 0.0, 0.0)).norm() < 1e-12,
        "{m:?}"
    );
    assert_eq!(s.pose(table), t1);
    assert!((s.pose(board).r - b1.r - m.t).norm() < 1e-12);
    s.consistent().unwrap();
}

#[test]
fn an_object_on_two_supports_slides_with_one_while_it_stays_on_the_other() {
    let objs = vec![
        obj("floor", true, [0.0, 0.0, -0.05], [2.0, 2.0, 0.05]),
        obj("a", false, [-0.3, 0.0, 0.2], [0.2, 0.2, 0.2]),
        obj("b", false, [0.3, 0.0, 0.2], [0.2, 0.2, 0.2]),
        obj("board", false, [0.0, 0.0, 0.41], [0.4, 0.1, 0.01]),
    ];
    let areas = vec![
        top(0, &objs[0], "on-floor"),
        bottom(1, &objs[1], "on-floor"),
        top(1, &objs[1], "on-workspace"),
        bottom(2, &objs[2], "on-floor"),
        top(2, &objs[2], "on-workspace"),
        foot(3, &objs[3], "on-workspace", -0.3, 0.0, 0.05, 0.05),
        foot(3, &objs[3], "on-workspace", 0.3, 0.0, 0.05, 0.05),
    ];
    let mut s = scene(&objs, areas, &[]);
    assert_eq!(
        graph(&s),
        edges(&[
            ("a", "board"),
            ("b", "board"),
            ("floor", "a"),
            ("floor", "b")
        ])
    );
    let (a, b, board) = (BodyId(1), BodyId(2), BodyId(3));
    // Both supports' normals are z: one direction. Table a may slide and
    // turn in the plane; the board rides along on b.
    assert_eq!(s.orientation_vectors(&s.group(a)).len(), 1);
    let m = s.move_object(
        a,
        Move {
            center: s.pose(a).r,
            t: Vector3::new(0.0, 0.06, 0.0),
            r: Vector3::zeros(),
        },
    );
    assert!((m.t - Vector3::new(0.0, 0.06, 0.0)).norm() < 1e-12);
    assert!((s.pose(board).r.y - 0.06).abs() < 1e-12);
    assert!((s.pose(b).r.y).abs() < 1e-12, "b stays");
    s.consistent().unwrap();
    // Further: foot b would leave table b's top (it ends at y = 0.2; the
    // foot's edge is at 0.06 + 0.05): refused whole.
    let before = (s.pose(a), s.pose(board));
    let m = s.move_object(
        a,
        Move {
            center: s.pose(a).r,
            t: Vector3::new(0.0, 0.1, 0.0),
            r: Vector3::zeros(),
        },
    );
    assert!(m.is_none());
    assert_eq!((s.pose(a), s.pose(board)), before);
    // The board itself: both constraints restrict it to the plane.
    let m = s.move_object(
        board,
        Move {
            center: s.pose(board).r,
            t: Vector3::new(0.01, 0.0, 0.01),
            r: Vector3::new(0.05, 0.0, 0.0),
        },
    );
    assert!((m.t - Vector3::new(0.01, 0.0, 0.0)).norm() < 1e-12 && m.r == Vector3::zeros());
    s.consistent().unwrap();
}
