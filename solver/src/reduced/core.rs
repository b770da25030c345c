//! The Eq. 7 core in joint coordinates: H = Sᵀ M̃ S by the composite
//! rigid-body algorithm, the kept rows' J_r = C_{r,q} S, and the finger
//! Schur complement after the loop rows are eliminated.
//!
//! ```text
//! H = L Lᵀ,   Y = L⁻¹ J_rᵀ,   W = Yᵀ Y = J_r H⁻¹ J_rᵀ = [W_LL W_LF; W_FL W_FF]
//! W_LL = L_L L_Lᵀ,   Z = L_L⁻¹ W_LF,   Σ_F = W_FF − Zᵀ Z
//! τ = Sᵀ b,   g = Y (L⁻¹ τ),   Σ_F λ_F = g_F − Zᵀ L_L⁻¹ g_L   (pseudo-inverse)
//! ```
//!
//! Loop rows dependent on the others (a planar loop of revolutes in 3-D)
//! are masked once, at construction, by a Cholesky of W_LL in row order that
//! drops a row whose pivot is below [`PIVOT_RATIO`] of its diagonal (the
//! squared sine of its angle to the rows before it, in the H⁻¹ metric) —
//! the joint-space counterpart of `force::redundancy`'s ordered test.
//! Finger angle rows are scaled by the characteristic length before the
//! pseudo-inverse, as in the fast path and `force::reference`.
//! Measurement-only: allocates at construction, not per call.

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::cholesky::llt::factor::cholesky_in_place_scratch;
use faer::linalg::cholesky::llt::factor::{LltRegularization, cholesky_in_place};
use faer::linalg::matmul::matmul;
use faer::linalg::triangular_solve::solve_lower_triangular_in_place;
use faer::{Accum, Mat, Par};
use nalgebra::{DMatrix, DVector, Matrix3, Matrix6, Vector6};

use super::ReducedError;
use super::kinematics::Kinematics;
use super::tree::JointTree;
use crate::force::inertia::BodyMass;
use crate::{BodyId, Evaluation, Model, RowUnit};

/// A loop row is dependent when its pivot in W_LL is below this fraction of
/// its diagonal.
pub const PIVOT_RATIO: f64 = 1e-8;

/// A loop row whose diagonal in W_LL is below this fraction of the largest
/// is measured against that floor, not its own diagonal (a row that no tree
/// motion moves, the out-of-plane rows of a planar loop, has a diagonal of
/// round-off, and a pivot ratio of round-off over round-off).
pub const ZERO_ROW: f64 = 1e-6;

/// Eigenvalues of Σ_F below this fraction of the largest are treated as 0.
pub const PINV_RATIO: f64 = 1e-10;

/// Workspace of the joint-space Eq. 7 core for one model.
pub struct JointSpace {
    /// The spanning tree.
    pub tree: JointTree,
    /// Frames and twists at the last assembled q.
    pub kin: Kinematics,
    /// Mass data per body (model order), `None` for fixed bodies.
    mass: Vec<Option<BodyMass>>,
    /// Per column of q: (body, local column 0..7).
    col_body: Vec<(u32, u8)>,
    /// Composite spatial inertia (w, v order, about the origin) per joint.
    ic: Vec<Matrix6<f64>>,
    /// H, then its Cholesky factor (lower).
    pub(crate) h: Mat<f64>,
    /// The kept rows: independent loop rows, then the finger rows.
    pub(crate) rows: Vec<usize>,
    /// Kept loop rows.
    pub(crate) n_loop: usize,
    /// Scale of each finger row (1, or the characteristic length).
    finger_scale: Vec<f64>,
    /// J_rᵀ, then Y = L⁻¹ J_rᵀ (dofs × rows).
    pub(crate) gt: Mat<f64>,
    /// W, then [L_L, Z; ·, Σ_F].
    pub(crate) w: Mat<f64>,
    tau: Mat<f64>,
    pub(super) rhs: Mat<f64>,
    mem: MemBuffer,
    /// The finger multipliers of the last [`Self::finger_solve`].
    pub lambda_f: Vec<f64>,
}

impl JointSpace {
    /// The workspace, with the loop rows' mask found at `q` (whose
    /// evaluation is `ev`).
    ///
    /// # Errors
    /// An unsupported model ([`JointTree::new`]), or a degenerate q.
    pub fn new(model: &Model, q: &[f64], ev: &Evaluation) -> Result<Self, ReducedError> {
        let tree = JointTree::new(model)?;
        let kin = Kinematics::new(model, &tree);
        let mut mass = vec![None; model.bodies().len()];
        let mut col_body = vec![(u32::MAX, 0u8); model.n_coords()];
        for m in BodyMass::of_model(model) {
            let (b, _) = model
                .layout()
                .moving_bodies()
                .find(|(_, o)| *o == m.offset)
                .expect("moving body");
            for k in 0..7 {
                col_body[m.offset + k] = (b.0, k as u8);
            }
            mass[b.index()] = Some(m);
        }
        let n = tree.dofs;
        let ell = model.characteristic_length_m();
        let finger_scale = tree
            .finger_rows
            .iter()
            .map(|&r| {
                if model.rows()[r].unit == RowUnit::Length {
                    1.0
                } else {
                    ell
                }
            })
            .collect();
        let mut rows = tree.loop_rows.clone();
        let n_loop = rows.len();
        rows.extend(&tree.finger_rows);
        let m = rows.len();
        let req = StackReq::any_of(&[cholesky_in_place_scratch::<f64>(
            n.max(m),
            Par::Seq,
            Default::default(),
        )]);
        let mut s = Self {
            ic: vec![Matrix6::zeros(); tree.joints.len()],
            tree,
            kin,
            mass,
            col_body,
            h: Mat::zeros(n, n),
            rows,
            n_loop,
            finger_scale,
            gt: Mat::zeros(n, m),
            w: Mat::zeros(m, m),
            tau: Mat::zeros(n, 1),
            rhs: Mat::zeros(m, 1),
            mem: MemBuffer::new(req),
            lambda_f: Vec::new(),
        };
        s.mask(model, q, ev)?;
        Ok(s)
    }

    /// Masked loop rows.
    pub fn masked(&self) -> usize {
        self.tree.loop_rows.len() - self.n_loop
    }

    /// The kept rows, loop rows first.
    pub fn rows(&self) -> &[usize] {
        &self.rows
    }

    /// Kinematics at `q`, H (CRBA) and J_rᵀ from `ev`'s Jacobian at `q`.
    ///
    /// # Errors
    /// A degenerate quaternion; a row touching more than two bodies.
    pub fn assemble(
        &mut self,
        model: &Model,
        q: &[f64],
        ev: &Evaluation,
    ) -> Result<(), ReducedError> {
        self.kin.update(model, &self.tree, q)?;
        self.inertia();
        let jac = ev.jacobian();
        let (rp, ci, vals) = (jac.row_ptr(), jac.col_idx(), jac.values());
        for (i, &r) in self.rows.iter().enumerate() {
            let col = self.gt.col_as_slice_mut(i);
            col.fill(0.0);
            let mut ends: [(u32, [f64; 7]); 2] = [(u32::MAX, [0.0; 7]); 2];
            for k in rp[r]..rp[r + 1] {
                let (b, local) = self.col_body[ci[k]];
                if b == u32::MAX {
                    continue;
                }
                let slot = match ends.iter().position(|e| e.0 == b || e.0 == u32::MAX) {
                    Some(s) => s,
                    None => {
                        return Err(ReducedError::Unsupported(format!(
                            "row {r} touches three bodies"
                        )));
                    }
                };
                ends[slot].0 = b;
                ends[slot].1[local as usize] += vals[k];
            }
            for (b, g) in ends.iter().filter(|e| e.0 != u32::MAX) {
                self.kin.project(&self.tree, BodyId(*b), g, col);
            }
        }
        Ok(())
    }

    /// H = Sᵀ M S by composite inertias (the c′ of M̃ acts only along e,
    /// which S never moves).
    pub(super) fn inertia(&mut self) {
        // Entries between branches stay 0; the factor overwrote the last H.
        self.h.fill(0.0);
        for (k, j) in self.tree.joints.iter().enumerate() {
            let m = self.mass[j.child.index()]
                .as_ref()
                .expect("tree children move");
            let f = &self.kin.frames[j.child.index()];
            let jw = m.world_inertia(f);
            let c = f.r.cross_matrix();
            let mut i6 = Matrix6::zeros();
            i6.fixed_view_mut::<3, 3>(0, 0)
                .copy_from(&(jw - c * c * m.mass));
            i6.fixed_view_mut::<3, 3>(0, 3).copy_from(&(c * m.mass));
            i6.fixed_view_mut::<3, 3>(3, 0).copy_from(&(-c * m.mass));
            i6.fixed_view_mut::<3, 3>(3, 3)
                .copy_from(&(Matrix3::identity() * m.mass));
            self.ic[k] = i6;
        }
        for k in (0..self.tree.joints.len()).rev() {
            if let Some(p) = self.tree.joints[k].parent_joint {
                let add = self.ic[k];
                self.ic[p] += add;
            }
        }
        let six =
            |t: &super::kinematics::Twist| Vector6::new(t.w.x, t.w.y, t.w.z, t.v.x, t.v.y, t.v.z);
        for (k, j) in self.tree.joints.iter().enumerate() {
            for d in j.dof..j.dof + j.freedom.dofs() {
                let f = self.ic[k] * six(&self.kin.twists[d]);
                let mut up = Some(k);
                while let Some(u) = up {
                    let ju = &self.tree.joints[u];
                    for e in ju.dof..ju.dof + ju.freedom.dofs() {
                        let v = f.dot(&six(&self.kin.twists[e]));
                        self.h[(d, e)] = v;
                        self.h[(e, d)] = v;
                    }
                    up = ju.parent_joint;
                }
            }
        }
    }

    pub(super) fn factor_h(&mut self) -> Result<(), ReducedError> {
        cholesky_in_place(
            self.h.as_mut(),
            LltRegularization::default(),
            Par::Seq,
            MemStack::new(&mut self.mem),
            Default::default(),
        )
        .map_err(|_| ReducedError::NotPositive("H"))?;
        Ok(())
    }

    /// Y = L⁻¹ J_rᵀ in place and W = Yᵀ Y (dense copy, for `mask` and tests).
    pub(super) fn gram(&mut self) -> DMatrix<f64> {
        solve_lower_triangular_in_place(self.h.as_ref(), self.gt.as_mut(), Par::Seq);
        matmul(
            self.w.as_mut(),
            Accum::Replace,
            self.gt.transpose(),
            self.gt.as_ref(),
            1.0,
            Par::Seq,
        );
        DMatrix::from_fn(self.w.nrows(), self.w.ncols(), |i, j| self.w[(i, j)])
    }

    /// Factor H, form W, factor its loop block and form Σ_F (after
    /// [`Self::assemble`]).
    ///
    /// # Errors
    /// H or the kept loop block not positive definite.
    pub fn factor(&mut self) -> Result<(), ReducedError> {
        self.factor_h()?;
        solve_lower_triangular_in_place(self.h.as_ref(), self.gt.as_mut(), Par::Seq);
        matmul(
            self.w.as_mut(),
            Accum::Replace,
            self.gt.transpose(),
            self.gt.as_ref(),
            1.0,
            Par::Seq,
        );
        let nl = self.n_loop;
        let (mut ll, mut lf, _, mut ff) = self.w.as_mut().split_at_mut(nl, nl);
        cholesky_in_place(
            ll.as_mut(),
            LltRegularization::default(),
            Par::Seq,
            MemStack::new(&mut self.mem),
            Default::default(),
        )
        .map_err(|_| ReducedError::NotPositive("W_LL"))?;
        solve_lower_triangular_in_place(ll.as_ref(), lf.as_mut(), Par::Seq);
        matmul(
            ff.as_mut(),
            Accum::Add,
            lf.as_ref().transpose(),
            lf.as_ref(),
            -1.0,
            Par::Seq,
        );
        Ok(())
    }

    /// Σ_F (after [`Self::factor`]), dense.
    pub fn finger_schur(&self) -> DMatrix<f64> {
        let (nl, mf) = (self.n_loop, self.tree.finger_rows.len());
        DMatrix::from_fn(mf, mf, |i, j| self.w[(nl + i, nl + j)])
    }

    /// The finger multipliers for the generalized force `b` (augmented, one
    /// entry per coordinate), after [`Self::factor`]: Σ_F⁺ (g_F − Zᵀ L_L⁻¹ g_L).
    pub fn finger_solve(&mut self, model: &Model, b: &[f64]) -> &[f64] {
        let t = self.tau.col_as_slice_mut(0);
        t.fill(0.0);
        for (body, o) in model.layout().moving_bodies() {
            let g: [f64; 7] = b[o..o + 7].try_into().expect("7");
            self.kin.project(&self.tree, body, &g, t);
        }
        solve_lower_triangular_in_place(self.h.as_ref(), self.tau.as_mut(), Par::Seq);
        matmul(
            self.rhs.as_mut(),
            Accum::Replace,
            self.gt.transpose(),
            self.tau.as_ref(),
            1.0,
            Par::Seq,
        );
        let nl = self.n_loop;
        let (ll, lf, _, _) = self.w.as_ref().split_at(nl, nl);
        let (mut gl, mut gf) = self.rhs.as_mut().split_at_row_mut(nl);
        solve_lower_triangular_in_place(ll, gl.as_mut(), Par::Seq);
        matmul(
            gf.as_mut(),
            Accum::Add,
            lf.transpose(),
            gl.as_ref(),
            -1.0,
            Par::Seq,
        );
        let mf = self.lambda_f.len();
        let sc = &self.finger_scale;
        if mf == 3 {
            // A point grasp: fixed size, no allocation.
            let sigma = Matrix3::from_fn(|i, j| self.w[(nl + i, nl + j)] * sc[i] * sc[j]);
            let rhs = nalgebra::Vector3::from_fn(|i, _| gf[(i, 0)] * sc[i]);
            let eig = sigma.symmetric_eigen();
            let top = eig.eigenvalues.max().max(0.0);
            let mut x = nalgebra::Vector3::zeros();
            for (k, &ev) in eig.eigenvalues.iter().enumerate() {
                if ev > PINV_RATIO * top {
                    let v = eig.eigenvectors.column(k);
                    x += v * (v.dot(&rhs) / ev);
                }
            }
            for i in 0..3 {
                self.lambda_f[i] = x[i] * sc[i];
            }
            return &self.lambda_f;
        }
        let sigma = DMatrix::from_fn(mf, mf, |i, j| self.w[(nl + i, nl + j)] * sc[i] * sc[j]);
        let rhs = DVector::from_fn(mf, |i, _| gf[(i, 0)] * sc[i]);
        let eig = sigma.symmetric_eigen();
        let top = eig.eigenvalues.iter().fold(0.0f64, |a, &v| a.max(v));
        let mut x = DVector::zeros(mf);
        for (k, &ev) in eig.eigenvalues.iter().enumerate() {
            if ev > PINV_RATIO * top {
                let v = eig.eigenvectors.column(k);
                x += v * (v.dot(&rhs) / ev);
            }
        }
        for i in 0..mf {
            self.lambda_f[i] = x[i] * sc[i];
        }
        &self.lambda_f
    }
}
