//! Value parsers for numeric flags: a value out of range is a usage error
//! (clap prints it with the flag's name and exits with status 2), caught
//! before anything runs.

/// Session or probe length, seconds: finite, in (0, 86400].
pub fn seconds(s: &str) -> Result<f64, String> {
    let v = number(s)?;
    if v > 0.0 && v <= 86_400.0 {
        Ok(v)
    } else {
        Err(format!("must be in (0, 86400] seconds, got {v}"))
    }
}

/// A gain: finite and > 0.
pub fn positive(s: &str) -> Result<f64, String> {
    let v = number(s)?;
    if v > 0.0 {
        Ok(v)
    } else {
        Err(format!("must be a finite number > 0, got {v}"))
    }
}

/// The velocity filter's time constant, ms: 0 (off) to 1000.
pub fn filter_ms(s: &str) -> Result<f64, String> {
    let v = number(s)?;
    if (0.0..=1000.0).contains(&v) {
        Ok(v)
    } else {
        Err(format!("must be 0–1000 ms, got {v}"))
    }
}

/// An update rule: `projected` (the default) or `gradient` (Nelson & Cohen
/// Eq. 1–3).
pub fn update_rule(s: &str) -> Result<haptloop_solver::UpdateRule, String> {
    match s.trim() {
        "projected" => Ok(haptloop_solver::UpdateRule::Projected),
        "gradient" => Ok(haptloop_solver::UpdateRule::Gradient),
        other => Err(format!(
            "unknown update rule `{other}` (expected `projected` or `gradient`)"
        )),
    }
}

fn number(s: &str) -> Result<f64, String> {
    let v: f64 = s
        .trim()
        .parse()
        .map_err(|_| format!("`{s}` is not a number"))?;
    if v.is_finite() {
        Ok(v)
    } else {
        Err(format!("must be finite, got {v}"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_are_enforced_at_their_edges() {
        assert_eq!(seconds("86400"), Ok(86_400.0));
        assert!(seconds("0").is_err() && seconds("86400.5").is_err());
        assert!(seconds("nan").is_err() && seconds("inf").is_err());
        assert!(positive("0").is_err() && positive("-1").is_err());
        assert_eq!(positive("1e20"), Ok(1e20));
        assert_eq!(filter_ms("0"), Ok(0.0));
        assert!(filter_ms("1000.1").is_err() && filter_ms("x").is_err());
        assert!(update_rule("gradient").is_ok() && update_rule("newton").is_err());
    }
}
