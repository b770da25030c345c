//! Numbers in words for the text reports: small values keep their
//! significant digits (`1.00e-4 mm`, never `0.000 mm`), a figure that was not
//! measured is said so (never `NaN`).

/// A length given in metres, written in millimetres: three decimals from
/// 0.01 mm up, three significant digits in scientific notation below it,
/// `0 mm` for exactly zero.
pub fn mm(m: f64) -> String {
    if !m.is_finite() {
        return format!("{m} m");
    }
    let v = m * 1e3;
    if v == 0.0 {
        "0 mm".into()
    } else if v.abs() >= 0.01 {
        format!("{v:.3} mm")
    } else {
        format!("{v:.2e} mm")
    }
}

/// `v` with `decimals` decimals and its unit, or `not measured` when it is
/// not a number.
pub fn or_not_measured(v: f64, decimals: usize, unit: &str) -> String {
    if v.is_nan() {
        "not measured".into()
    } else {
        format!("{v:.decimals$} {unit}")
    }
}

/// `v` in scientific notation with three significant digits and its unit;
/// a figure that is not finite is named as such (`not finite (NaN)`), never
/// printed as a bare `NaN` next to a unit.
pub fn sci(v: f64, unit: &str) -> String {
    if v.is_finite() {
        format!("{v:.2e} {unit}")
    } else {
        format!("not finite ({v})")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn small_lengths_keep_their_digits() {
        assert_eq!(mm(1e-4), "0.100 mm");
        assert_eq!(mm(1e-7), "1.00e-4 mm");
        assert_eq!(mm(0.0), "0 mm");
        assert_eq!(mm(2.5e-3), "2.500 mm");
        assert_eq!(or_not_measured(f64::NAN, 1, "ticks"), "not measured");
        assert_eq!(or_not_measured(2.25, 1, "ticks"), "2.2 ticks");
        assert_eq!(sci(1.234e-9, "m"), "1.23e-9 m");
        assert_eq!(sci(f64::NAN, "N"), "not finite (NaN)");
    }
}
