//! Every step of Algorithms 1 and 2 on hand-made geometry: the close-offer
//! search, the snap's rotate-then-translate, its rejections (collision, a
//! motion checkMove would change, a directed cycle), checkMove's
//! restrictions by one, two and three orientation vectors, inclusion and
//! collision, group moves, breaking and the exception list, and loading.

use haptloop_solver::semantic::{AreaId, Inconsistency, Move, relation};
use nalgebra::Vector3;

use crate::common::*;

const TABLE: usize = 1;
const CUP: usize = 2;

/// A floor (top z = 0), a 60 × 40 × 40 cm table standing on it, a 6 cm cup
/// `gap` above the table top and turned `tilt` about x, and a lamp on the
/// table.
fn furnished(gap: f64, cup_x: f64) -> (Vec<Obj>, Vec<haptloop_solver::semantic::AreaSpec>) {
    let objs = vec![
        obj("floor", true, [0.0, 0.0, -0.05], [1.0, 1.0, 0.05]),
        obj("table", false, [0.0, 0.0, 0.2], [0.3, 0.2, 0.2]),
        obj("cup", false, [cup_x, 0.0, 0.43 + gap], [0.03, 0.03, 0.03]),
        obj("lamp", false, [-0.2, 0.1, 0.45], [0.04, 0.04, 0.05]),
    ];
    let areas = vec![
        top(0, &objs[0], "on-floor"),
        bottom(1, &objs[1], "on-floor"),
        top(1, &objs[1], "on-workspace"),
        bottom(2, &objs[2], "on-workspace"),
        bottom(3, &objs[3], "on-workspace"),
    ];
    (objs, areas)
}

fn cup_binding(s: &haptloop_solver::semantic::SemanticScene) -> AreaId {
    s.objects()[CUP].bindings[0]
}

#[test]
fn loading_satisfies_what_is_aligned_and_nothing_else() {
    let (objs, areas) = furnished(0.004, 0.1);
    let s = scene(&objs, areas, &[]);
    assert_eq!(
        graph(&s),
        edges(&[("floor", "table"), ("table", "lamp")]),
        "the cup floats 4 mm above the table: not aligned, not satisfied"
    );
    assert!(s.bond(cup_binding(&s)).is_none());
}

#[test]
fn the_search_finds_a_close_fitting_offer_with_its_distance_and_angle() {
    let (objs, areas) = furnished(0.004, 0.1);
    let mut s = scene(&objs, areas, &[]);
    let cup = haptloop_solver::BodyId(CUP as u32);
    // The bottom's centre 4 mm over the table, the cup turned 0.1 rad about x.
    let th = 0.1f64;
    s.set_pose(
        cup,
        pose(
            [0.1, -0.03 * th.sin(), 0.404 + 0.03 * th.cos()],
            [1.0, 0.0, 0.0],
            th,
        ),
    );
    let c = s.search_close(cup_binding(&s));
    assert_eq!(c.len(), 1, "{c:?}");
    let table_top = s.objects()[TABLE].offers[0];
    assert_eq!(c[0].offer, table_top);
    assert!((c[0].relation.distance_m - 0.004).abs() < 1e-12);
    assert!((c[0].relation.angle_rad - 0.1).abs() < 1e-12);
    // Rotate about an axis parallel to the offer area (here x), back by the
    // tilt; then translate along the offer's normal by the distance.
    assert!((c[0].mv.r - Vector3::new(-0.1, 0.0, 0.0)).norm() < 1e-12);
    assert!((c[0].mv.t - Vector3::new(0.0, 0.0, -0.004)).norm() < 1e-12);
}

#[test]
fn the_search_refuses_far_steep_outside_and_unfitting_offers() {
    let cases: [(&str, [f64; 3], f64, &str); 4] = [
        ("2 cm above", [0.1, 0.0, 0.45], 0.0, "on-workspace"),
        ("tilted 30°", [0.1, 0.0, 0.434], 0.52, "on-workspace"),
        ("over the edge", [0.29, 0.0, 0.434], 0.0, "on-workspace"),
        ("a wall label", [0.1, 0.0, 0.434], 0.0, "on-wall"),
    ];
    for (what, r, tilt, label) in cases {
        let (objs, mut areas) = furnished(0.004, 0.1);
        areas[3].label = label.into();
        let mut s = scene(&objs, areas, &[]);
        let cup = haptloop_solver::BodyId(CUP as u32);
        s.set_pose(cup, pose(r, [1.0, 0.0, 0.0], tilt));
        assert!(s.search_close(cup_binding(&s)).is_empty(), "{what}");
    }
    // The order makes a label fit a more general one.
    let (objs, mut areas) = furnished(0.004, 0.1);
    areas[3].label = "on-tray".into();
    let s = scene(&objs, areas, &[("on-tray", "on-workspace")]);
    assert_eq!(s.search_close(cup_binding(&s)).len(), 1);
}

#[test]
fn a_snap_rotates_about_the_binding_centroid_then_translates_onto_the_plane() {
    let (objs, areas) = furnished(0.004, 0.1);
    let mut s = scene(&objs, areas, &[]);
    let cup = haptloop_solver::BodyId(CUP as u32);
    let start = pose([0.1, 0.02, 0.434], [1.0, 1.0, 0.0], 0.08);
    s.set_pose(cup, start);
    let b = cup_binding(&s);
    let centroid_before = s.area(b).centroid_w(&start);
    let snap = s.satisfy(b, false).expect("snaps");
    assert_eq!(snap.offer, s.objects()[TABLE].offers[0]);
    let after = s.pose(cup);
    let top = s.area(snap.offer);
    let rel = relation(s.area(b), &after, top, &s.pose(haptloop_solver::BodyId(1)));
    assert!(rel.off_plane_m < 1e-12, "on the plane: {rel:?}");
    assert!(rel.angle_rad < 1e-7, "anti-parallel: {rel:?}");
    // The centroid moved along the offer's normal only, by its distance.
    let centroid_after = s.area(b).centroid_w(&after);
    let d = centroid_after - centroid_before;
    assert!((d - Vector3::new(0.0, 0.0, -(centroid_before.z - 0.4))).norm() < 1e-12);
    assert_eq!(
        graph(&s),
        edges(&[("floor", "table"), ("table", "cup"), ("table", "lamp")])
    );
    s.consistent().unwrap();
}

#[test]
fn a_snap_that_would_collide_is_rejected_and_changes_nothing() {
    // The cup hovers over the lamp's corner: on the table it would overlap it.
    let (objs, areas) = furnished(0.004, 0.1);
    let mut s = scene(&objs, areas, &[]);
    let cup = haptloop_solver::BodyId(CUP as u32);
    // Lamp spans x ∈ [−0.24, −0.16], y ∈ [0.06, 0.14], z ∈ [0.40, 0.50].
    // The cup hovers 4 mm over the table beside it, tilted 0.1 rad about y
    // (its bottom-left edge lifted): clear of the lamp by 0.05 mm. Upright
    // its left face would be 0.05 mm inside the lamp.
    let th = 0.1f64;
    let cx = -0.16 + 0.03 * th.cos() + 5e-5;
    let start = pose(
        [cx + 0.03 * th.sin(), 0.1, 0.404 + 0.03 * th.cos()],
        [0.0, 1.0, 0.0],
        th,
    );
    s.set_pose(cup, start);
    s.consistent().expect("clear of the lamp where it hovers");
    assert!(!s.search_close(cup_binding(&s)).is_empty(), "it is close");
    assert!(s.satisfy(cup_binding(&s), false).is_none());
    assert_eq!(s.pose(cup), start, "nothing moved");
    assert!(s.bond(cup_binding(&s)).is_none());
    s.consistent().unwrap();
}

#[test]
fn checkmove_restricts_a_bound_object_to_its_plane_and_normal() {
    let (objs, areas) = furnished(0.0, 0.1);
    let s = scene(&objs, areas, &[]);
    let cup = haptloop_solver::BodyId(CUP as u32);
    assert!(
        s.bond(cup_binding(&s)).is_some(),
        "the cup stands on the table"
    );
    let c = s.pose(cup).r;
    let m = s.check_move(
        cup,
        Move {
            center: c,
            t: Vector3::new(0.02, 0.01, 0.05),
            r: Vector3::new(0.3, 0.0, 0.2),
        },
        None,
    );
    assert!(
        (m.t - Vector3::new(0.02, 0.01, 0.0)).norm() < 1e-15,
        "{m:?}"
    );
    assert!((m.r - Vector3::new(0.0, 0.0, 0.2)).norm() < 1e-15, "{m:?}");
    // Out of the table's polygon: no motion at all.
    let m = s.check_move(
        cup,
        Move {
            center: c,
            t: Vector3::new(0.25, 0.0, 0.0),
            r: Vector3::zeros(),
        },
        None,
    );
    assert!(m.is_none(), "the cup would leave the table: {m:?}");
    // Into the lamp: no motion.
    let m = s.check_move(
        cup,
        Move {
            center: c,
            t: Vector3::new(-0.27, 0.1, 0.0),
            r: Vector3::zeros(),
        },
        None,
    );
    assert!(m.is_none(), "the cup would hit the lamp: {m:?}");
}

#[test]
fn moving_the_table_moves_its_group_and_the_cup_can_move_alone() {
    let (objs, areas) = furnished(0.0, 0.1);
    let mut s = scene(&objs, areas, &[]);
    let (table, cup, lamp) = (
        haptloop_solver::BodyId(1),
        haptloop_solver::BodyId(2),
        haptloop_solver::BodyId(3),
    );
    assert_eq!(s.group(table), vec![table, cup, lamp]);
    let before: Vec<_> = [table, cup, lamp].iter().map(|&o| s.pose(o)).collect();
    let mv = Move {
        center: before[0].r,
        t: Vector3::new(0.1, 0.05, 0.0),
        r: Vector3::new(0.0, 0.0, 0.3),
    };
    let m = s.move_object(table, mv);
    assert!(
        m.same_as(&mv),
        "a table on the floor moves freely in its plane: {m:?}"
    );
    for (k, o) in [table, cup, lamp].into_iter().enumerate() {
        let want = mv.apply(&before[k]);
        let got = s.pose(o);
        assert!((got.r - want.r).norm() < 1e-12 && (got.rot - want.rot).norm() < 1e-12);
    }
    s.consistent().unwrap();
    // The cup alone: the table and lamp stay.
    let (t0, l0) = (s.pose(table), s.pose(lamp));
    let m = s.move_object(
        cup,
        Move {
            center: s.pose(cup).r,
            t: Vector3::new(0.01, 0.0, 0.0),
            r: Vector3::zeros(),
        },
    );
    assert!(!m.is_none());
    assert_eq!((s.pose(table), s.pose(lamp)), (t0, l0));
    s.consistent().unwrap();
}

/// A box in a corner: bound to the floor, then to one wall, then to a
/// second: one, two, three orientation vectors.
#[test]
fn one_two_and_three_orientation_vectors() {
    let objs = vec![
        obj("floor", true, [0.0, 0.0, -0.05], [1.0, 1.0, 0.05]),
        obj("wall_x", true, [-0.55, 0.0, 0.5], [0.05, 1.0, 0.5]),
        obj("wall_y", true, [0.0, -0.55, 0.5], [1.0, 0.05, 0.5]),
        obj("box", false, [-0.3, -0.3, 0.1], [0.1, 0.1, 0.1]),
    ];
    let side =
        |body: u32, n: [f64; 3], poly: Vec<[f64; 3]>, kind| haptloop_solver::semantic::AreaSpec {
            body: haptloop_solver::BodyId(body),
            kind,
            label: "on-wall".into(),
            polygon_m: poly,
            normal: n,
        };
    use haptloop_solver::semantic::AreaKind::{Binding, Offer};
    let areas = vec![
        top(0, &objs[0], "on-floor"),
        bottom(3, &objs[3], "on-floor"),
        // wall_x's face at x = −0.5 (local x = +0.05), facing +x.
        side(
            1,
            [1.0, 0.0, 0.0],
            vec![
                [0.05, -1.0, 0.0],
                [0.05, 1.0, 0.0],
                [0.05, 1.0, 1.0],
                [0.05, -1.0, 1.0],
            ]
            .into_iter()
            .map(|p| [p[0], p[1], p[2] - 0.5])
            .collect(),
            Offer,
        ),
        side(
            2,
            [0.0, 1.0, 0.0],
            vec![
                [-1.0, 0.05, -0.5],
                [1.0, 0.05, -0.5],
                [1.0, 0.05, 0.5],
                [-1.0, 0.05, 0.5],
            ],
            Offer,
        ),
        side(
            3,
            [-1.0, 0.0, 0.0],
            vec![
                [-0.1, -0.05, -0.05],
                [-0.1, 0.05, -0.05],
                [-0.1, 0.05, 0.05],
                [-0.1, -0.05, 0.05],
            ],
            Binding,
        ),
        side(
            3,
            [0.0, -1.0, 0.0],
            vec![
                [-0.05, -0.1, -0.05],
                [0.05, -0.1, -0.05],
                [0.05, -0.1, 0.05],
                [-0.05, -0.1, 0.05],
            ],
            Binding,
        ),
    ];
    let mut s = scene(&objs, areas, &[]);
    let b = haptloop_solver::BodyId(3);
    let probe = |s: &haptloop_solver::semantic::SemanticScene| {
        s.check_move(
            b,
            Move {
                center: s.pose(b).r,
                t: Vector3::new(0.01, 0.02, 0.03),
                r: Vector3::new(0.1, 0.2, 0.3),
            },
            None,
        )
    };
    // On the floor only (the box is 10 cm from both walls).
    assert_eq!(s.orientation_vectors(&[b]).len(), 1);
    let m = probe(&s);
    assert!((m.t - Vector3::new(0.01, 0.02, 0.0)).norm() < 1e-15);
    assert!((m.r - Vector3::new(0.0, 0.0, 0.3)).norm() < 1e-15);
    // Slide to wall_x (5 mm away), snap.
    s.move_object(
        b,
        Move {
            center: s.pose(b).r,
            t: Vector3::new(-0.095, 0.0, 0.0),
            r: Vector3::zeros(),
        },
    );
    let bx = s.objects()[3].bindings[1];
    assert!(s.satisfy(bx, false).is_some());
    assert_eq!(s.orientation_vectors(&[b]).len(), 2);
    let m = probe(&s);
    assert!(
        (m.t - Vector3::new(0.0, 0.02, 0.0)).norm() < 1e-12,
        "along the wall only: {m:?}"
    );
    assert_eq!(m.r, Vector3::zeros());
    // Into the corner, snap to wall_y: immovable.
    s.move_object(
        b,
        Move {
            center: s.pose(b).r,
            t: Vector3::new(0.0, -0.095, 0.0),
            r: Vector3::zeros(),
        },
    );
    let by = s.objects()[3].bindings[2];
    assert!(s.satisfy(by, false).is_some());
    assert_eq!(s.orientation_vectors(&[b]).len(), 3);
    assert!(probe(&s).is_none(), "three directions: immovable");
    s.consistent().unwrap();
}

#[test]
fn a_snap_checkmove_would_change_is_rejected() {
    // A board bound to table A (top 0.40) whose second foot hangs 3 mm
    // over table B (top 0.397): satisfying it needs a vertical move, which
    // the constraint on A forbids. Level with A, it is accepted.
    for (b_top, accepted) in [(0.397, false), (0.4, true)] {
        let b_half_z = b_top / 2.0;
        let objs = vec![
            obj("floor", true, [0.0, 0.0, -0.05], [2.0, 2.0, 0.05]),
            obj("a", false, [-0.3, 0.0, 0.2], [0.2, 0.2, 0.2]),
            obj("b", false, [0.3, 0.0, b_half_z], [0.2, 0.2, b_half_z]),
            obj("board", false, [0.0, 0.0, 0.41], [0.4, 0.1, 0.01]),
        ];
        let mut areas = vec![
            top(0, &objs[0], "on-floor"),
            bottom(1, &objs[1], "on-floor"),
            top(1, &objs[1], "on-workspace"),
            bottom(2, &objs[2], "on-floor"),
            top(2, &objs[2], "on-workspace"),
        ];
        areas.push(foot(3, &objs[3], "on-workspace", -0.3, 0.0, 0.05, 0.05));
        areas.push(foot(3, &objs[3], "on-workspace", 0.3, 0.0, 0.05, 0.05));
        let mut s = scene(&objs, areas, &[]);
        let board = haptloop_solver::BodyId(3);
        let (fa, fb) = (s.objects()[3].bindings[0], s.objects()[3].bindings[1]);
        assert!(s.bond(fa).is_some());
        if accepted {
            assert!(s.bond(fb).is_some(), "level: both feet satisfied at load");
            continue;
        }
        assert!(!s.search_close(fb).is_empty(), "foot B is close to table B");
        let before = s.pose(board);
        assert!(s.satisfy(fb, false).is_none());
        assert_eq!(s.pose(board), before);
    }
}

#[test]
fn a_snap_that_would_close_a_directed_cycle_is_rejected() {
    // Two blocks: `upper` stands on `lower`; `lower` also carries a binding
    // on its top face and `upper` an offer on its bottom face (labels that
    // fit), so `lower` could bind to `upper` too: lower → upper → lower.
    let objs = vec![
        obj("floor", true, [0.0, 0.0, -0.05], [1.0, 1.0, 0.05]),
        obj("lower", false, [0.0, 0.0, 0.1], [0.1, 0.1, 0.1]),
        obj("upper", false, [0.0, 0.0, 0.25], [0.05, 0.05, 0.05]),
    ];
    use haptloop_solver::semantic::AreaKind::{Binding, Offer};
    let mut areas = vec![
        top(0, &objs[0], "on-floor"),
        bottom(1, &objs[1], "on-floor"),
        top(1, &objs[1], "on-workspace"),
        bottom(2, &objs[2], "on-workspace"),
    ];
    // upper's underside offers "under"; lower's top (inner square) binds "under".
    let mut under = bottom(2, &objs[2], "under");
    under.kind = Offer;
    areas.push(under);
    let mut up = top(1, &objs[1], "under");
    up.kind = Binding;
    up.polygon_m = rect(0.0, 0.0, 0.04, 0.04, 0.1);
    up.normal = [0.0, 0.0, 1.0];
    areas.push(up);
    let (model, spec) = build(&objs, areas, &[], settings());
    let mut s =
        haptloop_solver::semantic::SemanticScene::from_model(&model, model.q0(), &spec).unwrap();
    // Satisfy upper → lower first (its binding comes first in area order).
    let upper_b = s.objects()[2].bindings[0];
    let lower_up = s.objects()[1].bindings[1];
    let lower_top = s.objects()[1].offers[0];
    let upper_under = s.objects()[2].offers[0];
    assert!(s.aligned(upper_b, lower_top, false) && s.aligned(lower_up, upper_under, false));
    assert_eq!(
        s.satisfy_aligned(),
        2,
        "floor → lower and lower → upper; the third would cycle"
    );
    assert!(s.would_cycle(lower_up, upper_under));
    assert!(s.bond(lower_up).is_none());
    assert!(s.satisfy(lower_up, false).is_none());
    assert!(!s.has_directed_cycle());
    // Without the first edge the same constraint is fine.
    s.break_bond(upper_b);
    assert!(!s.would_cycle(lower_up, upper_under));
}

#[test]
fn breaking_puts_the_pair_on_the_exception_list_until_it_separates() {
    let (objs, areas) = furnished(0.0, 0.1);
    let mut s = scene(&objs, areas, &[]);
    let cup = haptloop_solver::BodyId(CUP as u32);
    let table = haptloop_solver::BodyId(TABLE as u32);
    let b = cup_binding(&s);
    // Sink the cup 0.5 mm into the table (numerically touching surfaces).
    let p = s.pose(cup);
    s.set_pose(cup, at([p.r.x, p.r.y, p.r.z - 5e-4]));
    assert_eq!(s.break_bond(b), Some(s.objects()[TABLE].offers[0]));
    assert_eq!(s.exceptions(), &[[cup, table]]);
    s.consistent().expect("the overlap is excepted");
    assert!(s.search_close(b).is_empty(), "no snap back while excepted");
    assert!(s.update_exceptions().is_empty(), "still overlapping");
    // Lifted 5 mm: apart, but still within the snap distance.
    s.set_pose(cup, at([p.r.x, p.r.y, p.r.z + 5e-3]));
    assert!(s.update_exceptions().is_empty(), "still close");
    s.set_pose(cup, at([p.r.x, p.r.y, p.r.z + 2e-2]));
    assert_eq!(s.update_exceptions(), vec![[cup, table]]);
    // Back near the table it snaps again.
    s.set_pose(cup, at([p.r.x, p.r.y, p.r.z + 3e-3]));
    assert!(s.satisfy(b, false).is_some());
    s.consistent().unwrap();
}

#[test]
fn an_overlap_without_a_constraint_is_inconsistent() {
    let (objs, areas) = furnished(0.0, 0.1);
    let mut s = scene(&objs, areas, &[]);
    let lamp = haptloop_solver::BodyId(3);
    // Move the lamp (bound to the table) into the cup by force.
    s.set_pose(lamp, at([0.1, 0.0, 0.45]));
    match s.consistent() {
        Err(Inconsistency::Collision(c)) => {
            assert!(c.depth_m > 0.01, "{c:?}");
        }
        other => panic!("expected a collision, got {other:?}"),
    }
    // A misaligned constraint is caught too.
    let (objs, areas) = furnished(0.0, 0.1);
    let mut s = scene(&objs, areas, &[]);
    let cup = haptloop_solver::BodyId(CUP as u32);
    s.set_pose(cup, at([0.1, 0.0, 0.44]));
    assert!(matches!(
        s.consistent(),
        Err(Inconsistency::Misaligned { .. })
    ));
}
