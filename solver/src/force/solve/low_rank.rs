//! The release branch's second solve from the first factor: a low-rank
//! correction instead of a second factorisation.
//!
//! The first solve factored A_JJ (with the finger rows as the tail, so S =
//! A_FF − A_FJ A_JJ⁻¹ A_JF). Releasing the rows R (k of them) leaves the
//! kept rows N = J \ R; the masked system's solve on N, embedded with
//! zeros on R, is
//!
//! ```text
//! P = A_JJ⁻¹ − U W⁻¹ Uᵀ,   U = A_JJ⁻¹ E_R (n_J × k),   W = U_R = (A_JJ⁻¹)_RR
//! ```
//!
//! (P b is the z with A z = b − E_R μ and z_R = 0.) Since P E_R = 0, the
//! released rows' entries of A_JF and r_J drop out, and with
//! G_R = Uᵀ A_JF (k × m) and H = L_W⁻¹ G_R (W = L_W L_Wᵀ):
//!
//! ```text
//! S' = S + Hᵀ H,   s' = s₀ + Hᵀ L_W⁻¹ Uᵀ r_J',   λ̃_J' = v − U W⁻¹ v_R
//! ```
//!
//! where s₀ and v = A_JJ⁻¹ (r_J' − A_JF λ̃_F') are what one solve through
//! the first factor's tail gives for the right-hand side r' (r_J with R
//! zeroed). Cost: k + 1 triangular solve pairs and O(k n_J m) products,
//! where the masked refactorisation took a numeric factorisation and one
//! pair. Exact in exact arithmetic, not to the bit: the round-off is that
//! of A_JJ's factor amplified by W's condition number, which is bounded
//! here ([`MAX_CONDITION`]); above it, or for more than [`MAX_RANK`]
//! released rows, or when the factor was regularised, the caller
//! refactors as before.

use super::super::small::{factor_in_place, min_norm_solve, substitute};
use super::known::{put_known_in, take_known_out};
use super::{Gram, MultiplierSolve};

/// At most this many released rows take the correction (each costs a
/// triangular solve pair; a factorisation is worth a few).
pub(crate) const MAX_RANK: usize = 8;

/// The largest 1-norm condition number of W = (A_JJ⁻¹)_RR the correction
/// accepts. W⁻¹ is the Schur complement of the kept rows in A_JJ: a large
/// condition means a released row nearly depends on kept ones, and the
/// correction's round-off grows with it (relative error about
/// cond(W) · cond(A_JJ) · ε against cond(A_NN) · ε for a refactorisation).
/// A backstop for several released rows coupled to each other; one row
/// nearly dependent on the kept ones (W is 1 × 1 then, condition 1) is
/// [`MAX_INFLATION`]'s to catch.
pub(crate) const MAX_CONDITION: f64 = 1e6;

/// The largest (A_JJ⁻¹)_ii (A_JJ)_ii of a released row i the correction
/// accepts: 1 for a row orthogonal to the others, 1 / (1 − R²) for a row
/// whose part R² lies in the span of the others' (the variance inflation
/// factor). The correction subtracts U W⁻¹ Uᵀ of about that size from
/// A_JJ⁻¹ and loses its digits; a refactorisation of the kept rows does
/// not. 1e2 costs at most two digits over the refactorisation (measured:
/// Stewart's stroke limits 12.2, `cluttered`'s fourth contact corners up to
/// 2.5e5).
pub(crate) const MAX_INFLATION: f64 = 1e2;

/// Release solves that go straight to the refactorisation after the
/// correction refused one. A refusal is known only after the k solves that
/// form U, so on a model whose releases are mostly refused (`cluttered`,
/// `sit-on-chair`: a box's fourth contact corner is nearly redundant with
/// the other three) every attempt was a factorisation's worth of wasted
/// solves: 1.12× and 1.17× their ticks. After a refusal the next
/// `BACK_OFF` releases refactor at once, which bounds that waste to one
/// attempt in `BACK_OFF + 1`; a model whose releases the correction serves
/// (Stewart's stroke limits) never refuses and never backs off.
pub(crate) const BACK_OFF: u32 = 63;

/// Preallocated buffers of the correction and the first solve's
/// multipliers it keeps aside.
#[derive(Debug, Clone)]
pub(crate) struct LowRank {
    /// U, n_J × k column-major.
    u: Vec<f64>,
    /// W, then its Cholesky factor (k × k, row-major).
    w: Vec<f64>,
    /// H = L_W⁻¹ G_R, k × m row-major.
    h: Vec<f64>,
    /// Scratch of k entries.
    t: Vec<f64>,
    /// The released rows' J indices.
    rows: Vec<usize>,
    lambda_j: Vec<f64>,
    lambda_f: Vec<f64>,
    rank: usize,
    /// Solves done by the correction.
    pub done: u64,
    /// Releases left to refactor without trying ([`BACK_OFF`]).
    pub skip: u32,
    /// Releases the correction tried, refused, and skipped while backing
    /// off (the back-off's test reads them).
    pub tally: LowRankTally,
}

/// What the low-rank release did with the releases that reached it
/// (`Program::force_low_rank_tally`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct LowRankTally {
    /// Releases the correction was tried on.
    pub attempts: u64,
    /// Attempts it refused (each starts a back-off of [`BACK_OFF`]).
    pub refusals: u64,
    /// Releases refactored at once while backing off.
    pub skipped: u64,
}

impl LowRank {
    /// Buffers for `gram`'s sizes. Allocates.
    pub fn new(gram: &Gram) -> Self {
        let (n, m) = (gram.n_j, gram.m_f);
        Self {
            u: vec![0.0; n * MAX_RANK],
            w: vec![0.0; MAX_RANK * MAX_RANK],
            h: vec![0.0; MAX_RANK * m],
            t: vec![0.0; MAX_RANK],
            rows: Vec::with_capacity(MAX_RANK),
            lambda_j: vec![0.0; n],
            lambda_f: vec![0.0; m],
            rank: 0,
            done: 0,
            skip: 0,
            tally: LowRankTally::default(),
        }
    }

    /// Clears the released set.
    pub fn clear(&mut self) {
        self.rows.clear();
    }

    /// Adds J index `j` to the released set; false (set unchanged) when it
    /// is full.
    pub fn release(&mut self, j: usize) -> bool {
        if self.rows.len() == MAX_RANK {
            return false;
        }
        self.rows.push(j);
        true
    }
}

impl MultiplierSolve {
    /// The solve of the last [`solve`](Self::solve)'s A with the rows in
    /// `lr`'s released set switched off (decoupled, zero right-hand side),
    /// from the last factor by the low-rank correction (module docs). `r`,
    /// `known` as for `solve` (`r`'s released rows are read as 0). The
    /// multipliers, rank and factor are left as that solve's, except that
    /// `lambda_j`, `lambda_f` and `rank` hold the masked solve's; the
    /// first solve's go to `lr` ([`restore`](Self::restore_low_rank) puts
    /// them back).
    ///
    /// Returns `Ok(false)`, with nothing changed, when the correction is
    /// refused: no released row or more than [`MAX_RANK`], the factor was
    /// regularised, or W's condition is above [`MAX_CONDITION`].
    ///
    /// # Real-time
    /// No allocation; k + 1 triangular solve pairs, O(k n_J m + k³ + m³).
    pub fn solve_low_rank(
        &mut self,
        gram: &Gram,
        r: &[f64],
        known: &[Option<f64>],
        lr: &mut LowRank,
    ) -> Result<bool, super::FactorError> {
        let k = lr.rows.len();
        if k == 0 || k > MAX_RANK || self.llt.regularized != 0 || self.cg.is_some() {
            return Ok(false);
        }
        if !self.released_columns(gram, lr) {
            return Ok(false);
        }
        lr.lambda_j.copy_from_slice(&self.lambda_j);
        lr.lambda_f.copy_from_slice(&self.lambda_f);
        lr.rank = self.rank;
        self.corrected_schur(gram, lr);
        self.masked_solve(gram, r, known, lr);
        self.unmask_joint_multipliers(gram.n_j, lr);
        if !self.lambda_f.iter().all(|v| v.is_finite()) {
            return Err(super::FactorError);
        }
        lr.done += 1;
        Ok(true)
    }

    /// U = A_JJ⁻¹ E_R into `lr.u` and W's factor into `lr.w`; false when
    /// a released row is nearly dependent on kept ones or W is refused
    /// ([`factor_w`]). Part of [`solve_low_rank`](Self::solve_low_rank).
    fn released_columns(&mut self, gram: &Gram, lr: &mut LowRank) -> bool {
        let (n, k) = (gram.n_j, lr.rows.len());
        // U = A_JJ⁻¹ E_R.
        let u = &mut lr.u[..n * k];
        u.fill(0.0);
        for (i, &j) in lr.rows.iter().enumerate() {
            u[i * n + j] = 1.0;
        }
        self.llt.solve(u, k);
        // A released row nearly dependent on kept ones (a fourth contact
        // corner) has (A⁻¹)_ii A_ii ≫ 1: the correction would cancel that
        // much of A⁻¹'s size, and lose as many digits, where the masked
        // factor never sees the dependence.
        for (i, &j) in lr.rows.iter().enumerate() {
            let inflation = u[i * n + j] * gram.values[gram.diag[j]];
            if inflation.is_nan() || inflation > MAX_INFLATION {
                return false;
            }
        }
        factor_w(u, n, &lr.rows, &mut lr.w[..k * k])
    }

    /// H = L_W⁻¹ Uᵀ A_JF into `lr.h` and the corrected Schur complement
    /// S' = S + Hᵀ H into `schur`. Part of [`solve_low_rank`](Self::solve_low_rank).
    fn corrected_schur(&mut self, gram: &Gram, lr: &mut LowRank) {
        let (n, m, nnz) = (gram.n_j, gram.m_f, gram.nnz());
        let k = lr.rows.len();
        let (u, l_w) = (&lr.u[..n * k], &lr.w[..k * k]);
        // H = L_W⁻¹ Uᵀ A_JF.
        let a_fj = &gram.values[nnz..nnz + m * n];
        let h = &mut lr.h[..k * m];
        for i in 0..k {
            for f in 0..m {
                h[i * m + f] = dot(&u[i * n..(i + 1) * n], &a_fj[f * n..(f + 1) * n]);
            }
        }
        for f in 0..m {
            forward_column(l_w, k, h, m, f);
        }
        // S' = S + Hᵀ H.
        for f in 0..m {
            for g in 0..=f {
                let c: f64 = (0..k).map(|i| h[i * m + f] * h[i * m + g]).sum();
                let v = self.schur_keep[f * m + g] + c;
                self.schur[f * m + g] = v;
                self.schur[g * m + f] = v;
            }
        }
    }

    /// The masked right-hand side r' (released rows 0), t = L_W⁻¹ Uᵀ r_J'
    /// into `lr.t`, and the solve with the corrected Schur complement:
    /// `x` holds v (the joint part before [`unmask_joint_multipliers`](Self::unmask_joint_multipliers)),
    /// `lambda_f` and `rank` the masked solve's. Part of
    /// [`solve_low_rank`](Self::solve_low_rank).
    fn masked_solve(&mut self, gram: &Gram, r: &[f64], known: &[Option<f64>], lr: &mut LowRank) {
        let (n, m, nnz) = (gram.n_j, gram.m_f, gram.nnz());
        let k = lr.rows.len();
        let (u, l_w, h) = (&lr.u[..n * k], &lr.w[..k * k], &lr.h[..k * m]);
        // r' and L_W⁻¹ Uᵀ r_J'.
        self.gather(gram, r);
        for &j in &lr.rows {
            self.x[j] = 0.0;
        }
        let t = &mut lr.t[..k];
        for (i, ti) in t.iter_mut().enumerate() {
            *ti = dot(&u[i * n..(i + 1) * n], &self.x[..n]);
        }
        forward_column(l_w, k, t, 1, 0);
        let a_ff = &gram.values[nnz + m * n..];
        let reference = (0..m).map(|f| a_ff[f * m + f]).fold(0.0, f64::max);
        let Self {
            llt,
            x,
            schur,
            lambda_f,
            eig,
            ..
        } = self;
        let t = &lr.t[..k];
        let rank = llt.solve_with_tail(x, |_, s| {
            for (f, sf) in s.iter_mut().enumerate() {
                *sf += (0..k).map(|i| h[i * m + f] * t[i]).sum::<f64>();
            }
            let n_known = take_known_out(schur, s, known, reference);
            let rank = min_norm_solve(schur, s, lambda_f, eig, reference).saturating_sub(n_known);
            put_known_in(lambda_f, known);
            s.copy_from_slice(lambda_f);
            rank
        });
        self.rank = rank;
    }

    /// λ̃_J' = v − U W⁻¹ v_R, exactly 0 on R, into `lambda_j` (v in `x`).
    /// Part of [`solve_low_rank`](Self::solve_low_rank).
    fn unmask_joint_multipliers(&mut self, n: usize, lr: &mut LowRank) {
        let k = lr.rows.len();
        let (u, l_w) = (&lr.u[..n * k], &lr.w[..k * k]);
        let t = &mut lr.t[..k];
        for (ti, &j) in t.iter_mut().zip(&lr.rows) {
            *ti = self.x[j];
        }
        substitute(l_w, t);
        for j in 0..n {
            let mut v = self.x[j];
            for (i, ti) in t.iter().enumerate() {
                v -= u[i * n + j] * ti;
            }
            self.lambda_j[j] = v;
        }
        for &j in &lr.rows {
            self.lambda_j[j] = 0.0;
        }
    }

    /// Puts back the multipliers and rank [`solve_low_rank`](Self::solve_low_rank)
    /// kept aside: the first solve again (its factor never left).
    pub fn restore_low_rank(&mut self, lr: &LowRank) {
        self.lambda_j.copy_from_slice(&lr.lambda_j);
        self.lambda_f.copy_from_slice(&lr.lambda_f);
        self.rank = lr.rank;
    }
}

/// W = U_R (symmetrised) into `w` and its Cholesky factor in place; false
/// when W is not positive definite or its 1-norm condition exceeds
/// [`MAX_CONDITION`].
fn factor_w(u: &[f64], n: usize, rows: &[usize], w: &mut [f64]) -> bool {
    let k = rows.len();
    for (a, &ra) in rows.iter().enumerate() {
        for (b, &rb) in rows.iter().enumerate() {
            w[a * k + b] = 0.5 * (u[b * n + ra] + u[a * n + rb]);
        }
    }
    let norm = (0..k)
        .map(|c| (0..k).map(|r| w[r * k + c].abs()).sum::<f64>())
        .fold(0.0, f64::max);
    if !factor_in_place(w, k) {
        return false;
    }
    // ‖W⁻¹‖₁ column by column (k ≤ MAX_RANK: a stack buffer).
    let mut inv_norm = 0.0f64;
    let mut e = [0.0; MAX_RANK];
    for c in 0..k {
        let e = &mut e[..k];
        e.fill(0.0);
        e[c] = 1.0;
        substitute(w, e);
        inv_norm = inv_norm.max(e.iter().map(|t| t.abs()).sum());
    }
    let cond = norm * inv_norm;
    cond.is_finite() && cond <= MAX_CONDITION
}

/// Column `c` of the k × `stride` row-major `b` ← L⁻¹ (column `c`), L the
/// lower factor of [`factor_in_place`] (k × k).
fn forward_column(l: &[f64], k: usize, b: &mut [f64], stride: usize, c: usize) {
    for i in 0..k {
        let mut v = b[i * stride + c];
        for p in 0..i {
            v -= l[i * k + p] * b[p * stride + c];
        }
        b[i * stride + c] = v / l[i * k + i];
    }
}

#[inline]
fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}
