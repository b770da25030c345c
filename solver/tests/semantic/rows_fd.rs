//! The rows of satisfied surface constraints and holds
//! ([`Model::with_semantic`]): their analytic Jacobian against central
//! finite differences at random configurations (non-unit quaternions) with
//! random snap offsets, a fixed offer on one constraint; and their layout
//! (equalities stay a prefix, contact rows derived afterwards leave them be).

use haptloop_solver::constraint::witness::Witness;
use haptloop_solver::geometry::PairSpec;
use haptloop_solver::semantic::SemanticScene;
use haptloop_solver::{ConstraintKind, HoldSpec, Model, Sense, SnapSettings};
use nalgebra::{DMatrix, Quaternion};
use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed, TestRunner};

use crate::common::*;
use crate::fd;

/// Floor (fixed), table on it, cup on the table, a hold of the cup by the
/// table (any two bodies will do for the rows).
fn model() -> Model {
    let objs = vec![
        obj("floor", true, [0.0, 0.0, -0.05], [1.0, 1.0, 0.05]),
        obj("table", false, [0.0, 0.0, 0.2], [0.3, 0.2, 0.2]),
        obj("cup", false, [0.1, 0.0, 0.43], [0.03, 0.03, 0.03]),
    ];
    let areas = vec![
        top(0, &objs[0], "on-floor"),
        bottom(1, &objs[1], "on-floor"),
        top(1, &objs[1], "on-workspace"),
        bottom(2, &objs[2], "on-workspace"),
    ];
    let (base, spec) = build(&objs, areas, &[], settings());
    let mut s = SemanticScene::from_model(&base, base.q0(), &spec).unwrap();
    assert_eq!(s.satisfy_aligned(), 2);
    let specs = s.surface_specs();
    assert_eq!(specs.len(), 2);
    assert_eq!(specs[0].inclusion.len(), 16, "4 vertices × 4 edges");
    let hold = HoldSpec {
        name: "hold".into(),
        tip: haptloop_solver::BodyId(1),
        body: haptloop_solver::BodyId(2),
        tip_anchor_m: [0.1, 0.0, 0.2],
        body_anchor_m: [0.0, 0.0, -0.03],
        // A pinch (weld) taken at q0, where both bodies are unrotated.
        orientation: Some(nalgebra::Matrix3::identity()),
    };
    base.with_semantic(&specs, &[hold], SnapSettings::default())
        .unwrap()
}

/// C(q) with the witness table `w`.
fn values(model: &Model, q: &[f64], w: &[Witness]) -> Vec<f64> {
    fd::values_with(model, q, &[], w)
}

/// Central-difference C_q with the witness table `w`.
fn fd(model: &Model, q: &[f64], w: &[Witness], h: f64) -> DMatrix<f64> {
    fd::fd_jacobian_with(model, q, &[], w, h)
}

#[test]
fn the_layout_keeps_equalities_first_and_survives_contact_rows() {
    let m = model();
    let sem = m.semantic();
    assert_eq!(sem.surfaces.len(), 2);
    assert_eq!(sem.slots.len(), 2 * (3 + 16));
    let eq = m.equality_rows().end;
    for (i, r) in m.rows().iter().enumerate() {
        assert_eq!(r.sense == Sense::Equality, i < eq, "row {i}");
    }
    let kinds = |k| m.constraints().iter().filter(|c| c.kind == k).count();
    assert_eq!(kinds(ConstraintKind::SurfacePlane), 2);
    assert_eq!(kinds(ConstraintKind::SurfaceInclusion), 2);
    assert_eq!(kinds(ConstraintKind::Hold), 1);
    // At the loaded, aligned configuration every semantic row holds.
    let mut ev = m.evaluation();
    ev.evaluate(&m, m.q0(), &[]).unwrap();
    for c in m.constraints() {
        let v = &ev.values()[c.rows.clone()];
        match c.kind {
            ConstraintKind::SurfacePlane | ConstraintKind::Hold => {
                assert!(v.iter().all(|x| x.abs() < 1e-12), "{}: {v:?}", c.name)
            }
            ConstraintKind::SurfaceInclusion => {
                assert!(v.iter().all(|x| *x > -1e-12), "{}: {v:?}", c.name)
            }
            _ => {}
        }
    }
    // Contact slots take the table's head; the semantic rows still read theirs.
    let with = m
        .with_contacts(&[PairSpec {
            bodies: [2, 0],
            slots: 4,
            friction: false,
        }])
        .unwrap();
    let mut ev2 = with.evaluation();
    assert_eq!(ev2.witnesses().len(), 4 + sem.slots.len());
    ev2.evaluate(&with, with.q0(), &[]).unwrap();
    assert_eq!(&ev2.values()[..m.n_rows()], ev.values());
}

#[test]
fn surface_and_hold_rows_match_finite_differences() {
    let model = model();
    let config = Config {
        cases: 48,
        rng_seed: RngSeed::Fixed(0x5e3a_471c),
        failure_persistence: None,
        ..Config::default()
    };
    let n = 2 * 8 + model.semantic().slots.len();
    TestRunner::new(config)
        .run(&prop::collection::vec(-1.0f64..1.0, n), |u| {
            let mut it = u.into_iter();
            let mut q = model.q0().to_vec();
            for (_, o) in model.layout().moving_bodies() {
                for k in 0..3 {
                    q[o + k] += 0.05 * it.next().unwrap();
                }
                let d = Quaternion::new(
                    it.next().unwrap() + 2.0,
                    0.3 * it.next().unwrap(),
                    0.3 * it.next().unwrap(),
                    0.3 * it.next().unwrap(),
                );
                let norm = 0.8 + 0.2 * it.next().unwrap().abs();
                let d = d / d.norm() * norm;
                q[o + 3..o + 7].copy_from_slice(&[d.w, d.i, d.j, d.k]);
            }
            let mut ev = model.evaluation();
            let mut table = ev.witnesses().to_vec();
            for w in &mut table {
                if let Witness::Plane(p) = w {
                    p.margin = 0.01 * it.next().unwrap();
                }
            }
            ev.witnesses_mut().copy_from_slice(&table);
            ev.evaluate(&model, &q, &[]).unwrap();
            let a = ev.jacobian().to_dense();
            let (f1, f2) = (fd(&model, &q, &table, 1e-6), fd(&model, &q, &table, 5e-7));
            for r in 0..a.nrows() {
                for c in 0..a.ncols() {
                    let est = (f1[(r, c)] - f2[(r, c)]).abs();
                    let tol = 1e-7 * (1.0 + a[(r, c)].abs()) + 10.0 * est;
                    let err = (a[(r, c)] - f2[(r, c)]).abs();
                    prop_assert!(
                        err <= tol,
                        "row {r}, col {c}: analytic {:e} vs FD {:e}",
                        a[(r, c)],
                        f2[(r, c)]
                    );
                }
            }
            // The margin is the row's offset: value = raw − margin.
            let mut zero = table.clone();
            for w in &mut zero {
                if let Witness::Plane(p) = w {
                    p.margin = 0.0;
                }
            }
            let raw = values(&model, &q, &zero);
            let with = ev.values();
            let sem = model.semantic();
            for s in &sem.surfaces {
                let Witness::Plane(p) = table[s.first_slot] else {
                    unreachable!()
                };
                let r = model.constraints()[s.plane.index()].rows.start;
                prop_assert!((raw[r] - with[r] - p.margin).abs() < 1e-15);
            }
            Ok(())
        })
        .unwrap();
}
