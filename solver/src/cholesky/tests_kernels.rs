//! The dense kernel of a supernode's block: its column order against the
//! row order it replaced, on random symmetric positive definite blocks with
//! rows below the diagonal part (widths 1–20: the unrolled kernels of
//! 1–16 and the generic one).

use super::Regularization;
use super::kernels::{dense_factor, rows_order};
use super::tests::Lcg;

/// A block of width `w` with `below` rows under its diagonal part: the
/// diagonal part's lower triangle from B Bᵀ + w I (positive definite), the
/// rows below random (row-major, the upper triangle left as garbage that
/// neither order may read).
fn block(w: usize, below: usize, rng: &mut Lcg) -> Vec<f64> {
    let b: Vec<f64> = (0..w * w).map(|_| rng.next() - 0.5).collect();
    let mut out = vec![f64::NAN; (w + below) * w];
    for i in 0..w {
        for j in 0..=i {
            let bb: f64 = (0..w).map(|k| b[i * w + k] * b[j * w + k]).sum();
            out[i * w + j] = bb + if i == j { w as f64 } else { 0.0 };
        }
    }
    for v in &mut out[w * w..] {
        *v = rng.next() - 0.5;
    }
    out
}

/// Both orders compute each entry by the same expression: the factor,
/// its reciprocal pivots and the regularised-pivot count agree bit for
/// bit for every width, and a pivot the
/// regularisation replaces is replaced in both.
#[test]
fn the_column_order_equals_the_row_order_bit_for_bit() {
    let mut rng = Lcg(7);
    let reg = Regularization {
        epsilon: 1e-8,
        delta: 1.0,
    };
    for w in 1..=20 {
        for below in [0, 1, 2, 5, 12] {
            let mut a = block(w, below, &mut rng);
            if w > 2 {
                // Rows 1 and 2 equal over columns 0–2: a zero pivot at
                // column 2 (to round-off), which both orders replace.
                for j in 0..=1 {
                    a[2 * w + j] = a[w + j];
                }
                a[2 * w + 2] = a[w + 1];
            }
            let (mut col, mut row) = (a.clone(), a);
            let (mut inv_c, mut inv_r) = (vec![0.0; w], vec![0.0; w]);
            let nc = dense_factor(&mut col, w, 0, reg, &mut inv_c);
            let nr = rows_order(&mut row, w, 0, reg, &mut inv_r);
            assert_eq!(nc, nr, "w {w}, below {below}");
            assert_eq!(nc, Ok(usize::from(w > 2)), "w {w}, below {below}");
            let lower = |x: &[f64]| -> Vec<u64> {
                (0..w + below)
                    .flat_map(|i| (0..w.min(i + 1)).map(move |j| (i, j)))
                    .map(|(i, j)| x[i * w + j].to_bits())
                    .collect()
            };
            assert_eq!(lower(&col), lower(&row), "w {w}, below {below}");
            let bits = |x: &[f64]| x.iter().map(|t| t.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&inv_c), bits(&inv_r), "w {w}, below {below}");
        }
    }
}
