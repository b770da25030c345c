//! Finger rows whose multiplier is known in advance (proxies' coupling
//! forces): taken out of S's system and written back after it.

/// Rows whose multiplier is known (a proxy's coupling force): their part
/// moves to the right-hand side of the unknown rows, and each becomes the
/// decoupled row `reference · λ = 0` (so S stays full rank and takes the
/// Cholesky path; [`put_known_in`] then writes the known value). Returns how
/// many rows were known.
pub(super) fn take_known_out(
    schur: &mut [f64],
    rhs: &mut [f64],
    known: &[Option<f64>],
    reference: f64,
) -> usize {
    let m = rhs.len();
    let mut n_known = 0;
    for (f, k) in known.iter().enumerate() {
        let Some(v) = *k else { continue };
        n_known += 1;
        for (g, kg) in known.iter().enumerate() {
            if kg.is_none() {
                rhs[g] -= schur[g * m + f] * v;
            }
            schur[g * m + f] = 0.0;
            schur[f * m + g] = 0.0;
        }
        schur[f * m + f] = if reference > 0.0 { reference } else { 1.0 };
        rhs[f] = 0.0;
    }
    n_known
}

/// Writes the known multipliers over the solved ones.
pub(super) fn put_known_in(lambda_f: &mut [f64], known: &[Option<f64>]) {
    for (l, k) in lambda_f.iter_mut().zip(known) {
        if let Some(v) = *k {
            *l = v;
        }
    }
}
