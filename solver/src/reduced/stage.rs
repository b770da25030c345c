//! The joint tick's end: forward kinematics at the last iterate, J_r S
//! there, and Eq. 7 in joint coordinates with the factors the next tick's
//! steps reuse (plain loops on preallocated slices; `core` computes the
//! same quantities with faer and checks them):
//!
//! ```text
//! H = Lᵀ L (composite inertias),  Y = L⁻ᵀ (D J_r S)ᵀ,  W = Yᵀ Y
//! W_LL = L_L L_Lᵀ,  Z = L_L⁻¹ W_LF,  Σ_F = W_FF − Zᵀ Z,  Σ_F + 1/(K m̄) = L_K L_Kᵀ
//! τ = Sᵀ b,  g = Y L⁻¹ τ,  λ̃_F = Σ_F⁺ (g_F − Zᵀ L_L⁻¹ g_L)
//! ```
//!
//! b is the force stage's: gravity and −M q̈ with each body's velocity and
//! acceleration differenced from its poses (`force::motion`, its filter
//! included); the finger output adds the virtual coupling as
//! `Feedback::wrenches` does.
//!
//! H's factor, the solves with it, Y and W follow the tree's branches
//! (`branch`: Lᵀ L from the leaves up, no fill; Y's rows and W's dots over
//! each row's nonzeros), so a coordinate costs its path's depth, not n.

use nalgebra::{Matrix3, Matrix6, UnitQuaternion, Vector3, Vector6};

use super::ReducedError;
use super::branch::{Paths, dof_parents, factor_ltl, solve, solve_lt, sparse_dot, support};
use super::kinematics::{Kinematics, Twist};
use super::small::{dot, forward};
use super::tree::JointTree;
use crate::force::ACCELERATION_FILTER_FRACTION;
use crate::force::inertia::BodyMass;
use crate::force::small::{factor_in_place, min_norm_solve};
use crate::{BodyId, Model};

/// One body's motion history (`force::motion`).
#[derive(Debug, Clone, Copy)]
pub(super) struct History {
    pub e: UnitQuaternion<f64>,
    pub r: Vector3<f64>,
    pub v: Vector3<f64>,
    pub w: Vector3<f64>,
    pub a: Vector3<f64>,
    pub alpha: Vector3<f64>,
}

/// Factors and buffers of the force stage.
pub(crate) struct Stage {
    /// H, then its factor L (H = Lᵀ L, `branch`; n × n, lower triangle).
    pub h: Vec<f64>,
    /// Per joint coordinate, its ancestors (`branch`).
    pub(super) paths: Paths,
    /// Y row by row: row i = L⁻ᵀ (D J_r S)ᵢ (m × n).
    pub(super) yt: Vec<f64>,
    /// Row i of Y's nonzero positions: `supp[i * n..i * n + supp_len[i]]`.
    pub(super) supp: Vec<u32>,
    pub(super) supp_len: Vec<usize>,
    pub(super) w: Vec<f64>,
    /// W_LL's factor (nl × nl), Z row by finger row (mf × nl).
    pub wll: Vec<f64>,
    pub z: Vec<f64>,
    sig: Vec<f64>,
    /// Σ_F + 1/(K m̄), factored (mf × mf).
    pub sk: Vec<f64>,
    work: Vec<f64>,
    eig: Vec<f64>,
    pub(crate) g: Vec<f64>,
    pub(crate) tau: Vec<f64>,
    pub lambda_f: Vec<f64>,
    reference: f64,
    ic: Vec<Matrix6<f64>>,
    /// Per body (model order).
    mass: Vec<Option<BodyMass>>,
    /// Moving bodies (index, first column) with their history.
    pub(super) bodies: Vec<(usize, usize, History)>,
    pub(super) ticks: u32,
    /// Per finger: its first row in the finger block, row count, the
    /// body's end.
    pub(super) fingers: Vec<(usize, usize, usize)>,
    pub(super) prev_error: Vec<Vector3<f64>>,
}

impl Stage {
    /// Buffers for n joint coordinates and m kept rows (nl loop rows).
    /// Allocates.
    pub fn new(model: &Model, tree: &JointTree, n: usize, m: usize, nl: usize, q: &[f64]) -> Self {
        let mf = m - nl;
        let mut mass = vec![None; model.bodies().len()];
        let mut bodies = Vec::new();
        for bm in BodyMass::of_model(model) {
            let (b, _) = model
                .layout()
                .moving_bodies()
                .find(|(_, o)| *o == bm.offset)
                .expect("moving body");
            let (r, e) = pose(q, bm.offset);
            let h = History {
                e,
                r,
                v: Vector3::zeros(),
                w: Vector3::zeros(),
                a: Vector3::zeros(),
                alpha: Vector3::zeros(),
            };
            bodies.push((b.index(), bm.offset, h));
            mass[b.index()] = Some(bm);
        }
        let mut fingers = Vec::new();
        let mut next = 0;
        for f in model.fingers() {
            let c = f.constraint.index();
            let rows = model.constraints()[c].rows.len();
            let end = usize::from(model.geometry[c].frames()[0] != f.body.index());
            fingers.push((next, rows, end));
            next += rows;
        }
        Self {
            h: vec![0.0; n * n],
            paths: Paths::new(dof_parents(tree)),
            yt: vec![0.0; m * n],
            supp: vec![0; m * n],
            supp_len: vec![0; m],
            w: vec![0.0; m * m],
            wll: vec![0.0; nl * nl],
            z: vec![0.0; mf * nl],
            sig: vec![0.0; mf * mf],
            sk: vec![0.0; mf * mf],
            work: vec![0.0; mf * mf],
            eig: vec![0.0; mf * mf],
            g: vec![0.0; m],
            tau: vec![0.0; n],
            lambda_f: vec![0.0; mf],
            reference: 0.0,
            ic: vec![Matrix6::zeros(); tree.joints.len()],
            mass,
            bodies,
            ticks: 0,
            fingers,
            prev_error: vec![Vector3::zeros(); model.fingers().len()],
        }
    }

    /// H = Sᵀ M S by composite inertias (as `JointSpace::inertia`).
    pub(super) fn inertia(&mut self, tree: &JointTree, kin: &Kinematics) {
        let n = tree.dofs;
        self.h.fill(0.0);
        for (k, j) in tree.joints.iter().enumerate() {
            let m = self.mass[j.child.index()].as_ref().expect("moving");
            let f = &kin.frames[j.child.index()];
            let c = f.r.cross_matrix();
            let mut i6 = Matrix6::zeros();
            i6.fixed_view_mut::<3, 3>(0, 0)
                .copy_from(&(m.world_inertia(f) - c * c * m.mass));
            i6.fixed_view_mut::<3, 3>(0, 3).copy_from(&(c * m.mass));
            i6.fixed_view_mut::<3, 3>(3, 0).copy_from(&(-c * m.mass));
            i6.fixed_view_mut::<3, 3>(3, 3)
                .copy_from(&(Matrix3::identity() * m.mass));
            self.ic[k] = i6;
        }
        for k in (0..tree.joints.len()).rev() {
            if let Some(p) = tree.joints[k].parent_joint {
                let add = self.ic[k];
                self.ic[p] += add;
            }
        }
        let six = |t: &Twist| Vector6::new(t.w.x, t.w.y, t.w.z, t.v.x, t.v.y, t.v.z);
        for (k, j) in tree.joints.iter().enumerate() {
            for d in j.dof..j.dof + j.freedom.dofs() {
                let f = self.ic[k] * six(&kin.twists[d]);
                let mut up = Some(k);
                while let Some(u) = up {
                    let ju = &tree.joints[u];
                    for e in ju.dof..ju.dof + ju.freedom.dofs() {
                        let v = f.dot(&six(&kin.twists[e]));
                        self.h[d * n + e] = v;
                        self.h[e * n + d] = v;
                    }
                    up = ju.parent_joint;
                }
            }
        }
    }

    /// Factors H, W, W_LL, Σ_F and Σ_F + 1/(K m̄) from D J_r S (`jr`).
    pub(super) fn factor(
        &mut self,
        tree: &JointTree,
        kin: &Kinematics,
        jr: &[f64],
        nl: usize,
        k_inv: &[f64],
    ) -> Result<(), ReducedError> {
        self.inertia(tree, kin);
        let n = tree.dofs;
        let m = jr.len() / n.max(1);
        let mf = m - nl;
        #[cfg(test)]
        let h0 = super::stage_check::enabled().then(|| self.h.clone());
        if !factor_ltl(&mut self.h, &self.paths) {
            return Err(ReducedError::NotPositive("H"));
        }
        self.gram(jr, n, m);
        #[cfg(test)]
        if let Some(h0) = h0 {
            super::stage_check::factor(&h0, jr, self, m);
        }
        self.loop_block(m, nl)?;
        self.reference = 0.0;
        for f in 0..mf {
            self.reference = self.reference.max(self.w[(nl + f) * m + nl + f]);
        }
        self.sk.copy_from_slice(&self.sig);
        for (f, k) in k_inv.iter().enumerate() {
            self.sk[f * mf + f] += k;
        }
        if !factor_in_place(&mut self.sk, mf) {
            return Err(ReducedError::NotPositive("Σ_F + 1/(K m̄)"));
        }
        Ok(())
    }

    /// Y = L⁻ᵀ (D J_r S)ᵀ row by row (each row's work the ancestors of its
    /// nonzeros) with its rows' supports, and W = Yᵀ Y over them.
    fn gram(&mut self, jr: &[f64], n: usize, m: usize) {
        // Fewer rows than the buffers hold while limits are inactive.
        self.yt[..jr.len()].copy_from_slice(jr);
        for i in 0..m {
            let y = &mut self.yt[i * n..(i + 1) * n];
            solve_lt(&self.h, &self.paths, y);
            self.supp_len[i] = support(y, &mut self.supp[i * n..(i + 1) * n]);
        }
        for a in 0..m {
            for b in 0..=a {
                let s = if self.supp_len[a] <= self.supp_len[b] {
                    a
                } else {
                    b
                };
                let s = &self.supp[s * n..s * n + self.supp_len[s]];
                let v = sparse_dot(
                    s,
                    &self.yt[a * n..(a + 1) * n],
                    &self.yt[b * n..(b + 1) * n],
                );
                self.w[a * m + b] = v;
                self.w[b * m + a] = v;
            }
        }
    }

    /// x ← H⁻¹ x with H's factor (the steps' u).
    pub(super) fn solve_h(&self, x: &mut [f64]) {
        #[cfg(test)]
        let x0 = super::stage_check::enabled().then(|| x.to_vec());
        solve(&self.h, &self.paths, x);
        #[cfg(test)]
        if let Some(x0) = x0 {
            super::stage_check::solve(x0, x);
        }
    }

    /// Advances the motion history to `frames` (as `Motion::advance`) and
    /// forms τ = Sᵀ b.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn load(
        &mut self,
        model: &Model,
        tree: &JointTree,
        kin: &Kinematics,
        q: &[f64],
        dt_s: f64,
        tau_s: f64,
    ) {
        let (af, aa) = if tau_s > 0.0 {
            let ratio = ACCELERATION_FILTER_FRACTION;
            (dt_s / (tau_s + dt_s), dt_s / (ratio * tau_s + dt_s))
        } else {
            (1.0, 1.0)
        };
        let first = self.ticks == 0;
        let g = model.gravity_m_s2();
        self.tau.fill(0.0);
        for (b, o, h) in self.bodies.iter_mut() {
            let f = &kin.frames[*b];
            let (r, e) = pose(q, *o);
            let v_raw = (r - h.r) / dt_s;
            let w_raw = (e * h.e.inverse()).scaled_axis() / dt_s;
            let v = h.v + (v_raw - h.v) * af;
            let w = h.w + (w_raw - h.w) * af;
            if first {
                h.a = Vector3::zeros();
                h.alpha = Vector3::zeros();
            } else {
                h.a += ((v - h.v) / dt_s - h.a) * aa;
                h.alpha += ((w - h.w) / dt_s - h.alpha) * aa;
            }
            (h.v, h.w, h.r, h.e) = (v, w, r, e);
            let m = self.mass[*b].as_ref().expect("moving");
            let mut b7 = [0.0; 7];
            m.generalized_force(f, &g, &h.a, &h.w, &h.alpha, &mut b7);
            kin.project(tree, BodyId(*b as u32), &b7, &mut self.tau);
        }
        self.ticks = self.ticks.saturating_add(1);
    }

    /// λ̃_F for τ (after [`Self::factor`] and [`Self::load`]).
    pub(super) fn finger_solve(&mut self, n: usize, nl: usize) {
        let mf = self.lambda_f.len();
        let m = nl + mf;
        solve_lt(&self.h, &self.paths, &mut self.tau);
        for i in 0..m {
            let s = &self.supp[i * n..i * n + self.supp_len[i]];
            self.g[i] = sparse_dot(s, &self.yt[i * n..(i + 1) * n], &self.tau);
        }
        let (gl, gf) = self.g[..m].split_at_mut(nl);
        forward(&self.wll, gl);
        for (f, v) in gf.iter_mut().enumerate() {
            *v -= dot(&self.z[f * nl..(f + 1) * nl], gl);
        }
        self.work.copy_from_slice(&self.sig);
        debug_assert_eq!(gf.len(), mf);
        min_norm_solve(
            &mut self.work,
            gf,
            &mut self.lambda_f,
            &mut self.eig,
            self.reference,
        );
    }

    /// Copies the factors (not the motion history) into `to`, a stage of
    /// the same sizes (`limits`: the steps' factors kept aside while Eq. 7
    /// is solved without a released limit). No allocation.
    pub(super) fn copy_factors(&self, to: &mut Stage) {
        to.h.copy_from_slice(&self.h);
        to.yt.copy_from_slice(&self.yt);
        to.supp.copy_from_slice(&self.supp);
        to.supp_len.copy_from_slice(&self.supp_len);
        to.w.copy_from_slice(&self.w);
        to.wll.copy_from_slice(&self.wll);
        to.z.copy_from_slice(&self.z);
        to.sig.copy_from_slice(&self.sig);
        to.sk.copy_from_slice(&self.sk);
        to.reference = self.reference;
    }

    /// The factors for Eq. 7 without the loop rows `gone` (kept-row
    /// positions, ascending, all < `nl`; `limits`: released limits), from
    /// the current ones for m rows: their rows of Y and rows and columns of
    /// W dropped, W_LL, Z and Σ_F formed again (H's factor is unchanged;
    /// Σ_F + 1/(K m̄), for the steps, is not formed). No allocation.
    pub(super) fn drop_loop_rows(
        &mut self,
        n: usize,
        m: usize,
        nl: usize,
        gone: &[usize],
    ) -> Result<(), ReducedError> {
        let kept = |i: &usize| !gone.contains(i);
        let (m2, nl2) = (m - gone.len(), nl - gone.len());
        for (to, from) in (0..m).filter(kept).enumerate() {
            self.yt.copy_within(from * n..(from + 1) * n, to * n);
            self.supp.copy_within(from * n..(from + 1) * n, to * n);
            self.supp_len[to] = self.supp_len[from];
        }
        let mut to = 0;
        for a in (0..m).filter(kept) {
            for b in (0..m).filter(kept) {
                self.w[to] = self.w[a * m + b];
                to += 1;
            }
        }
        self.loop_block(m2, nl2)
    }

    /// From W (m × m, its first `nl` rows the loop rows): W_LL's factor,
    /// Z = W_LL⁻¹ᐟ² W_LF and Σ_F = W_FF − ZᵀZ, shared by [`Stage::factor`]
    /// and [`Stage::drop_loop_rows`].
    fn loop_block(&mut self, m: usize, nl: usize) -> Result<(), ReducedError> {
        let mf = m - nl;
        for a in 0..nl {
            self.wll[a * nl..(a + 1) * nl].copy_from_slice(&self.w[a * m..a * m + nl]);
        }
        if !factor_in_place(&mut self.wll, nl) {
            return Err(ReducedError::NotPositive("W_LL"));
        }
        for f in 0..mf {
            let zf = &mut self.z[f * nl..(f + 1) * nl];
            for (a, z) in zf.iter_mut().enumerate() {
                *z = self.w[a * m + nl + f];
            }
            forward(&self.wll, zf);
        }
        for f in 0..mf {
            for g in 0..mf {
                let zz = dot(&self.z[f * nl..(f + 1) * nl], &self.z[g * nl..(g + 1) * nl]);
                self.sig[f * mf + g] = self.w[(nl + f) * m + nl + g] - zz;
            }
        }
        Ok(())
    }
}

/// Position and unit orientation of the body at column `o` of q.
pub(super) fn pose(q: &[f64], o: usize) -> (Vector3<f64>, UnitQuaternion<f64>) {
    let e = nalgebra::Quaternion::new(q[o + 3], q[o + 4], q[o + 5], q[o + 6]);
    (
        Vector3::new(q[o], q[o + 1], q[o + 2]),
        UnitQuaternion::new_normalize(e),
    )
}
