//! The per-body products of A's assembly (`gram`), vectorised across the
//! columns of the body's block.
//!
//! A body touched by k rows adds C_b M̃_b⁻¹ C_bᵀ (k × k, lower triangle) to A:
//! k (k + 1) / 2 dot products of length 7. Written as one dot product per
//! entry, each is a chain of 7 dependent multiply-adds; here the row c_a
//! multiplies the columns u_b of four entries b at a time (U stored
//! transposed, 7 rows of k, so four consecutive b are one vector), which is
//! 7 independent vector multiply-adds per four entries. On the planar
//! lattice (132 bars, about 16 rows each) that is most of the assembly's
//! time (BENCHMARKS.md, "Issue 23 — the lattice's tick").
//!
//! **Same numbers.** Each entry is still Σᵢ c_a[i] u_b[i] summed in the
//! order i = 0..7 from 0, added to its destination in the same order as the
//! scalar loop: without FMA the result is bit-identical; with the AVX2 +
//! FMA build (chosen at run time, as the factor's kernels are) only the
//! rounding of each multiply-add differs.

/// Columns of U per vector.
pub(crate) const LANES: usize = 4;

/// k rounded up to whole vectors: the row stride of U's transposed buffer.
pub(crate) fn padded(k: usize) -> usize {
    k.div_ceil(LANES) * LANES
}

/// Adds the lower triangle of C Uᵀ (k × k) to `values`: entry (a, b), b ≤ a,
/// goes to `values[dests[a (a + 1) / 2 + b]]`. `c`: k rows of 7, row a at
/// `c[c_stride · a..]`; `ut`: 7 rows of `stride` ≥ [`padded`]`(k)` (entries
/// past k are read but their products never stored). `simd`: the CPU runs
/// AVX2 and FMA.
///
/// # Real-time
/// No allocation; k (k + 1) / 2 · 7 multiply-adds in vectors of four.
#[allow(clippy::too_many_arguments)]
pub(crate) fn add_products(
    k: usize,
    c: &[f64],
    c_stride: usize,
    ut: &[f64],
    stride: usize,
    dests: &[u32],
    values: &mut [f64],
    simd: bool,
) {
    assert!(
        c_stride >= 7 && c.len() >= c_stride * k && ut.len() >= 7 * stride && stride >= padded(k)
    );
    assert!(dests.len() >= k * (k + 1) / 2);
    #[cfg(target_arch = "x86_64")]
    if simd {
        // SAFETY: `simd` is true only where the CPU reported AVX2 and FMA
        // (`cholesky::simd_available`), the features this is compiled for.
        unsafe { add_products_avx2(k, c, c_stride, ut, stride, dests, values) };
        return;
    }
    let _ = simd;
    add_products_in(k, c, c_stride, ut, stride, dests, values);
}

/// [`add_products_in`] with explicit four-lane fused multiply-adds (the
/// compiler does not contract `a * b + c`, and left the lanes scalar).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn add_products_avx2(
    k: usize,
    c: &[f64],
    c_stride: usize,
    ut: &[f64],
    stride: usize,
    dests: &[u32],
    values: &mut [f64],
) {
    use std::arch::x86_64::{
        __m256d, _mm256_fmadd_pd, _mm256_loadu_pd, _mm256_set1_pd, _mm256_setzero_pd,
        _mm256_storeu_pd,
    };
    let mut first = 0;
    for a in 0..k {
        let ca: &[f64; 7] = c[c_stride * a..c_stride * a + 7]
            .try_into()
            .expect("seven values");
        let cv: [__m256d; 7] = ca.map(|x| _mm256_set1_pd(x));
        let mut b0 = 0;
        while b0 <= a {
            let mut acc = _mm256_setzero_pd();
            for (i, &ci) in cv.iter().enumerate() {
                let u: &[f64; LANES] = ut[i * stride + b0..i * stride + b0 + LANES]
                    .try_into()
                    .expect("four values");
                // SAFETY: `u` is four readable f64 (unaligned load).
                acc = _mm256_fmadd_pd(ci, unsafe { _mm256_loadu_pd(u.as_ptr()) }, acc);
            }
            let mut out = [0.0f64; LANES];
            // SAFETY: `out` is four writable f64 (unaligned store).
            unsafe { _mm256_storeu_pd(out.as_mut_ptr(), acc) };
            let n = (a + 1 - b0).min(LANES);
            for (l, &v) in out.iter().enumerate().take(n) {
                values[dests[first + b0 + l] as usize] += v;
            }
            b0 += LANES;
        }
        first += a + 1;
    }
}

#[inline(always)]
fn add_products_in(
    k: usize,
    c: &[f64],
    c_stride: usize,
    ut: &[f64],
    stride: usize,
    dests: &[u32],
    values: &mut [f64],
) {
    let mut first = 0;
    for a in 0..k {
        let ca: &[f64; 7] = c[c_stride * a..c_stride * a + 7]
            .try_into()
            .expect("seven values");
        let mut b0 = 0;
        while b0 <= a {
            let mut acc = [0.0f64; LANES];
            for (i, &ci) in ca.iter().enumerate() {
                let u: &[f64; LANES] = ut[i * stride + b0..i * stride + b0 + LANES]
                    .try_into()
                    .expect("four values");
                for l in 0..LANES {
                    acc[l] += ci * u[l];
                }
            }
            let n = (a + 1 - b0).min(LANES);
            for (l, &v) in acc.iter().enumerate().take(n) {
                values[dests[first + b0 + l] as usize] += v;
            }
            b0 += LANES;
        }
        first += a + 1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The vectorised products equal the one-dot-product-per-entry loop
    /// (bit for bit without FMA; to round-off with it), including the
    /// destinations shared by several entries.
    #[test]
    fn products_match_the_scalar_loop() {
        for k in [1usize, 3, 4, 5, 8, 13, 16, 17] {
            let stride = padded(k) + 4;
            let c: Vec<f64> = (0..7 * k)
                .map(|i| ((i * 37 % 11) as f64 - 5.0) * 0.37)
                .collect();
            let mut ut = vec![f64::NAN; 7 * stride];
            for b in 0..k {
                for i in 0..7 {
                    ut[i * stride + b] = ((b * 7 + i) * 13 % 17) as f64 * 0.11 - 0.9;
                }
            }
            // Past k the buffer holds NaN: multiplied, never stored.
            let n = k * (k + 1) / 2;
            let dests: Vec<u32> = (0..n).map(|t| ((t * 7) % (n / 2 + 1)) as u32).collect();
            let mut expected = vec![0.25; n];
            let mut t = 0;
            for a in 0..k {
                for b in 0..=a {
                    let mut acc = 0.0;
                    for i in 0..7 {
                        acc += c[7 * a + i] * ut[i * stride + b];
                    }
                    expected[dests[t] as usize] += acc;
                    t += 1;
                }
            }
            for simd in [false, crate::cholesky::simd_available()] {
                let mut got = vec![0.25; n];
                add_products(k, &c, 7, &ut, stride, &dests, &mut got, simd);
                for (g, e) in got.iter().zip(&expected) {
                    if simd {
                        assert!(
                            (g - e).abs() <= 1e-13 * (1.0 + e.abs()),
                            "k {k}: {g} vs {e}"
                        );
                    } else {
                        assert_eq!(g.to_bits(), e.to_bits(), "k {k}: {g} vs {e}");
                    }
                }
            }
        }
    }
}
