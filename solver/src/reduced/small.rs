//! Dense kernels for the joint tick's small matrices (3–10 rows): plain
//! loops over caller-owned row-major slices, no allocation, no library
//! call. The Cholesky factor itself is `force::small::factor_in_place`.

/// b ← L⁻¹ b for the lower factor `l` (n × n row-major, n = b.len()).
#[inline]
pub(crate) fn forward(l: &[f64], b: &mut [f64]) {
    let n = b.len();
    for i in 0..n {
        let row = &l[i * n..i * n + i];
        let mut v = b[i];
        for (lk, bk) in row.iter().zip(&b[..i]) {
            v -= lk * bk;
        }
        b[i] = v / l[i * n + i];
    }
}

/// b ← L⁻ᵀ b for the lower factor `l` (n × n row-major, n = b.len()).
#[inline]
pub(crate) fn backward(l: &[f64], b: &mut [f64]) {
    let n = b.len();
    for i in (0..n).rev() {
        let mut v = b[i];
        for k in i + 1..n {
            v -= l[k * n + i] * b[k];
        }
        b[i] = v / l[i * n + i];
    }
}

/// a · b.
#[inline]
pub(crate) fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::force::small::factor_in_place;

    /// forward then backward against the dense solve of L Lᵀ x = b.
    #[test]
    fn the_two_sweeps_solve_the_factored_system() {
        let n = 5;
        let a = nalgebra::DMatrix::from_fn(n, n, |i, j| {
            1.0 / (1.0 + i as f64 + j as f64) + if i == j { 2.0 } else { 0.0 }
        });
        let b = nalgebra::DVector::from_fn(n, |i, _| (i as f64 * 0.7).sin() + 0.1);
        let want = a.clone().cholesky().unwrap().solve(&b);
        let mut l: Vec<f64> = (0..n * n).map(|k| a[(k / n, k % n)]).collect();
        assert!(factor_in_place(&mut l, n));
        let mut x: Vec<f64> = b.iter().copied().collect();
        forward(&l, &mut x);
        backward(&l, &mut x);
        let err = (0..n).map(|i| (x[i] - want[i]).abs()).fold(0.0, f64::max);
        assert!(err < 1e-13, "|x − x_dense| = {err:.2e}");
        assert!(want.amax() > 0.1);
    }
}
