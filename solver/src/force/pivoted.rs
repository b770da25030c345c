//! The minimum-norm solve of a rank-deficient finger Schur complement by a
//! rank-revealing (diagonally pivoted) Cholesky factor, certified to take
//! the eigensolve's rank decision.
//!
//! Against a stroke limit the rigid grasp of a 6-DOF platform has a 6 × 6
//! S of rank 3 (Stewart's stop phase): neither the rank-one closed form
//! nor the full-rank Cholesky applies, and the Jacobi eigensolve ran on
//! every force solve. Here, with P the pivoting and E the Schur remainder
//! after r steps, S = P (L Lᵀ + E) Pᵀ with L n × r of full column rank;
//! S⁺ b is taken as P L (LᵀL)⁻² Lᵀ Pᵀ b, the pseudo-inverse of L Lᵀ.
//!
//! The eigensolve keeps the eigenvalues above τ = [`RANK_TOLERANCE`] ·
//! max(λ_max, reference). The path is taken only where both sides of that
//! decision are proved with [`MARGIN`] to spare (Weyl: S's eigenvalues are
//! those of L Lᵀ, r of them ≥ λ_min(LᵀL) and n − r zero, moved by at most
//! ‖E‖₂ ≤ ‖E‖₁):
//! - dropped: ‖E‖₁ · `MARGIN` ≤ [`RANK_TOLERANCE`] · max(max S_ii, reference),
//!   a lower bound of τ (λ_max ≥ max S_ii);
//! - kept: 1/‖(LᵀL)⁻¹‖₁ − ‖E‖₁ ≥ `MARGIN` · [`RANK_TOLERANCE`] ·
//!   max(‖S‖₁, reference), an upper bound of τ (λ_max ≤ ‖S‖₁).
//!
//! Then the eigensolve's rank is r, and its solution and this one differ
//! by the dropped part E: about ‖E‖/λ_r relative (1e-14 · cond on the
//! built-in mechanisms). Anything else goes to the eigensolve. Not bit for
//! bit with it; `tests_pivoted` compares the two.
//!
//! Only r < n is taken (a block of full rank is the full-rank shortcut's,
//! which runs first), so an accepted block has an eigenvalue within ‖E‖₂
//! of zero: λ_min(S) ≤ ‖E‖₁ ≤ τ_low / `MARGIN`, τ_low = [`RANK_TOLERANCE`]
//! · max(max S_ii, reference). The full-rank shortcut's refusal leaves
//! ‖S⁻¹‖₁ from its factor, and λ_min(S) ≥ 1/‖S⁻¹‖₁; where that bound is
//! above τ_low no eigenvalue can be dropped and the block is refused before
//! any work (the precheck: exact up to the two factors' round-off, about
//! 1e-14 of S against the `MARGIN` = 1e3 between the two bounds). The
//! rigid grasps of `sit-on-chair` and the cluttered table (6 × 6, full
//! rank, smallest eigenvalue 1e-6 of the largest: between the shortcut's
//! bound and the threshold, where only the eigensolve decides) are refused
//! there, at the cost of a scan of the diagonal (before it, a 4- to 6-step
//! factor each, a third of sit-on-chair's with the whole certificate).

use super::small::{RANK_TOLERANCE, factor_in_place, substitute};
use std::cell::Cell;
use std::cmp::Ordering;

/// The largest block taken (finger blocks are 3 × 3 or 6 × 6).
const MAX: usize = 6;

/// The decades kept between each bound and the rank threshold (as the
/// full-rank shortcut's).
const MARGIN: f64 = 1e3;

/// A pivot below this × the first sends the block to the eigensolve before
/// the factor is finished: a kept part conditioned beyond about 1e5 would
/// likely fail the kept bound only after the whole factor and its r solves,
/// and its solution would differ from the eigensolve's by the rest over
/// λ_r² anyway. (`sit-on-chair`'s full-rank grasps, which this and the kept
/// bound used to catch at the 5th pivot, now stop at the precheck.)
const PIVOT_RATIO: f64 = 1e-5;

thread_local! {
    /// Set by [`eigensolve_only`] for the comparisons the tests make.
    static EIGENSOLVE_ONLY: Cell<bool> = const { Cell::new(false) };
    /// This thread's counts ([`pivoted_tally`]).
    static TALLY: Cell<PivotedTally> = const { Cell::new(PivotedTally::ZERO) };
}

/// What the pivoted shortcut did on this thread, from its start: every
/// block it was offered (of at most 6 × 6, the shortcut on) ends in exactly
/// one of `prechecked`, `refused` and `served`.
#[doc(hidden)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PivotedTally {
    /// Refused by the precheck (module docs), before any factor work.
    pub prechecked: u64,
    /// Factored (at least in part), then refused.
    pub refused: u64,
    /// Solved here: the eigensolve skipped.
    pub served: u64,
}

impl PivotedTally {
    const ZERO: Self = Self {
        prechecked: 0,
        refused: 0,
        served: 0,
    };
}

/// This thread's [`PivotedTally`]: what the tests read to prove which way
/// the blocks went.
#[doc(hidden)]
pub fn pivoted_tally() -> PivotedTally {
    TALLY.with(Cell::get)
}

/// Finger solves this thread's pivoted shortcut has served
/// ([`PivotedTally::served`]).
#[doc(hidden)]
pub fn pivoted_solves() -> u64 {
    pivoted_tally().served
}

/// Adds one to the count `field` picks.
fn count(field: fn(&mut PivotedTally) -> &mut u64) {
    TALLY.with(|c| {
        let mut t = c.get();
        *field(&mut t) += 1;
        c.set(t);
    });
}

/// Runs `f` with [`min_norm_solve`](super::small::min_norm_solve)'s pivoted shortcut off on this thread
/// (every rank-deficient block, other than rank one, by the eigensolve as
/// before it): the reference the pivoted path's tests compare with. Not
/// for the fast loop's own use.
#[doc(hidden)]
pub fn eigensolve_only<R>(f: impl FnOnce() -> R) -> R {
    struct Reset(bool);
    impl Drop for Reset {
        fn drop(&mut self) {
            EIGENSOLVE_ONLY.with(|c| c.set(self.0));
        }
    }
    let _reset = Reset(EIGENSOLVE_ONLY.with(|c| c.replace(true)));
    f()
}

/// x = S⁺ b for the symmetric positive semi-definite n × n `a` (row-major,
/// left intact) when the pivoted factor proves the eigensolve's rank
/// (module docs) and that rank is below n: `Some(rank)`; `None` (x
/// unspecified) sends the caller to the eigensolve. `inv_norm`: ‖a⁻¹‖₁ as
/// the full-rank shortcut computed it when it refused (∞ where its factor
/// failed), for the precheck. `l` (n × n) is scratch.
///
/// # Real-time
/// No allocation; n + 1 comparisons where the precheck refuses, else
/// n² r + O(r³) multiply-adds.
pub(crate) fn pivoted_solve(
    a: &[f64],
    b: &[f64],
    x: &mut [f64],
    l: &mut [f64],
    reference: f64,
    inv_norm: f64,
) -> Option<usize> {
    let n = b.len();
    if n == 0 || n > MAX || EIGENSOLVE_ONLY.with(Cell::get) {
        return None;
    }
    let max_diag = (0..n).map(|i| a[i * n + i]).fold(0.0, f64::max);
    let low = RANK_TOLERANCE * max_diag.max(reference);
    // λ_min ≥ 1/‖a⁻¹‖₁ > low: three decades above any eigenvalue an
    // accepted factor drops (NaN: no bound, go on).
    if inv_norm * low < 1.0 {
        count(|t| &mut t.prechecked);
        return None;
    }
    let solved = factor_and_solve(a, b, x, l, reference, low);
    if solved.is_some() {
        count(|t| &mut t.served);
    } else {
        count(|t| &mut t.refused);
    }
    solved
}

/// [`pivoted_solve`] past its precheck: the factor, the certificate, the
/// solve. `low`: τ_low of the module docs.
fn factor_and_solve(
    a: &[f64],
    b: &[f64],
    x: &mut [f64],
    l: &mut [f64],
    reference: f64,
    low: f64,
) -> Option<usize> {
    let n = b.len();
    let l = &mut l[..n * n];
    l.copy_from_slice(&a[..n * n]);
    let norm = (0..n)
        .map(|c| (0..n).map(|r| a[r * n + c].abs()).sum::<f64>())
        .fold(0.0, f64::max);
    let high = MARGIN * RANK_TOLERANCE * norm.max(reference);
    let mut perm = [0usize; MAX];
    for (i, p) in perm.iter_mut().enumerate() {
        *p = i;
    }
    let r = factor_pivoted(l, n, &mut perm, low / (MARGIN * n as f64), high)?;
    let rest = remainder_norm(l, n, r);
    if !matches!(
        (rest * MARGIN).partial_cmp(&low),
        Some(Ordering::Less | Ordering::Equal)
    ) {
        return None;
    }
    x.fill(0.0);
    if r == 0 {
        return Some(0);
    }
    let mut g = [0.0; MAX * MAX];
    let g = &mut g[..r * r];
    for k in 0..r {
        for m in 0..=k {
            let v: f64 = (k..n).map(|i| l[i * n + k] * l[i * n + m]).sum();
            g[k * r + m] = v;
            g[m * r + k] = v;
        }
    }
    if !factor_in_place(g, r) {
        return None;
    }
    // ‖(LᵀL)⁻¹‖₁: the largest column sum of |G⁻¹ e_c|.
    let mut e = [0.0; MAX];
    let e = &mut e[..r];
    let mut inv_norm = 0.0f64;
    for c in 0..r {
        e.fill(0.0);
        e[c] = 1.0;
        substitute(g, e);
        inv_norm = inv_norm.max(e.iter().map(|t| t.abs()).sum());
    }
    if !(inv_norm.is_finite() && inv_norm * (high + rest) < 1.0) {
        return None;
    }
    // z = (LᵀL)⁻² Lᵀ Pᵀ b, then x = P L z.
    for (k, z) in e.iter_mut().enumerate() {
        *z = (k..n).map(|i| l[i * n + k] * b[perm[i]]).sum();
    }
    substitute(g, e);
    substitute(g, e);
    for i in 0..n {
        x[perm[i]] = (0..=i.min(r - 1)).map(|k| l[i * n + k] * e[k]).sum();
    }
    x.iter().all(|t| t.is_finite()).then_some(r)
}

/// Outer-product Cholesky of the symmetric n × n `l` (row-major, both
/// triangles) with the largest remaining diagonal as pivot, stopping when
/// it is at most `stop` (or not a number): returns r < n. L's r columns end in
/// `l`'s lower triangle (rows in pivot order, `perm[i]` the original index
/// of row i), the remainder in its trailing (n − r) × (n − r) block.
///
/// `None` as soon as a pivot d above `stop` has n d ≤ `kept`: the column it
/// starts has ‖L e_r‖² ≤ n d (complete pivoting bounds each entry's square
/// by d), so λ_min(LᵀL) ≤ n d and the kept bound cannot be proved (an
/// eigenvalue between the two bounds: the eigensolve decides, and the
/// factor's rest is not worth finishing); also when d is below
/// [`PIVOT_RATIO`] × the first pivot, and at the n-th pivot above `stop`
/// (full rank: not taken here).
fn factor_pivoted(
    l: &mut [f64],
    n: usize,
    perm: &mut [usize],
    stop: f64,
    kept: f64,
) -> Option<usize> {
    let mut first = 0.0;
    for r in 0..n {
        let mut p = r;
        for i in r + 1..n {
            if l[i * n + i] > l[p * n + p] {
                p = i;
            }
        }
        let d = l[p * n + p];
        if d.partial_cmp(&stop) != Some(Ordering::Greater) {
            return Some(r);
        }
        if n as f64 * d <= kept || d < PIVOT_RATIO * first || r + 1 == n {
            return None;
        }
        if r == 0 {
            first = d;
        }
        if p != r {
            for k in 0..n {
                l.swap(r * n + k, p * n + k);
            }
            for k in 0..n {
                l.swap(k * n + r, k * n + p);
            }
            perm.swap(r, p);
        }
        let s = d.sqrt();
        l[r * n + r] = s;
        for i in r + 1..n {
            l[i * n + r] /= s;
        }
        for i in r + 1..n {
            for j in r + 1..=i {
                let v = l[i * n + j] - l[i * n + r] * l[j * n + r];
                l[i * n + j] = v;
                l[j * n + i] = v;
            }
        }
    }
    None
}

/// ‖E‖₁ of the trailing (n − r) × (n − r) remainder of [`factor_pivoted`]
/// (NaN if any entry is).
fn remainder_norm(l: &[f64], n: usize, r: usize) -> f64 {
    let mut worst = 0.0f64;
    for c in r..n {
        let s: f64 = (r..n).map(|i| l[i * n + c].abs()).sum();
        if s.is_nan() {
            return f64::NAN;
        }
        worst = worst.max(s);
    }
    worst
}
