//! Minimum-norm solution of a small symmetric positive semi-definite system
//! (the finger Schur complement, m_f × m_f with m_f = 3 or 6 per finger) by
//! cyclic Jacobi eigendecomposition in caller-owned buffers.
//!
//! A 1-DOF mechanism held by a point finger has a rank-1 Schur complement
//! (only the component of the finger force along the mechanism's motion is
//! determined), so a plain Cholesky would fail; the pseudo-inverse gives the
//! smallest finger force that does the job.

/// Eigenvalues below this × the largest are treated as zero. The Schur
/// complement's structurally zero eigenvalues come out at 1e-14 relative on
/// the built-in mechanisms (round-off of the sparse solve); genuinely
/// non-zero ones are O(1).
pub(crate) const RANK_TOLERANCE: f64 = 1e-9;

/// Sweeps after which Jacobi stops even if not converged (it converges
/// quadratically; 3 × 3 and 6 × 6 systems need 4–6 sweeps).
const MAX_SWEEPS: usize = 30;

/// x = A⁺ b for the symmetric n × n matrix `a` (row-major; destroyed: its
/// diagonal ends up holding the eigenvalues). `v` (n × n) is scratch.
/// Eigenvalues at most [`RANK_TOLERANCE`] × max(largest eigenvalue,
/// `reference`) count as zero: `reference` is the scale of the matrix the
/// Schur complement was reduced from (A_FF), so a complement that cancels to
/// round-off everywhere (a finger on a mechanism with no free motion left,
/// e.g. held against a stop) has rank 0, not a round-off rank 1 whose
/// inverse is noise. Returns the numerical rank.
///
/// # Real-time
/// No allocation; at most 30 sweeps of n²/2 rotations, O(n³) each.
pub(crate) fn min_norm_solve(
    a: &mut [f64],
    b: &[f64],
    x: &mut [f64],
    v: &mut [f64],
    reference: f64,
) -> usize {
    let n = b.len();
    // A 1-DOF mechanism's point finger: rank one, in closed form.
    if super::rank_one::rank_one_solve(a, b, x, reference) {
        return 1;
    }
    // Refused, it leaves ‖A⁻¹‖₁ as its factor computed it (∞ without one).
    let inv_norm = match full_rank_solve(a, b, x, v, reference) {
        Ok(()) => return n,
        Err(inv_norm) => inv_norm,
    };
    // A rank-deficient block whose rank a pivoted factor proves (Stewart
    // against a stroke limit: 6 × 6 of rank 3); that ‖A⁻¹‖₁ rules it out
    // before any work where no eigenvalue can be dropped (sit-on-chair's
    // and the cluttered table's grasps: full rank, ill-conditioned).
    if let Some(rank) = super::pivoted::pivoted_solve(a, b, x, v, reference, inv_norm) {
        return rank;
    }
    v.fill(0.0);
    for i in 0..n {
        v[i * n + i] = 1.0;
    }
    let scale: f64 = a.iter().map(|t| t * t).sum::<f64>().sqrt();
    // The finger blocks are 3 × 3 (a point) or 6 × 6 (a rigid grasp, or two
    // points): with the size known the sweeps unroll and lose their bounds
    // checks (the 6 × 6 eigensolve was a sixth of the Stewart tick).
    match n {
        3 => sweeps::<3>(a, v, scale),
        6 => sweeps::<6>(a, v, scale),
        _ => sweeps_any(a, v, n, scale),
    }
    let top = (0..n)
        .map(|i| a[i * n + i])
        .fold(0.0, f64::max)
        .max(reference);
    x.fill(0.0);
    let mut rank = 0;
    for k in 0..n {
        let d = a[k * n + k];
        // NaN-safe: a NaN eigenvalue fails `d > …` and is skipped too.
        if d.partial_cmp(&(RANK_TOLERANCE * top)) != Some(std::cmp::Ordering::Greater) {
            continue;
        }
        rank += 1;
        let proj: f64 = (0..n).map(|i| v[i * n + k] * b[i]).sum::<f64>() / d;
        for i in 0..n {
            x[i] += v[i * n + k] * proj;
        }
    }
    rank
}

/// Cyclic Jacobi eigendecomposition of the symmetric n × n `a` (row-major,
/// its first n² values): `a` ends diagonal (the eigenvalues), `v`'s columns
/// the eigenvectors. The sweeps of [`min_norm_solve`], to 1e-15 of `a`'s
/// Frobenius norm. No allocation.
pub(crate) fn symmetric_eigen(a: &mut [f64], v: &mut [f64], n: usize) {
    let v = &mut v[..n * n];
    v.fill(0.0);
    for i in 0..n {
        v[i * n + i] = 1.0;
    }
    let scale = a[..n * n].iter().map(|x| x * x).sum::<f64>().sqrt();
    sweeps_any(a, v, n, scale);
}

/// The Jacobi sweeps of [`min_norm_solve`] on the n × n `a` (row-major),
/// accumulating the rotations into `v`, until the off-diagonal norm is
/// 1e-15 × `scale` or [`MAX_SWEEPS`].
fn sweeps_any(a: &mut [f64], v: &mut [f64], n: usize, scale: f64) {
    for _ in 0..MAX_SWEEPS {
        let off: f64 = (0..n)
            .flat_map(|i| (0..n).filter(move |&j| j != i).map(move |j| (i, j)))
            .map(|(i, j)| a[i * n + j] * a[i * n + j])
            .sum::<f64>()
            .sqrt();
        if off <= 1e-15 * scale || !off.is_finite() {
            break;
        }
        for p in 0..n {
            for q in p + 1..n {
                let apq = a[p * n + q];
                if apq.abs() <= 1e-300 {
                    continue;
                }
                let theta = (a[q * n + q] - a[p * n + p]) / (2.0 * apq);
                let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
                let c = 1.0 / (t * t + 1.0).sqrt();
                let s = t * c;
                rotate(a, n, p, q, c, s);
                for k in 0..n {
                    let (vp, vq) = (v[k * n + p], v[k * n + q]);
                    v[k * n + p] = c * vp - s * vq;
                    v[k * n + q] = s * vp + c * vq;
                }
            }
        }
    }
}

/// [`sweeps_any`] for n = `N` known at compile time: the same rotations in
/// the same order, so the same result to the last bit.
fn sweeps<const N: usize>(a: &mut [f64], v: &mut [f64], scale: f64) {
    let a = &mut a.as_chunks_mut::<N>().0[..N];
    let v = &mut v.as_chunks_mut::<N>().0[..N];
    for _ in 0..MAX_SWEEPS {
        let mut off = 0.0;
        for (i, row) in a.iter().enumerate() {
            for (j, &x) in row.iter().enumerate() {
                if j != i {
                    off += x * x;
                }
            }
        }
        let off: f64 = f64::sqrt(off);
        if off <= 1e-15 * scale || !off.is_finite() {
            break;
        }
        for p in 0..N {
            for q in p + 1..N {
                let apq = a[p][q];
                if apq.abs() <= 1e-300 {
                    continue;
                }
                let theta = (a[q][q] - a[p][p]) / (2.0 * apq);
                let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
                let c = 1.0 / (t * t + 1.0).sqrt();
                let s = t * c;
                for row in a.iter_mut() {
                    let (akp, akq) = (row[p], row[q]);
                    row[p] = c * akp - s * akq;
                    row[q] = s * akp + c * akq;
                }
                let (head, tail) = a.split_at_mut(q);
                let (rp, rq) = (&mut head[p], &mut tail[0]);
                for k in 0..N {
                    let (apk, aqk) = (rp[k], rq[k]);
                    rp[k] = c * apk - s * aqk;
                    rq[k] = s * apk + c * aqk;
                }
                for row in v.iter_mut() {
                    let (vp, vq) = (row[p], row[q]);
                    row[p] = c * vp - s * vq;
                    row[q] = s * vp + c * vq;
                }
            }
        }
    }
}

/// The common case of [`min_norm_solve`] without the eigensolve: when a
/// Cholesky factor of `a` (into `v`) proves every eigenvalue far above the
/// rank threshold, A⁺ = A⁻¹ and x = A⁻¹ b. The proof: λ_min ≥ 1/‖A⁻¹‖₁ and
/// λ_max ≤ ‖A‖₁ (symmetric A), so 1/‖A⁻¹‖₁ > 1000 · [`RANK_TOLERANCE`] ·
/// max(‖A‖₁, `reference`) leaves no eigenvalue the eigensolve would drop,
/// with three decades to spare. `a` is left intact; `Err` (x unspecified)
/// sends the caller to the eigensolve (a rank-deficient or nearly singular
/// A: a 1-DOF mechanism's finger) with ‖A⁻¹‖₁ as computed from the factor,
/// or ∞ where the factor failed (a pivot not positive: no bound). A rigid grasp of a 6-DOF platform takes
/// this path: one 6 × 6 Cholesky and 7 triangular solve pairs instead of up
/// to 30 Jacobi sweeps.
///
/// # Real-time
/// No allocation; O(n³).
pub(super) fn full_rank_solve(
    a: &[f64],
    b: &[f64],
    x: &mut [f64],
    v: &mut [f64],
    reference: f64,
) -> Result<(), f64> {
    let n = b.len();
    // The finger blocks' sizes, known at compile time: the same operations
    // in the same order without bounds checks (`fixed_size`).
    match n {
        0 => return Err(f64::INFINITY),
        3 => return super::small_fixed::full_rank_solve::<3>(a, b, x, v, reference),
        6 => return super::small_fixed::full_rank_solve::<6>(a, b, x, v, reference),
        _ => {}
    }
    full_rank_solve_generic(a, b, x, v, reference)
}

/// [`full_rank_solve`] for any n ≥ 1, with n known at run time.
pub(super) fn full_rank_solve_generic(
    a: &[f64],
    b: &[f64],
    x: &mut [f64],
    v: &mut [f64],
    reference: f64,
) -> Result<(), f64> {
    let n = b.len();
    v[..n * n].copy_from_slice(&a[..n * n]);
    let norm = (0..n)
        .map(|c| (0..n).map(|r| a[r * n + c].abs()).sum::<f64>())
        .fold(0.0, f64::max);
    if !factor_in_place(v, n) {
        return Err(f64::INFINITY);
    }
    // ‖A⁻¹‖₁: the largest column sum of |A⁻¹ e_c|.
    let mut inv_norm = 0.0f64;
    for c in 0..n {
        x.fill(0.0);
        x[c] = 1.0;
        substitute(v, x);
        inv_norm = inv_norm.max(x.iter().map(|t| t.abs()).sum());
    }
    if !(inv_norm.is_finite() && inv_norm * 1e3 * RANK_TOLERANCE * norm.max(reference) < 1.0) {
        return Err(inv_norm);
    }
    x.copy_from_slice(b);
    substitute(v, x);
    x.iter()
        .all(|t| t.is_finite())
        .then_some(())
        .ok_or(inv_norm)
}

/// Lower Cholesky factor of the n × n row-major `a` in place (lower
/// triangle); false if a pivot is not positive.
pub(crate) fn factor_in_place(a: &mut [f64], n: usize) -> bool {
    for j in 0..n {
        let mut d = a[j * n + j];
        for k in 0..j {
            d -= a[j * n + k] * a[j * n + k];
        }
        if d.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
            return false;
        }
        let d = d.sqrt();
        a[j * n + j] = d;
        for i in j + 1..n {
            let mut v = a[i * n + j];
            for k in 0..j {
                v -= a[i * n + k] * a[j * n + k];
            }
            a[i * n + j] = v / d;
        }
    }
    true
}

/// b ← (L Lᵀ)⁻¹ b with the factor of [`factor_in_place`].
pub(crate) fn substitute(l: &[f64], b: &mut [f64]) {
    let n = b.len();
    for i in 0..n {
        let mut v = b[i];
        for k in 0..i {
            v -= l[i * n + k] * b[k];
        }
        b[i] = v / l[i * n + i];
    }
    for i in (0..n).rev() {
        let mut v = b[i];
        for k in i + 1..n {
            v -= l[k * n + i] * b[k];
        }
        b[i] = v / l[i * n + i];
    }
}

/// Solves A x = b in place (`b` becomes x) for the symmetric positive
/// definite n × n matrix `a` (row-major, destroyed: its lower triangle becomes
/// L). Returns false, leaving `b` unspecified, if a pivot is not positive.
///
/// # Real-time
/// No allocation; n³/6 multiply-adds.
pub(crate) fn cholesky_solve(a: &mut [f64], b: &mut [f64]) -> bool {
    let n = b.len();
    if !factor_in_place(a, n) {
        return false;
    }
    substitute(a, b);
    true
}

/// A ← Jᵀ A J for the Jacobi rotation J in the (p, q) plane.
fn rotate(a: &mut [f64], n: usize, p: usize, q: usize, c: f64, s: f64) {
    for k in 0..n {
        let (akp, akq) = (a[k * n + p], a[k * n + q]);
        a[k * n + p] = c * akp - s * akq;
        a[k * n + q] = s * akp + c * akq;
    }
    for k in 0..n {
        let (apk, aqk) = (a[p * n + k], a[q * n + k]);
        a[p * n + k] = c * apk - s * aqk;
        a[q * n + k] = s * apk + c * aqk;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn full_rank_system_is_solved_exactly() {
        let a0 = [4.0, 1.0, 0.5, 1.0, 3.0, -0.2, 0.5, -0.2, 2.0];
        let b = [1.0, -2.0, 0.5];
        let (mut a, mut x, mut v) = (a0, [0.0; 3], [0.0; 9]);
        assert_eq!(min_norm_solve(&mut a, &b, &mut x, &mut v, 0.0), 3);
        for i in 0..3 {
            let r: f64 = (0..3).map(|j| a0[i * 3 + j] * x[j]).sum::<f64>() - b[i];
            assert!(r.abs() < 1e-14, "row {i}: {r}");
        }
    }

    #[test]
    fn cholesky_solves_an_spd_system_and_refuses_an_indefinite_one() {
        let a0 = [4.0, 1.0, 0.5, 1.0, 3.0, -0.2, 0.5, -0.2, 2.0];
        let (mut a, mut x) = (a0, [1.0, -2.0, 0.5]);
        assert!(cholesky_solve(&mut a, &mut x));
        for i in 0..3 {
            let r: f64 = (0..3).map(|j| a0[i * 3 + j] * x[j]).sum::<f64>() - [1.0, -2.0, 0.5][i];
            assert!(r.abs() < 1e-14);
        }
        let mut bad = [1.0, 2.0, 2.0, 1.0];
        assert!(!cholesky_solve(&mut bad, &mut [1.0, 1.0]));
    }

    /// Q diag(d) Qᵀ for a fixed rotation Q of R⁶ (a product of plane
    /// rotations), row-major.
    fn with_eigenvalues(d: [f64; 6]) -> [f64; 36] {
        let mut q = [0.0; 36];
        for i in 0..6 {
            q[i * 6 + i] = 1.0;
        }
        for (p, r, t) in [
            (0, 3, 0.7),
            (1, 4, -0.4),
            (2, 5, 1.1),
            (0, 1, 0.3),
            (3, 5, -0.9),
        ] {
            let (c, s) = (f64::cos(t), f64::sin(t));
            for k in 0..6 {
                let (a, b) = (q[k * 6 + p], q[k * 6 + r]);
                q[k * 6 + p] = c * a - s * b;
                q[k * 6 + r] = s * a + c * b;
            }
        }
        let mut a = [0.0; 36];
        for i in 0..6 {
            for j in 0..6 {
                a[i * 6 + j] = (0..6).map(|k| q[i * 6 + k] * d[k] * q[j * 6 + k]).sum();
            }
        }
        a
    }

    /// The sweeps unrolled for 3 × 3 and 6 × 6 blocks rotate exactly as the
    /// generic ones: eigenvalues and eigenvectors equal to the last bit, on
    /// a rank-deficient 6 × 6 and on its leading 3 × 3.
    #[test]
    fn unrolled_sweeps_equal_the_generic_ones_bit_for_bit() {
        let a6 = with_eigenvalues([2.0, 0.0, 0.5, 3.0, 1e-12, 1.5]);
        let a3: Vec<f64> = (0..3)
            .flat_map(|i| (0..3).map(move |j| a6[i * 6 + j]))
            .collect();
        for a0 in [a6.to_vec(), a3] {
            let n = if a0.len() == 36 { 6 } else { 3 };
            let scale = a0.iter().map(|t| t * t).sum::<f64>().sqrt();
            let identity: Vec<f64> = (0..n * n)
                .map(|k| if k % (n + 1) == 0 { 1.0 } else { 0.0 })
                .collect();
            let (mut a1, mut v1) = (a0.clone(), identity.clone());
            let (mut a2, mut v2) = (a0.clone(), identity);
            sweeps_any(&mut a1, &mut v1, n, scale);
            match n {
                3 => sweeps::<3>(&mut a2, &mut v2, scale),
                _ => sweeps::<6>(&mut a2, &mut v2, scale),
            }
            let bits = |x: &[f64]| x.iter().map(|t| t.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&a1), bits(&a2), "{n} × {n}: eigenvalues");
            assert_eq!(bits(&v1), bits(&v2), "{n} × {n}: eigenvectors");
            // And the sweeps did diagonalise: off-diagonal round-off only.
            let off = (0..n * n)
                .filter(|k| k % (n + 1) != 0)
                .map(|k| a2[k].abs())
                .fold(0.0, f64::max);
            assert!(off < 1e-14 * scale, "{n} × {n}: off-diagonal {off:e}");
        }
    }

    /// The Cholesky shortcut and the eigensolve agree where the shortcut is
    /// taken, and the shortcut is refused where an eigenvalue would be
    /// dropped (or nearly so): the rank decides as before.
    #[test]
    fn the_full_rank_shortcut_agrees_with_the_eigensolve() {
        let b = [1.0, -2.0, 0.5, 0.25, 3.0, -1.0];
        let a0 = with_eigenvalues([2.0, 1.0, 0.5, 3.0, 0.1, 1.5]);
        let (mut x, mut v) = ([0.0; 6], [0.0; 36]);
        assert!(full_rank_solve(&a0, &b, &mut x, &mut v, 0.0).is_ok());
        let mut a = a0;
        assert_eq!(min_norm_solve(&mut a, &b, &mut x, &mut v, 0.0), 6);
        for i in 0..6 {
            let r: f64 = (0..6).map(|j| a0[i * 6 + j] * x[j]).sum::<f64>() - b[i];
            assert!(r.abs() < 1e-13, "row {i}: {r:e}");
        }
        // An eigenvalue 1e-8 below the largest: kept by the eigensolve, but
        // too close to the threshold for the shortcut.
        let near = with_eigenvalues([2.0, 1.0, 0.5, 3.0, 3e-8, 1.5]);
        assert!(full_rank_solve(&near, &b, &mut x, &mut v, 0.0).is_err());
        let mut a = near;
        assert_eq!(min_norm_solve(&mut a, &b, &mut x, &mut v, 0.0), 6);
        // Below the threshold: dropped, rank 5.
        let singular = with_eigenvalues([2.0, 1.0, 0.5, 3.0, 1e-12, 1.5]);
        assert!(full_rank_solve(&singular, &b, &mut x, &mut v, 0.0).is_err());
        let mut a = singular;
        assert_eq!(min_norm_solve(&mut a, &b, &mut x, &mut v, 0.0), 5);
        // A large reference scale makes every eigenvalue small: rank 0.
        let mut a = a0;
        assert!(full_rank_solve(&a0, &b, &mut x, &mut v, 1e12).is_err());
        assert_eq!(min_norm_solve(&mut a, &b, &mut x, &mut v, 1e12), 0);
    }

    #[test]
    fn rank_one_system_gives_the_minimum_norm_solution() {
        // A = u uᵀ, b = 2 u: the minimum-norm solution is 2 u / |u|².
        let u = [1.0, -2.0, 0.5];
        let uu: f64 = u.iter().map(|t| t * t).sum();
        let mut a = [0.0; 9];
        for i in 0..3 {
            for j in 0..3 {
                a[i * 3 + j] = u[i] * u[j];
            }
        }
        let b = u.map(|t| 2.0 * t * uu);
        let (mut x, mut v) = ([0.0; 3], [0.0; 9]);
        assert_eq!(min_norm_solve(&mut a, &b, &mut x, &mut v, 0.0), 1);
        for i in 0..3 {
            assert!((x[i] - 2.0 * u[i]).abs() < 1e-13, "{x:?}");
        }
    }
}
