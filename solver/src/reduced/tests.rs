//! The joint-space core against independently computed things, at the q a
//! `Program` reaches after a few hundred ticks of each scene's hand path:
//! S against central differences of forward kinematics; C_tree,q S against
//! zero; H (composite inertias) against the dense Sᵀ M̃ S; J_r S H⁻¹ Sᵀ J_rᵀ
//! against the augmented Schur complement of the tree and quaternion-norm
//! rows with the force stage's own M̃⁻¹; and the finger force against the
//! dense null-space reference (`force::reference_finger_wrenches`).

use std::sync::Arc;
use std::time::Duration;

use nalgebra::{DMatrix, DVector, UnitQuaternion, Vector3, Vector4};

use super::{JointSpace, displace};
use crate::force::inertia::BodyMass;
use crate::rotation::BodyFrame;
use crate::{Evaluation, FingerTarget, Model, Program, SolverSettings, TickOutcome};

/// The scenes checked; the lattice only in optimised builds (its dense
/// references are O(n³) in 924 coordinates).
fn scenes() -> Vec<&'static str> {
    let mut v = vec!["bennett", "four-bar", "peaucellier"];
    if !cfg!(debug_assertions) {
        v.push("lattice");
    }
    v
}

/// The model and its q after `ticks` ticks of the hand on a 2 mm circle.
pub(crate) fn state(name: &str, ticks: usize) -> (Arc<Model>, Vec<f64>) {
    let p = program_after(name, ticks);
    (p.model_arc().clone(), p.q().to_vec())
}

/// The scene `name`'s program (its step and iterations) after `ticks` ticks
/// of the hand on a 2 mm circle.
pub(crate) fn program_after(name: &str, ticks: usize) -> Program {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../scenes")
        .join(format!("{name}.toml"));
    let compiled = crate::scene::load(&path).unwrap().compile().unwrap();
    let mut settings = SolverSettings::default();
    if let Some(v) = compiled.settings.step {
        settings.step = v;
    }
    if let Some(v) = compiled.settings.iterations {
        settings.iterations = v;
    }
    let model = Arc::new(compiled.model);
    let mut p = Program::new(model.clone(), settings).unwrap();
    let t0 = model.initial_targets();
    let mut t = t0.clone();
    for k in 0..ticks {
        let a = 2.0 * std::f64::consts::PI * k as f64 / 500.0;
        for (t, t0) in t.iter_mut().zip(&t0) {
            t.position_m = t0.position_m + Vector3::new(a.cos() - 1.0, a.sin(), 0.0) * 0.002;
        }
        let r = p.tick(&t, Duration::from_millis(1));
        assert_eq!(r.status, TickOutcome::Ok, "{name} tick {k}");
    }
    p
}

/// Each finger holding its attachment point at q.
pub(crate) fn targets(model: &Model, q: &[f64]) -> Vec<FingerTarget> {
    model
        .fingers()
        .iter()
        .enumerate()
        .map(|(k, f)| FingerTarget {
            position_m: model.finger_point(q, crate::FingerId(k as u32)).unwrap(),
            orientation: UnitQuaternion::from_matrix(&model.body_rotation(q, f.body).unwrap()),
        })
        .collect()
}

/// The evaluation at q with [`targets`].
pub(crate) fn evaluation(model: &Model, q: &[f64]) -> Evaluation {
    let mut ev = model.evaluation();
    ev.evaluate(model, q, &targets(model, q)).unwrap();
    ev
}

fn frame(q: &[f64], o: usize) -> BodyFrame {
    BodyFrame::new(
        Vector3::new(q[o], q[o + 1], q[o + 2]),
        [q[o + 3], q[o + 4], q[o + 5], q[o + 6]],
    )
    .unwrap()
}

/// M̃ and the force stage's M̃⁻¹ (`force::inertia`), dense.
fn metric(model: &Model, q: &[f64]) -> (DMatrix<f64>, DMatrix<f64>) {
    let n = model.n_coords();
    let (mut m, mut mi) = (DMatrix::zeros(n, n), DMatrix::zeros(n, n));
    for bm in BodyMass::of_model(model) {
        let o = bm.offset;
        let f = frame(q, o);
        let e = Vector4::new(q[o + 3], q[o + 4], q[o + 5], q[o + 6]);
        let s = e.norm_squared();
        m.view_mut((o, o), (3, 3)).fill_diagonal(bm.mass);
        mi.view_mut((o, o), (3, 3)).fill_diagonal(1.0 / bm.mass);
        let me = bm.rotational_mass(&f) + e * e.transpose() * (4.0 * bm.norm_mass / (s * s));
        m.view_mut((o + 3, o + 3), (4, 4)).copy_from(&me);
        mi.view_mut((o + 3, o + 3), (4, 4))
            .copy_from(&bm.inv_rotational_mass(&f, &e));
    }
    (m, mi)
}

fn rows_of(cq: &DMatrix<f64>, rows: &[usize]) -> DMatrix<f64> {
    DMatrix::from_fn(rows.len(), cq.ncols(), |i, j| cq[(rows[i], j)])
}

fn max_abs(m: &DMatrix<f64>) -> f64 {
    m.iter().fold(0.0, |a, v| a.max(v.abs()))
}

#[test]
fn s_is_the_derivative_of_forward_kinematics() {
    for name in scenes() {
        let (model, q) = state(name, 300);
        let ev = evaluation(&model, &q);
        let mut js = JointSpace::new(&model, &q, &ev).unwrap();
        js.kin.update(&model, &js.tree, &q).unwrap();
        let s = js.kin.s_dense(&model, &js.tree);
        let (n, h) = (js.tree.dofs(), 1e-6);
        let (mut plus, mut minus) = (q.clone(), q.clone());
        let mut worst = 0.0f64;
        for d in 0..n {
            let mut th = vec![0.0; n];
            th[d] = h;
            displace(&model, &js.tree, &js.kin, &q, &th, &mut plus);
            th[d] = -h;
            displace(&model, &js.tree, &js.kin, &q, &th, &mut minus);
            for i in 0..q.len() {
                let fd = (plus[i] - minus[i]) / (2.0 * h);
                worst = worst.max((fd - s[(i, d)]).abs());
            }
        }
        // Central differences: error O(h²) of the second derivative (|S|
        // ≲ 1 m/rad here) plus round-off 1e-16 / h.
        assert!(worst < 1e-8, "{name}: |S − FD| = {worst:.2e}");
        assert!(max_abs(&s) > 0.1, "{name}: S is not trivially zero");
    }
}

#[test]
fn tree_and_norm_rows_vanish_along_s() {
    for name in scenes() {
        let (model, q) = state(name, 300);
        let ev = evaluation(&model, &q);
        let mut js = JointSpace::new(&model, &q, &ev).unwrap();
        js.kin.update(&model, &js.tree, &q).unwrap();
        let s = js.kin.s_dense(&model, &js.tree);
        let cq = ev.jacobian().to_dense();
        let tree = rows_of(&cq, &js.tree.tree_rows) * &s;
        let norm = rows_of(&cq, &js.tree.norm_rows) * &s;
        // Off the tree manifold by the violation v, a tree joint's point
        // rows change along S by ω × (p_i − p_j): |C_T S| ≤ |ω| v.
        let viol = js
            .tree
            .tree_rows
            .iter()
            .fold(0.0f64, |a, &r| a.max(ev.values()[r].abs()));
        let bound = 1e-13 + 10.0 * viol;
        assert!(
            max_abs(&tree) < bound,
            "{name}: |C_T S| {:.2e}, violation {viol:.2e}",
            max_abs(&tree)
        );
        assert!(
            max_abs(&norm) < 1e-13,
            "{name}: |C_norm S| {:.2e}",
            max_abs(&norm)
        );
        let loops = rows_of(&cq, &js.tree.loop_rows) * &s;
        assert!(
            js.tree.loop_rows.is_empty() || max_abs(&loops) > 1e-3,
            "{name}: loop rows see S"
        );
    }
}

#[test]
fn joint_inertia_is_s_transpose_m_s() {
    for name in scenes() {
        let (model, q) = state(name, 300);
        let ev = evaluation(&model, &q);
        let mut js = JointSpace::new(&model, &q, &ev).unwrap();
        let h = js.joint_inertia(&model, &q);
        let s = js.kin.s_dense(&model, &js.tree);
        let (m, _) = metric(&model, &q);
        let dense = s.transpose() * m * &s;
        let err = max_abs(&(&h - &dense)) / max_abs(&dense);
        assert!(err < 1e-12, "{name}: |H − SᵀM̃S| / |H| = {err:.2e}");
    }
}

/// J_r S H⁻¹ Sᵀ J_rᵀ against J_r (M̃⁻¹ − M̃⁻¹J_Tᵀ (J_T M̃⁻¹ J_Tᵀ)⁻¹ J_T M̃⁻¹) J_rᵀ,
/// J_T the tree joints' rows and the quaternion-norm rows. Unscaled rows,
/// no Tikhonov term (`force_regularization` is 0 by default, and it is
/// added to A's diagonal after this product in the fast path).
#[test]
fn joint_gram_is_the_augmented_schur_complement_of_the_tree_rows() {
    for name in scenes() {
        let (model, q) = state(name, 300);
        let ev = evaluation(&model, &q);
        let mut js = JointSpace::new(&model, &q, &ev).unwrap();
        let (rows, w) = js.unmasked_gram(&model, &q, &ev).unwrap();
        let cq = ev.jacobian().to_dense();
        let (_, mi) = metric(&model, &q);
        let mut t_rows = js.tree.tree_rows.clone();
        t_rows.extend(&js.tree.norm_rows);
        let jt = rows_of(&cq, &t_rows);
        let jr = rows_of(&cq, &rows);
        let a_tt = &jt * &mi * jt.transpose();
        let chol = a_tt.clone().cholesky().expect("tree rows independent");
        let x = chol.solve(&(&jt * &mi * jr.transpose()));
        let aug = &jr * &mi * jr.transpose() - (&jr * &mi * jt.transpose()) * x;
        let err = max_abs(&(&w - &aug)) / max_abs(&aug);
        // The tree rows at q are off the tree manifold by ~1e-10 and A_TT's
        // condition number scales that; 1e-7 is far above both.
        let eig = a_tt.symmetric_eigen().eigenvalues;
        let kappa = eig.max() / eig.min();
        assert!(
            err < 1e-7,
            "{name}: relative |W − W_aug| = {err:.2e} (κ(A_TT) {kappa:.1e})"
        );
    }
}

#[test]
fn finger_force_matches_the_null_space_reference() {
    for name in scenes() {
        let (model, q) = state(name, 300);
        let ev = evaluation(&model, &q);
        let mut js = JointSpace::new(&model, &q, &ev).unwrap();
        let n = model.n_coords();
        // An arbitrary acceleration as well as gravity: b = Q_e − M q̈.
        let q_ddot = DVector::from_fn(n, |i, _| ((i * 37 % 11) as f64 - 5.0) * 0.3);
        let mut b = vec![0.0; n];
        let g = model.gravity_m_s2();
        for bm in BodyMass::of_model(&model) {
            let o = bm.offset;
            let f = frame(&q, o);
            let e = Vector4::new(q[o + 3], q[o + 4], q[o + 5], q[o + 6]);
            let ed = Vector4::new(q_ddot[o + 3], q_ddot[o + 4], q_ddot[o + 5], q_ddot[o + 6]);
            let (w, alpha) = crate::force::inertia::angular_motion(&f, &e, &Vector4::zeros(), &ed);
            let a = Vector3::new(q_ddot[o], q_ddot[o + 1], q_ddot[o + 2]);
            bm.generalized_force(&f, &g, &a, &w, &alpha, &mut b[o..o + 7]);
        }
        js.assemble(&model, &q, &ev).unwrap();
        js.factor().unwrap();
        let lambda = js.finger_solve(&model, &b).to_vec();
        let reference =
            crate::force::reference_finger_wrenches(&model, &q, &vec![0.0; n], q_ddot.as_slice())
                .unwrap();
        let cq = ev.jacobian().to_dense();
        let mut it = lambda.iter();
        let mut worst = (0.0f64, 0.0f64);
        for (k, finger) in model.fingers().iter().enumerate() {
            let o = model.layout().body_offset(finger.body).unwrap();
            let mut force = Vector3::zeros();
            for r in model.constraints()[finger.constraint.index()].rows.clone() {
                let l = it.next().unwrap();
                force += Vector3::new(cq[(r, o)], cq[(r, o + 1)], cq[(r, o + 2)]) * *l;
            }
            let want = reference[k].force_n;
            worst.0 = worst.0.max((force - want).norm());
            worst.1 = worst.1.max(want.norm());
        }
        assert!(worst.1 > 1e-3, "{name}: the load is not trivially zero");
        assert!(
            worst.0 < 1e-7 * worst.1,
            "{name}: |F − F_ref| {:.2e} of {:.2e} N",
            worst.0,
            worst.1
        );
    }
}

impl JointSpace {
    /// J_r S H⁻¹ Sᵀ J_rᵀ over every loop and finger row (no mask), at `q`.
    pub(crate) fn unmasked_gram(
        &mut self,
        model: &Model,
        q: &[f64],
        ev: &Evaluation,
    ) -> Result<(Vec<usize>, DMatrix<f64>), super::ReducedError> {
        let saved = (self.rows.clone(), self.n_loop);
        let mut rows = self.tree.loop_rows.clone();
        rows.extend(&self.tree.finger_rows);
        let (n, m) = (self.tree.dofs, rows.len());
        self.rows = rows.clone();
        (self.gt, self.w) = (faer::Mat::zeros(n, m), faer::Mat::zeros(m, m));
        self.assemble(model, q, ev)?;
        self.factor_h()?;
        let w = self.gram();
        (self.rows, self.n_loop) = saved;
        let k = self.rows.len();
        (self.gt, self.w) = (faer::Mat::zeros(n, k), faer::Mat::zeros(k, k));
        Ok((rows, w))
    }

    /// H (assembled, not factored) at `q`, dense.
    pub(crate) fn joint_inertia(&mut self, model: &Model, q: &[f64]) -> DMatrix<f64> {
        self.kin.update(model, &self.tree, q).expect("frames");
        self.inertia();
        DMatrix::from_fn(self.tree.dofs, self.tree.dofs, |i, j| self.h[(i, j)])
    }
}
