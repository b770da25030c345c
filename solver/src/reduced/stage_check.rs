//! The branch-sparse force stage (`branch`, `stage`) against the dense
//! reference it replaced, checked inside every factor and solve of a run
//! while [`Checking`] is alive on the thread (tests only):
//!
//! - L against a dense Lᵀ L factor of the same H (every entry of the lower
//!   triangle, no ancestor structure used: the absent fill is checked too);
//! - W, g = Y L⁻ᵀ τ (τ fixed) and every step's H⁻¹ u against the same
//!   factor used densely (dense solves, dense dots);
//! - the same three against the dense path before this change: H = L Lᵀ
//!   (`factor_in_place`), Y = L⁻¹ (D J_r S)ᵀ, W = YᵀY, `substitute`.
//!   The two factorisations round differently: their gap grows with H's
//!   condition (the 64-link chain's, BENCHMARKS.md).
//!
//! Each is the largest |difference| over the largest |entry| of the
//! reference.

use std::cell::{Cell, RefCell};

use super::small::{backward, dot, forward};
use super::stage::Stage;
use crate::force::small::{factor_in_place, substitute};

thread_local! {
    static ON: Cell<bool> = const { Cell::new(false) };
    /// Worst relative gaps (`Checking::worst`) and the counts of factors
    /// and solves checked.
    static WORST: Cell<([f64; 8], [usize; 2])> = const { Cell::new(([0.0; 8], [0; 2])) };
    /// The dense Lᵀ L and L Lᵀ factors of the last H.
    static DENSE: RefCell<(Vec<f64>, Vec<f64>)> = const { RefCell::new((Vec::new(), Vec::new())) };
}

/// Checks on while alive (tests).
pub(crate) struct Checking;

impl Checking {
    pub fn start() -> Self {
        ON.with(|c| c.set(true));
        WORST.with(|w| w.set(([0.0; 8], [0; 2])));
        Self
    }

    /// Worst relative gaps [L, W, g, H⁻¹ u against dense Lᵀ L; W, g, H⁻¹ u
    /// against the dense L Lᵀ path], then H's condition at the first
    /// factor; and [factors, solves] checked.
    pub fn worst(&self) -> ([f64; 8], [usize; 2]) {
        WORST.with(Cell::get)
    }
}

impl Drop for Checking {
    fn drop(&mut self) {
        ON.with(|c| c.set(false));
    }
}

pub(super) fn enabled() -> bool {
    ON.with(Cell::get)
}

fn gap(a: &[f64], reference: &[f64]) -> f64 {
    let big = reference.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let d = a
        .iter()
        .zip(reference)
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
    if big > 0.0 { d / big } else { d }
}

fn record(k: usize, g: f64, count: usize) {
    WORST.with(|w| {
        let (mut v, mut c) = w.get();
        v[k] = v[k].max(g);
        if k == 0 || k == 3 {
            c[count] += 1;
        }
        w.set((v, c));
    });
}

/// H = Lᵀ L densely, from the last row up (the lower triangle of `a`).
fn dense_ltl(a: &mut [f64], n: usize) {
    for k in (0..n).rev() {
        let d = a[k * n + k].sqrt();
        a[k * n + k] = d;
        for i in 0..k {
            a[k * n + i] /= d;
        }
        for i in 0..k {
            for j in 0..=i {
                a[i * n + j] -= a[k * n + i] * a[k * n + j];
            }
        }
    }
}

fn lower(a: &[f64], n: usize) -> Vec<f64> {
    (0..n)
        .flat_map(|i| (0..=i).map(move |j| a[i * n + j]))
        .collect()
}

/// Y rows, W = YᵀY and g = Y t (t = L⁻¹ τ or L⁻ᵀ τ by `solve`) densely.
fn dense_w_g(
    y: &mut [f64],
    n: usize,
    m: usize,
    solve: impl Fn(&mut [f64]),
) -> (Vec<f64>, Vec<f64>) {
    for i in 0..m {
        solve(&mut y[i * n..(i + 1) * n]);
    }
    let mut w = vec![0.0; m * m];
    for a in 0..m {
        for b in 0..m {
            w[a * m + b] = dot(&y[a * n..(a + 1) * n], &y[b * n..(b + 1) * n]);
        }
    }
    let mut t = tau(n);
    solve(&mut t);
    let g = (0..m).map(|i| dot(&y[i * n..(i + 1) * n], &t)).collect();
    (w, g)
}

fn tau(n: usize) -> Vec<f64> {
    (0..n).map(|i| (1.3 * i as f64 + 0.4).sin()).collect()
}

/// After `Stage::factor` (`h0`: H before it, m rows of `jr`).
pub(super) fn factor(h0: &[f64], jr: &[f64], st: &Stage, m: usize) {
    let n = st.paths.len();
    let mut ltl = h0.to_vec();
    dense_ltl(&mut ltl, n);
    record(0, gap(&lower(&st.h, n), &lower(&ltl, n)), 0);
    if WORST.with(Cell::get).1[0] == 1 {
        let e = nalgebra::DMatrix::from_row_slice(n, n, h0).symmetric_eigenvalues();
        record(7, e.max() / e.min(), 0);
    }
    let mut llt = h0.to_vec();
    assert!(factor_in_place(&mut llt, n), "dense H not positive");
    let mut t = tau(n);
    super::branch::solve_lt(&st.h, &st.paths, &mut t);
    let g: Vec<f64> = (0..m)
        .map(|i| dot(&st.yt[i * n..(i + 1) * n], &t))
        .collect();
    let w = &st.w[..m * m];
    let (w1, g1) = dense_w_g(&mut jr[..m * n].to_vec(), n, m, |x| backward(&ltl, x));
    let (w2, g2) = dense_w_g(&mut jr[..m * n].to_vec(), n, m, |x| forward(&llt, x));
    record(1, gap(w, &w1), 0);
    record(2, gap(&g, &g1), 0);
    record(4, gap(w, &w2), 0);
    record(5, gap(&g, &g2), 0);
    DENSE.with(|d| *d.borrow_mut() = (ltl, llt));
}

/// After `Stage::solve_h` (`x0` before it, `x` after).
pub(super) fn solve(x0: Vec<f64>, x: &[f64]) {
    let (mut a, mut b) = (x0.clone(), x0);
    DENSE.with(|d| {
        let d = d.borrow();
        backward(&d.0, &mut a);
        forward(&d.0, &mut a);
        substitute(&d.1, &mut b);
    });
    record(3, gap(x, &a), 1);
    record(6, gap(x, &b), 1);
}
