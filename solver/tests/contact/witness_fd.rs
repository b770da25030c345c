//! Every witness row's analytic Jacobian against central finite differences,
//! at random configurations with non-unit quaternions and random witness
//! parameters of every kind, with the point (or edge) on either end and a
//! fixed body on the other end of one pair. Fixed seed.

use haptloop_solver::constraint::witness::{
    BallWitness, EdgeWitness, LineWitness, PlaneWitness, Witness, WitnessType,
};
use haptloop_solver::{FingerTarget, Model};
use nalgebra::{DMatrix, Quaternion, Vector3};
use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed, TestRunner};

use crate::common::{cuboid, three_bodies};
use crate::fd;

/// Central-difference C_q with the witness table `w`.
fn fd(model: &Model, q: &[f64], w: &[Witness], h: f64) -> DMatrix<f64> {
    fd::fd_jacobian_with(model, q, &[], w, h)
}

fn v3(u: &mut impl Iterator<Item = f64>, s: f64) -> Vector3<f64> {
    Vector3::new(u.next().unwrap(), u.next().unwrap(), u.next().unwrap()) * s
}

fn unit(u: &mut impl Iterator<Item = f64>) -> Vector3<f64> {
    let v = v3(u, 1.0);
    if v.norm() < 0.2 {
        Vector3::new(0.3, -0.5, 0.8).normalize()
    } else {
        v.normalize()
    }
}

/// A witness of kind `k` from random numbers.
fn witness(k: usize, end: u8, u: &mut impl Iterator<Item = f64>) -> Witness {
    let origin = WitnessType::VertexFace;
    match k {
        0 => Witness::Plane(PlaneWitness {
            origin,
            features: [0, 0],
            point_end: end,
            point: v3(u, 0.1),
            plane_point: v3(u, 0.1),
            normal: unit(u),
            margin: 0.01,
        }),
        1 => Witness::Ball(BallWitness {
            origin,
            features: [0, 0],
            point_a: v3(u, 0.1),
            point_b: v3(u, 0.1),
            fallback: unit(u),
            margin: 0.02,
        }),
        2 => Witness::Line(LineWitness {
            origin,
            features: [0, 0],
            point_end: end,
            point: v3(u, 0.1),
            line_point: v3(u, 0.1),
            line_dir: unit(u),
            fallback: unit(u),
            margin: 0.005,
        }),
        _ => Witness::EdgeEdge(EdgeWitness {
            origin,
            features: [0, 0],
            edge_end: end,
            edge_point: v3(u, 0.1),
            edge_dir: unit(u),
            face_point: v3(u, 0.1),
            face_normal: unit(u),
            sep_normal: unit(u),
            margin: 0.0,
        }),
    }
}

#[test]
fn witness_rows_match_finite_differences() {
    let s = cuboid([0.05, 0.04, 0.03]);
    let model = three_bodies([s.clone(), s.clone(), s], 4);
    // Two pairs of 4 witness slots; the friction pair between two bodies
    // holds its two tangent rows and its twist row.
    assert_eq!(model.contact().slots, 4 + 3 + 4);
    let config = Config {
        cases: 64,
        rng_seed: RngSeed::Fixed(0x3171_5e55),
        failure_persistence: None,
        ..Config::default()
    };
    let n = 2 * 8 + model.contact().slots * 20;
    let checked = std::cell::Cell::new([0usize; 4]);
    TestRunner::new(config)
        .run(&prop::collection::vec(-1.0f64..1.0, n), |u| {
            let mut it = u.into_iter();
            let mut q = model.q0().to_vec();
            for (_, o) in model.layout().moving_bodies() {
                for k in 0..3 {
                    q[o + k] = 0.3 * it.next().unwrap();
                }
                let d = Quaternion::new(
                    it.next().unwrap() + 1.2,
                    it.next().unwrap(),
                    it.next().unwrap(),
                    it.next().unwrap(),
                );
                let norm = 0.7 + 0.3 * it.next().unwrap().abs();
                let d = d / d.norm() * norm;
                q[o + 3..o + 7].copy_from_slice(&[d.w, d.i, d.j, d.k]);
            }
            let mut table = vec![Witness::Off; model.contact().slots];
            for (slot, w) in table.iter_mut().enumerate() {
                let k = slot % 4;
                let end = ((slot / 4) % 2) as u8;
                *w = witness(k, end, &mut it);
                let mut c = checked.get();
                c[k] += 1;
                checked.set(c);
            }
            let mut ev = model.evaluation();
            ev.witnesses_mut().copy_from_slice(&table);
            ev.evaluate(&model, &q, &[] as &[FingerTarget]).unwrap();
            let a = ev.jacobian().to_dense();
            let (f1, f2) = (fd(&model, &q, &table, 1e-6), fd(&model, &q, &table, 5e-7));
            for r in 0..a.nrows() {
                for c in 0..a.ncols() {
                    let est = (f1[(r, c)] - f2[(r, c)]).abs();
                    let tol = 1e-7 * (1.0 + a[(r, c)].abs()) + 10.0 * est;
                    let err = (a[(r, c)] - f2[(r, c)]).abs();
                    prop_assert!(
                        err <= tol,
                        "row {r} ({:?}), col {c}: analytic {:e} vs FD {:e}",
                        table.get(r.saturating_sub(model.n_rows() - table.len())),
                        a[(r, c)],
                        f2[(r, c)]
                    );
                }
            }
            Ok(())
        })
        .unwrap();
    let checked = checked.get();
    assert!(checked.iter().all(|&c| c > 0), "{checked:?}");
}

/// The checker can fail: a witness row's gradient with a wrong sign on the
/// plane's rotation term (a corrupted analytic entry) is caught.
#[test]
fn a_corrupted_entry_is_caught() {
    let s = cuboid([0.05, 0.04, 0.03]);
    let model = three_bodies([s.clone(), s.clone(), s], 4);
    let mut it = (0..400).map(|k| ((k * 37 % 23) as f64 / 11.5) - 1.0);
    let table: Vec<Witness> = (0..model.contact().slots)
        .map(|slot| witness(slot % 4, 0, &mut it))
        .collect();
    let q = model.q0().to_vec();
    let mut ev = model.evaluation();
    ev.witnesses_mut().copy_from_slice(&table);
    ev.evaluate(&model, &q, &[]).unwrap();
    let mut a = ev.jacobian().to_dense();
    let f = fd(&model, &q, &table, 1e-6);
    let row = model.n_rows() - table.len();
    let worst = (0..a.ncols())
        .map(|c| (a[(row, c)] - f[(row, c)]).abs())
        .fold(0.0, f64::max);
    assert!(worst < 1e-7, "unmodified row matches: {worst:e}");
    a[(row, 4)] += 1e-4;
    assert!((a[(row, 4)] - f[(row, 4)]).abs() > 1e-5);
}
