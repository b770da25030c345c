//! Masked rows kept closed while design columns move.
//!
//! `Program::new` masks equality rows that are redundant at q0 with the
//! design frozen (`force::redundancy`): in the body columns they are
//! combinations of the kept rows, so enforcing the kept rows enforces them.
//! Once design columns move, the geometry changes and they need not be: a
//! Bennett 4R loop is mobile only because of its proportions (a / sin α =
//! b / sin β); free one of its anchors and the three rows masked at build
//! stop following from the others, and the loop came apart (15 mm, half
//! the ticks failed) while nothing in the step looked at them.
//!
//! In the body columns a masked row m still is a combination of the joint
//! rows: J_b,m = T_m J_b,J, so its body part adds nothing the kept rows'
//! multipliers cannot carry. What it adds is a condition on the design
//! step v (scaled units, as in `design`): with the kept rows' linearisation
//! enforced, row m's is
//!
//! ```text
//! G v = h,   G_m = U_m − T_m U,   h_m = r_m − T_m r
//! ```
//!
//! U the scaled design columns of the kept rows, r their right-hand side,
//! U_m, r_m row m's (scaled by its ℓ). T_m comes from the factor the step
//! already has: T_mᵀ = A_JJ⁻¹ a_m, a_m = D J_b M⁻¹ J_b,mᵀ ℓ_m (one sparse
//! product and one solve per masked row, once per factorisation, with Z).
//! The design step then solves the small KKT system
//!
//! ```text
//! [ S  −Gᵀ ] [ v   ]   [ Uᵀ ŷ₀ ]
//! [ G   0  ] [ y_m ] = [ h     ]      S = W + Uᵀ P U (as in `design`)
//! ```
//!
//! by y_m = K⁺ (h − G S⁻¹ Uᵀ ŷ₀), K = G S⁻¹ Gᵀ (a minimum-norm solve: rows
//! whose design part cancels, such as a planar linkage's out-of-plane rows
//! under planar design changes, have G = 0 to round-off and drop out, and
//! the step is exactly the plain one), v = S⁻¹ (Uᵀ ŷ₀ + Gᵀ y_m); the kept
//! rows' ŷ = ŷ₀ − Z v as before, and each design column's pull is
//! (Uᵀ ŷ + Gᵀ y_m)_c. Frozen (bounded) columns enter with their fixed step.
//!
//! # Real-time
//! No allocation: every buffer is sized by `new`.

use crate::force::feedback::Feedback;
use crate::force::small::{factor_in_place, min_norm_solve, substitute};
use crate::{Evaluation, Model};

/// The masked equality rows of a program with design columns (see the
/// module docs).
#[derive(Debug, Clone)]
pub(crate) struct MaskedRows {
    /// (model row, ℓ) of each masked equality row.
    rows: Vec<(usize, f64)>,
    /// Columns of q that belong to bodies (design columns follow).
    body_cols: usize,
    /// Per masked row: T_m over model rows, row-major r × m.
    t: Vec<f64>,
    /// G, row-major r × n_d (design columns in `DesignStep` order).
    g: Vec<f64>,
    /// Per masked row: ℓ_m J_m,c per design column, r × n_d.
    um: Vec<f64>,
    /// K's reference scale: the largest Σ_c (|U_m,c| + |T_m| |U_c|)² / w_c,
    /// the size of the terms G is the difference of (a masked row whose
    /// design part cancels, G at round-off of that, has rank 0 in K).
    reference: f64,
    /// This step's h (before frozen columns), and y_m.
    h: Vec<f64>,
    pub y: Vec<f64>,
    /// Scratch.
    gq: Vec<f64>,
    mq: Vec<f64>,
    jrow: Vec<f64>,
    sj: Vec<f64>,
    k: Vec<f64>,
    eig: Vec<f64>,
    rhs_m: Vec<f64>,
    x: Vec<f64>,
    l: Vec<f64>,
}

impl MaskedRows {
    /// For `masked` (model row, ℓ) of `model`, whose design step has `n`
    /// columns; `None` without any. Allocates.
    pub fn new(model: &Model, masked: &[(usize, f64)], n: usize) -> Option<Self> {
        if masked.is_empty() || n == 0 {
            return None;
        }
        let (r, m, nq) = (masked.len(), model.n_rows(), model.n_coords());
        Some(Self {
            rows: masked.to_vec(),
            body_cols: model.layout().body_coords(),
            t: vec![0.0; r * m],
            g: vec![0.0; r * n],
            um: vec![0.0; r * n],
            reference: 0.0,
            h: vec![0.0; r],
            y: vec![0.0; r],
            gq: vec![0.0; nq],
            mq: vec![0.0; nq],
            jrow: vec![0.0; m],
            sj: vec![0.0; m],
            k: vec![0.0; r * r],
            eig: vec![0.0; r * r],
            rhs_m: vec![0.0; r],
            x: vec![0.0; n * r],
            l: vec![0.0; n * n],
        })
    }

    /// T, U_m and G for the factor `fb` holds and the Jacobian of `ev`;
    /// `u` the design step's scaled columns (column-major n × m), `cols`
    /// their q columns, `w` their metric. Once per factorisation.
    pub fn refresh(
        &mut self,
        ev: &Evaluation,
        fb: &mut Feedback,
        u: &[f64],
        cols: &[usize],
        w: &[f64],
    ) -> Result<(), ()> {
        let jac = ev.jacobian();
        let (m, n) = (self.jrow.len(), cols.len());
        let (ptr, idx, val) = (jac.row_ptr(), jac.col_idx(), jac.values());
        self.reference = 0.0;
        for (k, &(row, ell)) in self.rows.iter().enumerate() {
            // a_m = D J_b M⁻¹ J_b,mᵀ ℓ_m, then T_mᵀ = A_JJ⁻¹ a_m.
            self.gq.fill(0.0);
            let um = &mut self.um[k * n..(k + 1) * n];
            um.fill(0.0);
            for p in ptr[row]..ptr[row + 1] {
                let c = idx[p];
                if c < self.body_cols {
                    self.gq[c] = ell * val[p];
                } else if let Ok(d) = cols.binary_search(&c) {
                    um[d] = ell * val[p];
                }
            }
            fb.apply_inverse_mass(&self.gq, &mut self.mq);
            jac.mul_vec(&self.mq, &mut self.jrow).map_err(|_| ())?;
            let (scale, jrows) = (fb.row_scale(), fb.joint_rows());
            let nj = jrows.len();
            for (j, &i) in jrows.iter().enumerate() {
                self.sj[j] = scale[i] * self.jrow[i];
            }
            fb.solve_joint(&mut self.sj[..nj]);
            let t = &mut self.t[k * m..(k + 1) * m];
            t.fill(0.0);
            for (j, &i) in fb.joint_rows().iter().enumerate() {
                t[i] = self.sj[j];
            }
            // G, and the size of the terms it is the difference of: a row
            // whose G cancels to round-off of that size has no design part.
            let t_norm = dot(t, t).sqrt();
            let mut size = 0.0;
            for d in 0..n {
                let ud = &u[d * m..(d + 1) * m];
                let um = self.um[k * n + d];
                self.g[k * n + d] = um - dot(t, ud);
                size += (um.abs() + t_norm * dot(ud, ud).sqrt()).powi(2) / w[d];
            }
            self.reference = self.reference.max(size);
        }
        if !self.t.iter().chain(&self.g).all(|x| x.is_finite()) {
            return Err(());
        }
        Ok(())
    }

    /// This step's h_m = ℓ_m (c_m − J_m d) − T_m r (`r`: the kept rows'
    /// scaled right-hand side, `d`: the step's offset from q_ref).
    pub fn prepare(&mut self, ev: &Evaluation, d: &[f64], r: &[f64]) {
        let jac = ev.jacobian();
        let (ptr, idx, val) = (jac.row_ptr(), jac.col_idx(), jac.values());
        let c = ev.values();
        let m = self.jrow.len();
        for (k, &(row, ell)) in self.rows.iter().enumerate() {
            let jd: f64 = (ptr[row]..ptr[row + 1]).map(|p| val[p] * d[idx[p]]).sum();
            self.h[k] = ell * (c[row] - jd) - dot(&self.t[k * m..(k + 1) * m], r);
        }
    }

    /// The design step v over the `free` columns (`small`: S over them,
    /// row-major; `rhs`: Uᵀ ŷ₀ over them, becomes v) with the
    /// masked rows' condition; `dd[c]`: the fixed step offset of each
    /// frozen column c (0 for free ones), `n`: all columns. Sets
    /// [`y`](Self::y). False if S is not positive definite.
    pub fn solve(
        &mut self,
        small: &[f64],
        rhs: &mut [f64],
        free: &[usize],
        dd: &[f64],
        n: usize,
    ) -> bool {
        let (r, nf) = (self.rows.len(), free.len());
        // h with the frozen columns' fixed steps: h − Σ_frozen G_c dd_c.
        for k in 0..r {
            let frozen: f64 = (0..n).map(|c| self.g[k * n + c] * dd[c]).sum();
            self.rhs_m[k] = self.h[k] - frozen;
        }
        self.y.fill(0.0);
        if nf == 0 {
            return true;
        }
        let l = &mut self.l[..nf * nf];
        l.copy_from_slice(&small[..nf * nf]);
        if !factor_in_place(l, nf) {
            return false;
        }
        // b0 = S⁻¹ Uᵀ ŷ₀; X = S⁻¹ G_freeᵀ (column k: masked row k).
        substitute(l, &mut rhs[..nf]);
        for k in 0..r {
            let x = &mut self.x[k * nf..(k + 1) * nf];
            for (i, &a) in free.iter().enumerate() {
                x[i] = self.g[k * n + a];
            }
            substitute(l, x);
        }
        // K = G X, rhs_m −= G b0.
        for a in 0..r {
            for b in 0..r {
                self.k[a * r + b] = free
                    .iter()
                    .enumerate()
                    .map(|(i, &c)| self.g[a * n + c] * self.x[b * nf + i])
                    .sum();
            }
            let gb: f64 = free
                .iter()
                .enumerate()
                .map(|(i, &c)| self.g[a * n + c] * rhs[i])
                .sum();
            self.rhs_m[a] -= gb;
        }
        min_norm_solve(
            &mut self.k,
            &self.rhs_m,
            &mut self.y,
            &mut self.eig,
            self.reference,
        );
        // v = b0 + X y_m.
        for (i, v) in rhs[..nf].iter_mut().enumerate() {
            *v += (0..r).map(|k| self.x[k * nf + i] * self.y[k]).sum::<f64>();
        }
        true
    }

    /// (Gᵀ y_m)_c: what the masked rows add to design column c's pull.
    pub fn pull(&self, c: usize, n: usize) -> f64 {
        self.y
            .iter()
            .enumerate()
            .map(|(k, y)| self.g[k * n + c] * y)
            .sum()
    }
}

#[inline]
fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}
