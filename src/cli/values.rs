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

/// A finite number ≥ 0 (a damping).
pub fn non_negative(s: &str) -> Result<f64, String> {
    let v = number(s)?;
    if v >= 0.0 {
        Ok(v)
    } else {
        Err(format!("must be a finite number ≥ 0, got {v}"))
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

/// Update iterations per tick: an integer 1–10000.
pub fn iterations(s: &str) -> Result<u32, String> {
    match s.trim().parse::<u32>() {
        Ok(v) if (1..=10_000).contains(&v) => Ok(v),
        Ok(v) => Err(format!("must be 1–10000, got {v}")),
        Err(_) => Err(format!("`{s}` is not a whole number 1–10000")),
    }
}

/// A loop rate, Hz: an integer in the scheduler's range.
pub fn rate(s: &str) -> Result<u32, String> {
    use haptloop_rt::schedule::{MAX_RATE_HZ, MIN_RATE_HZ};
    match s.trim().parse::<u32>() {
        Ok(v) if (MIN_RATE_HZ..=MAX_RATE_HZ).contains(&v) => Ok(v),
        Ok(v) => Err(format!("must be {MIN_RATE_HZ}–{MAX_RATE_HZ} Hz, got {v}")),
        Err(_) => Err(format!(
            "`{s}` is not a whole number of Hz ({MIN_RATE_HZ}–{MAX_RATE_HZ})"
        )),
    }
}

/// Milliseconds between reference samples: 0 (every tick) to 10000.
pub fn reference_ms(s: &str) -> Result<f64, String> {
    let v = number(s)?;
    if (0.0..=10_000.0).contains(&v) {
        Ok(v)
    } else {
        Err(format!("must be 0–10000 ms, got {v}"))
    }
}

/// A fraction in (0, 1].
pub fn fraction(s: &str) -> Result<f64, String> {
    let v = number(s)?;
    if v > 0.0 && v <= 1.0 {
        Ok(v)
    } else {
        Err(format!("must be in (0, 1], got {v}"))
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

/// The fast loop's coordinates: `augmented`, `joint` or `auto`.
pub fn coordinates(s: &str) -> Result<haptloop_solver::Coordinates, String> {
    haptloop_solver::Coordinates::parse(s.trim()).ok_or_else(|| {
        format!("unknown coordinates `{s}` (expected `augmented`, `joint` or `auto`)")
    })
}

/// The Eq. 7 solver: `cholesky` (a numeric factorisation a tick; the
/// default) or `matvec` (the matvec-only tick: conjugate gradients
/// preconditioned by a factor the slow loop refreshes, each solve to its
/// tolerance within a cap of 64 iterations), `matvec:N` for a cap of N
/// (1–1000), `cg:N` (Jacobi-preconditioned conjugate gradients, at most N
/// iterations per right-hand side, 1–1000; gradient update only), `tree`
/// or `tree:N` (conjugate gradients preconditioned by a spanning tree of
/// the mechanism, no full factor; a cap of N iterations a solve, default
/// 500), `multilevel` or `multilevel:N` (conjugate gradients preconditioned
/// by an aggregation V-cycle, no full factor; a cap of N, default 500).
pub fn force_solver(s: &str) -> Result<haptloop_solver::ForceSolver, String> {
    use haptloop_solver::ForceSolver;
    let s = s.trim();
    match s.split_once(':') {
        None if s == "cholesky" => Ok(ForceSolver::Cholesky),
        None if s == "matvec" => Ok(ForceSolver::MATVEC),
        Some(("matvec", n)) => match n.trim().parse::<u32>() {
            Ok(max_iterations @ 1..=1000) => Ok(ForceSolver::Matvec { max_iterations }),
            _ => Err(format!(
                "`{n}` is not an iteration cap of 1–1000 (as in `matvec:8`)"
            )),
        },
        None if s == "tree" => Ok(ForceSolver::TREE),
        Some(("tree", n)) => match n.trim().parse::<u32>() {
            Ok(max_iterations @ 1..=1000) => Ok(ForceSolver::Tree { max_iterations }),
            _ => Err(format!(
                "`{n}` is not an iteration cap of 1–1000 (as in `tree:200`)"
            )),
        },
        None if s == "multilevel" => Ok(ForceSolver::MULTILEVEL),
        Some(("multilevel", n)) => match n.trim().parse::<u32>() {
            Ok(max_iterations @ 1..=1000) => Ok(ForceSolver::Multilevel { max_iterations }),
            _ => Err(format!(
                "`{n}` is not an iteration cap of 1–1000 (as in `multilevel:50`)"
            )),
        },
        Some(("cg", n)) => match n.trim().parse::<u32>() {
            Ok(max_iterations @ 1..=1000) => Ok(ForceSolver::ConjugateGradient { max_iterations }),
            _ => Err(format!(
                "`{n}` is not an iteration cap of 1–1000 (as in `cg:64`)"
            )),
        },
        _ => Err(format!(
            "unknown force solver `{s}` (expected `cholesky`, `matvec`, `matvec:N`, `tree`, `tree:N`, `multilevel`, `multilevel:N` or `cg:N`)"
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
        assert_eq!((iterations("1"), iterations("10000")), (Ok(1), Ok(10_000)));
        assert!(iterations("0").is_err() && iterations("").is_err() && iterations("2.5").is_err());
        assert_eq!((rate("100"), rate("20000")), (Ok(100), Ok(20_000)));
        assert!(rate("99").is_err() && rate("20001").is_err() && rate("").is_err());
        assert!(reference_ms("0").is_ok() && reference_ms("-1").is_err());
        assert!(fraction("1").is_ok() && fraction("0").is_err() && fraction("1.5").is_err());
    }

    /// `tree` and `tree:N` parse to the tree tick and print back as typed;
    /// a cap outside 1–1000 is refused naming the value.
    #[test]
    fn the_tree_force_solver_parses_and_prints_back() {
        for s in [
            "tree",
            "tree:1",
            "tree:1000",
            "matvec",
            "cg:64",
            "multilevel",
            "multilevel:16",
        ] {
            assert_eq!(force_solver(s).map(|f| f.label()), Ok(s.to_string()));
        }
        assert_eq!(force_solver("tree"), Ok(haptloop_solver::ForceSolver::TREE));
        for bad in ["tree:0", "tree:1001", "tree:x"] {
            let e = force_solver(bad).unwrap_err();
            assert!(e.contains(&bad[5..]), "{e}");
        }
        for bad in ["multilevel:0", "multilevel:1001", "multilevel:x"] {
            let e = force_solver(bad).unwrap_err();
            assert!(e.contains(&bad[11..]), "{e}");
        }
    }
}
