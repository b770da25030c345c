//! The analytic Jacobians of `on_surface` rows (every surface kind, offset
//! by a ball's radius or not, on a fixed and on a moving body: a cam) and of
//! `rolling` rows (anchored at one configuration, evaluated at another)
//! against central finite differences.

use haptloop_solver::parametric::SurfaceKind;
use haptloop_solver::{
    BodySpec, ContactSurface, FingerTarget, JointKind, JointSpec, Model, ModelBuilder,
};
use nalgebra::{DMatrix, Vector3};

use super::common::{LEVEL, ball, bowl, plane};
use crate::flexible::common::Lcg;

fn fd(model: &Model, anchor: &[f64], q: &[f64], t: &[FingerTarget], h: f64) -> DMatrix<f64> {
    let mut ev = model.evaluation();
    ev.anchor_rolling(model, anchor);
    let mut j = DMatrix::zeros(model.n_rows(), model.n_coords());
    let mut x = q.to_vec();
    for c in 0..q.len() {
        x[c] = q[c] + h;
        ev.evaluate_values(model, &x, t).unwrap();
        let plus = ev.values().to_vec();
        x[c] = q[c] - h;
        ev.evaluate_values(model, &x, t).unwrap();
        for (r, p) in plus.iter().enumerate() {
            j[(r, c)] = (p - ev.values()[r]) / (2.0 * h);
        }
        x[c] = q[c];
    }
    j
}

/// Random states near q0 (bodies by `size`, (u, v) by 1 cm), the rolling
/// anchors at another random state; every entry against FD.
fn check(model: &Model, seed: u64, size: f64) {
    let mut rng = Lcg(seed);
    let aux = model.n_coords() - model.layout().aux_coords();
    let nudge = |rng: &mut Lcg| -> Vec<f64> {
        model
            .q0()
            .iter()
            .enumerate()
            .map(|(c, v)| v + if c >= aux { 0.01 } else { size } * rng.next())
            .collect()
    };
    for case in 0..16 {
        let (anchor, q) = (nudge(&mut rng), nudge(&mut rng));
        let t = model.initial_targets();
        let mut ev = model.evaluation();
        ev.anchor_rolling(model, &anchor);
        ev.evaluate(model, &q, &t).unwrap();
        let a = ev.jacobian().to_dense();
        let (f1, f2) = (
            fd(model, &anchor, &q, &t, 1e-6),
            fd(model, &anchor, &q, &t, 5e-7),
        );
        for r in 0..a.nrows() {
            for c in 0..a.ncols() {
                let est = (f1[(r, c)] - f2[(r, c)]).abs();
                let tol = 1e-7 * (1.0 + a[(r, c)].abs()) + 10.0 * est;
                assert!(
                    (a[(r, c)] - f2[(r, c)]).abs() <= tol,
                    "case {case}, row {r} ({}), col {c}: {:e} vs FD {:e}",
                    model.constraints()[model.rows()[r].constraint.index()].name,
                    a[(r, c)],
                    f2[(r, c)]
                );
            }
        }
    }
}

#[test]
fn rolling_and_sliding_balls_match_finite_differences() {
    let tilt = [0.96, 0.2, -0.15, 0.1];
    for (k, (kind, rolling)) in [
        (plane(), true),
        (bowl(), true),
        (bowl(), false),
        (
            SurfaceKind::Sphere {
                radius_m: 0.15,
                concave: false,
            },
            true,
        ),
        (
            SurfaceKind::Cylinder {
                radius_m: 0.1,
                concave: true,
            },
            true,
        ),
        (
            SurfaceKind::Cylinder {
                radius_m: 0.12,
                concave: false,
            },
            false,
        ),
    ]
    .into_iter()
    .enumerate()
    {
        let model = ball(
            kind,
            if k % 2 == 0 { LEVEL } else { tilt },
            [0.02, -0.03],
            rolling,
            true,
        );
        check(&model, 40 + k as u64, 0.05);
    }
}

/// A point of one moving body on a dome fixed to another moving body (a
/// spatial cam and follower): both bodies' columns and (u, v).
#[test]
fn a_follower_on_a_moving_cam_matches_finite_differences() {
    let mut b = ModelBuilder::new();
    b.body(
        BodySpec::new("cam")
            .at([0.0, 0.0, 0.0])
            .oriented([0.9, 0.1, 0.3, -0.2]),
    );
    b.body(BodySpec::new("follower").at([0.05, 0.02, 0.2]));
    b.joint(
        JointSpec::new(JointKind::OnSurface, "follower", "cam")
            .named("touch")
            .anchors([0.0, 0.0, -0.02], [0.0; 3])
            .surface(ContactSurface {
                kind: SurfaceKind::Sphere {
                    radius_m: 0.2,
                    concave: false,
                },
                origin_m: [0.0, 0.0, 0.05],
                orientation_wxyz: [0.98, 0.0, 0.1, 0.1],
            }),
    );
    let model = b.build().unwrap();
    assert!(model.n_coords() == 16, "{}", model.n_coords());
    check(&model, 77, 0.1);
    let _ = Vector3::<f64>::zeros();
}
