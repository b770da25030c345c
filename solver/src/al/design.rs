//! Design variables in the projected update: the Gauss–Newton step with the
//! design columns moving too, on the factor the step already has.
//!
//! The projected step (`projected`) solves, per iteration,
//! min ½ (d + Δ)ᵀ M̂ (d + Δ) + fingers s.t. C + J Δ = 0 through the scaled
//! normal equations Â ŷ = r̂, Â = D J M⁻¹ Jᵀ D (+ the fingers' diagonal), whose
//! factor the force solve computed. Design variables have no inertia: there
//! M⁻¹ = 0 and they would stay where they are. With a metric w_c per design
//! column (the least-astonishment weight of a design variable: the mean body
//! mass × `design_weight`), the matrix becomes Â + U W⁻¹ Uᵀ, U = D J_D the
//! scaled design columns: a rank-n_d update, solved by Woodbury with the
//! existing factor P = Â⁻¹,
//!
//! ```text
//! ŷ = ŷ₀ − Z S⁻¹ Uᵀ ŷ₀,   ŷ₀ = P r̂,   Z = P U,   S = W + Uᵀ Z    (n_d × n_d)
//! Δ_c = −d_c − (Jᵀ y)_c / w_c   on a design column c
//! ```
//!
//! Z costs n_d solves with the factor, once per factorisation (tracked by
//! `Feedback::generation`: once per tick, plus any in-tick activation);
//! each step then costs O(m n_d + n_d³) on top of the plain step. The Eq. 7
//! force solve is unchanged: design variables stay frozen there.
//!
//! **Bounds** (`constraint::bound`) are a box on the design columns, solved
//! as an active set inside the step: a column at a bound whose step would
//! leave the box, or one whose step would cross a bound, is *frozen* at that
//! bound (its d becomes q_c − b so that Δ_c = b − q_c, and it leaves the
//! Woodbury set; ŷ₀ follows as ŷ₀ − Z_c δd_c, no new solve); a frozen column
//! whose free step would point back inside is released. At most n_d + 2
//! rounds. A column switched off (Nelson & Cohen §3's flags, [`DesignStep::
//! set_off`]) is frozen where it is and never released. Pinned components (lo = hi) never enter: their d is set before
//! the right-hand side is formed ([`DesignStep::pin`]), so they cost no
//! solve. The result satisfies the linearised joints exactly, so bounds
//! never fight the joints.
//!
//! **Masked rows.** Rows masked as redundant at build with the design
//! frozen need not stay redundant once it moves (a Bennett loop); the small
//! solve above then carries their condition on the design step
//! (`design_closure`).
//!
//! # Real-time
//! No allocation: every buffer is sized by `new`.

use super::design_closure::MaskedRows;
use crate::force::feedback::Feedback;
use crate::force::small::cholesky_solve;
use crate::{Evaluation, Model};

/// A step that would leave the box by less than this (m) is not a crossing.
const BOX_SLACK_M: f64 = 1e-12;

/// Woodbury data of the design columns and the box active set.
#[derive(Debug, Clone)]
pub(crate) struct DesignStep {
    /// Design columns of q, ascending.
    pub cols: Vec<usize>,
    /// Indices (into `cols`) of the components that may move (not pinned).
    moving: Vec<usize>,
    /// w_c, kg.
    w: Vec<f64>,
    /// [lo, hi] per column (±∞ when unbounded).
    lo: Vec<f64>,
    hi: Vec<f64>,
    m: usize,
    /// U, column-major n_d × m: the scaled design columns of J.
    u: Vec<f64>,
    /// Z = P U, column-major.
    z: Vec<f64>,
    /// S = W + Uᵀ Z, n_d × n_d, row-major.
    s: Vec<f64>,
    /// The factorisation `z` and `s` belong to.
    generation: Option<u64>,
    /// Scratch: ŷ₀ of the round, the frozen set and its targets, t = Uᵀ ŷ.
    y0: Vec<f64>,
    frozen: Vec<bool>,
    at: Vec<f64>,
    d0: Vec<f64>,
    t: Vec<f64>,
    small: Vec<f64>,
    rhs: Vec<f64>,
    free: Vec<usize>,
    /// Per design column: W⁻¹ (Jᵀ y)_c of the last step (0 when frozen).
    pub mg: Vec<f64>,
    /// Rows masked as redundant with the design frozen, kept closed
    /// (`design_closure`); `None` without any.
    masked: Option<MaskedRows>,
    /// Scratch: each column's fixed step offset while frozen.
    dd: Vec<f64>,
    /// Per design column: switched off (Nelson & Cohen's flags: held where
    /// it is, like a pin at its current value).
    off: Vec<bool>,
}

impl DesignStep {
    /// For `model`'s design columns with metric `w_kg` each; `masked`: the
    /// equality rows masked as redundant (model row, ℓ). `None` without
    /// design columns. Allocates.
    pub fn new(model: &Model, w_kg: f64, masked: &[(usize, f64)]) -> Option<Self> {
        let l = model.layout();
        let cols: Vec<usize> = l.design_range().collect();
        if cols.is_empty() {
            return None;
        }
        let n = cols.len();
        let (mut lo, mut hi) = (vec![f64::NEG_INFINITY; n], vec![f64::INFINITY; n]);
        for d in l.design_vars() {
            if let Some(b) = d.bounds {
                for (k, range) in b.iter().take(d.width).enumerate() {
                    let c = d.offset + k - l.body_coords();
                    [lo[c], hi[c]] = *range;
                }
            }
        }
        let m = model.n_rows();
        let moving = (0..n).filter(|&k| lo[k] != hi[k]).collect();
        Some(Self {
            moving,
            w: vec![w_kg; n],
            lo,
            hi,
            m,
            u: vec![0.0; n * m],
            z: vec![0.0; n * m],
            s: vec![0.0; n * n],
            generation: None,
            y0: vec![0.0; m],
            frozen: vec![false; n],
            at: vec![0.0; n],
            d0: vec![0.0; n],
            t: vec![0.0; n],
            small: vec![0.0; n * n],
            rhs: vec![0.0; n],
            free: Vec::with_capacity(n),
            mg: vec![0.0; n],
            masked: MaskedRows::new(model, masked, n),
            dd: vec![0.0; n],
            off: vec![false; n],
            cols,
        })
    }

    /// Z and S for the factor `fb` holds and the Jacobian in `ev`, unless
    /// they are current. `k_inv`: the fingers' diagonal of the step.
    fn refresh(&mut self, ev: &Evaluation, fb: &mut Feedback, k_inv: &[f64]) -> Result<(), ()> {
        if self.generation == Some(fb.generation) {
            return Ok(());
        }
        let (n, m) = (self.cols.len(), self.m);
        let jac = ev.jacobian();
        let (ptr, rows, vals) = (jac.col_ptr(), jac.col_rows(), jac.col_value_index());
        self.u.fill(0.0);
        let scale = fb.row_scale();
        for (k, &c) in self.cols.iter().enumerate() {
            let col = &mut self.u[k * m..(k + 1) * m];
            for p in ptr[c]..ptr[c + 1] {
                col[rows[p]] = scale[rows[p]] * jac.values()[vals[p]];
            }
        }
        for &k in &self.moving {
            let (u, z) = (&self.u[k * m..(k + 1) * m], &mut self.z[k * m..(k + 1) * m]);
            z.fill(0.0);
            fb.project(u, k_inv, z).map_err(|_| ())?;
        }
        for &a in &self.moving {
            for &b in &self.moving {
                let v = dot(&self.u[a * m..(a + 1) * m], &self.z[b * m..(b + 1) * m]);
                self.s[a * n + b] = v + if a == b { self.w[a] } else { 0.0 };
            }
        }
        // Symmetrise round-off.
        for &a in &self.moving {
            for &b in self.moving.iter().filter(|&&b| b < a) {
                let v = 0.5 * (self.s[a * n + b] + self.s[b * n + a]);
                self.s[a * n + b] = v;
                self.s[b * n + a] = v;
            }
        }
        if let Some(mr) = &mut self.masked {
            mr.refresh(ev, fb, &self.u, &self.cols, &self.w)?;
        }
        self.generation = Some(fb.generation);
        Ok(())
    }

    /// Switches design column `k` (index among the design columns) off
    /// (held at its current value) or on.
    pub fn set_off(&mut self, k: usize, off: bool) {
        if let Some(f) = self.off.get_mut(k) {
            *f = off;
        }
    }

    /// Sets d on the pinned components so that their step lands on the pin
    /// (Δ_c = lo − q_c), and on the switched-off ones so that they stay
    /// (Δ_c = 0): call before the step's right-hand side is formed.
    ///
    /// # Real-time
    /// No allocation; O(n_d).
    pub fn pin(&self, q: &[f64], d: &mut [f64]) {
        for (k, &c) in self.cols.iter().enumerate() {
            if self.off[k] {
                d[c] = 0.0;
            } else if self.lo[k] == self.hi[k] {
                d[c] = q[c] - self.lo[k];
            }
        }
    }

    /// Corrects the plain step's ŷ₀ (in `y`, scaled, one per row) for the
    /// design columns, freezing bounded ones as needed; updates `d` on
    /// frozen columns (so that Δ_c = b − q_c) and fills [`Self::mg`]. `q`:
    /// the current configuration; `step`: the fraction of the step taken.
    /// Returns whether `d` changed (the caller's J d is then stale).
    ///
    /// # Real-time
    /// No allocation; at most n_d + 2 rounds of O(m n_d + n_d³).
    #[allow(clippy::too_many_arguments)]
    pub fn correct(
        &mut self,
        ev: &Evaluation,
        fb: &mut Feedback,
        k_inv: &[f64],
        q: &[f64],
        d: &mut [f64],
        r: &[f64],
        y: &mut [f64],
        step: f64,
    ) -> Result<bool, ()> {
        self.refresh(ev, fb, k_inv)?;
        if let Some(mr) = &mut self.masked {
            mr.prepare(ev, d, r);
        }
        self.start_frozen(q, d);
        for _round in 0..self.cols.len() + 2 {
            self.shift_frozen(q, y);
            self.woodbury()?;
            if !self.refreeze(q, step) {
                break;
            }
        }
        Ok(self.finish(q, d, y))
    }

    /// Each column's d₀ and whether it starts frozen (pinned, switched
    /// off, or already at a bound) and where.
    #[inline]
    fn start_frozen(&mut self, q: &[f64], d: &[f64]) {
        for k in 0..self.cols.len() {
            let c = self.cols[k];
            self.d0[k] = d[c];
            let pinned = self.lo[k] == self.hi[k];
            // Pinned, switched off, or already at a bound: start frozen there.
            self.frozen[k] = pinned
                || self.off[k]
                || q[c] <= self.lo[k] + BOX_SLACK_M
                || q[c] >= self.hi[k] - BOX_SLACK_M;
            self.at[k] = if self.off[k] {
                q[c]
            } else if q[c] >= self.hi[k] - BOX_SLACK_M {
                self.hi[k]
            } else {
                self.lo[k]
            };
        }
    }

    /// ŷ₀ (from `y`) with the frozen columns' d moved to their bounds.
    #[inline]
    fn shift_frozen(&mut self, q: &[f64], y: &[f64]) {
        let m = self.m;
        self.y0[..m].copy_from_slice(&y[..m]);
        self.dd.fill(0.0);
        for &k in &self.moving {
            if self.frozen[k] {
                let dd = (q[self.cols[k]] - self.at[k]) - self.d0[k];
                self.dd[k] = dd;
                if dd != 0.0 {
                    let z = &self.z[k * m..(k + 1) * m];
                    for (y0, zk) in self.y0.iter_mut().zip(z) {
                        *y0 -= zk * dd;
                    }
                }
            }
        }
    }

    /// Woodbury over the free columns: ŷ₀ corrected by their n_f × n_f
    /// system.
    #[inline]
    fn woodbury(&mut self) -> Result<(), ()> {
        let (n, m) = (self.cols.len(), self.m);
        self.free.clear();
        self.free
            .extend(self.moving.iter().copied().filter(|&k| !self.frozen[k]));
        let nf = self.free.len();
        for (i, &a) in self.free.iter().enumerate() {
            self.rhs[i] = dot(&self.u[a * m..(a + 1) * m], &self.y0);
            for (j, &b) in self.free.iter().enumerate() {
                self.small[i * nf + j] = self.s[a * n + b];
            }
        }
        let solved = match &mut self.masked {
            Some(mr) => mr.solve(
                &self.small[..nf * nf],
                &mut self.rhs[..nf],
                &self.free,
                &self.dd,
                n,
            ),
            None => nf == 0 || cholesky_solve(&mut self.small[..nf * nf], &mut self.rhs[..nf]),
        };
        if !solved {
            return Err(());
        }
        for (i, &a) in self.free.iter().enumerate() {
            let (z, s) = (&self.z[a * m..(a + 1) * m], self.rhs[i]);
            for (y0, zk) in self.y0.iter_mut().zip(z) {
                *y0 -= zk * s;
            }
        }
        Ok(())
    }

    /// t = Uᵀ ŷ, each column's step, and the active set's changes: frees
    /// a frozen column its step pulls inward, freezes a free one its step
    /// takes out of the box. Returns whether anything changed.
    #[inline]
    fn refreeze(&mut self, q: &[f64], step: f64) -> bool {
        let (n, m) = (self.cols.len(), self.m);
        let mut again = false;
        for k in 0..n {
            self.t[k] = dot(&self.u[k * m..(k + 1) * m], &self.y0)
                + self.masked.as_ref().map_or(0.0, |mr| mr.pull(k, n));
            let c = self.cols[k];
            let want = -(self.d0[k] + self.t[k] / self.w[k]);
            let pinned = self.lo[k] == self.hi[k] || self.off[k];
            if self.frozen[k] {
                let inward = (self.at[k] == self.lo[k] && want > 0.0)
                    || (self.at[k] == self.hi[k] && want < 0.0);
                if !pinned
                    && inward
                    && q[c] + step * want <= self.hi[k] + BOX_SLACK_M
                    && q[c] + step * want >= self.lo[k] - BOX_SLACK_M
                {
                    self.frozen[k] = false;
                    again = true;
                }
            } else {
                let next = q[c] + step * want;
                if next < self.lo[k] - BOX_SLACK_M || next > self.hi[k] + BOX_SLACK_M {
                    self.frozen[k] = true;
                    self.at[k] = if next < self.lo[k] {
                        self.lo[k]
                    } else {
                        self.hi[k]
                    };
                    again = true;
                }
            }
        }
        again
    }

    /// The corrected y, d moved to the bounds on frozen columns, and each
    /// column's step in [`Self::mg`]. Returns whether `d` changed.
    #[inline]
    fn finish(&mut self, q: &[f64], d: &mut [f64], y: &mut [f64]) -> bool {
        let m = self.m;
        let mut changed = false;
        y[..m].copy_from_slice(&self.y0[..m]);
        for &k in &self.moving {
            let c = self.cols[k];
            if self.frozen[k] {
                let target = q[c] - self.at[k];
                changed |= d[c] != target;
                d[c] = target;
                self.mg[k] = 0.0;
            } else {
                self.mg[k] = self.t[k] / self.w[k];
            }
        }
        changed
    }
}

#[inline]
fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}
