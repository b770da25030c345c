//! `[[design_flag]]` tables and the `--design-on` / `--design-off` flags:
//! design variables switched on and off at given times of a run (Nelson &
//! Cohen §3: "design parameters, and therefore Jacobian columns, can be
//! removed or turned off with flags"). Every variable starts on; a switched-
//! off one is held where it is (`Program::set_design_active`).

use serde::Deserialize;
use toml::Spanned;

use super::{LoadedScene, SceneError};
use crate::Model;

/// `[[design_flag]]`: at `at` seconds, the variables in `off` are switched
/// off and those in `on` on.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DesignFlagSection {
    /// Session time, s, ≥ 0.
    pub at: Spanned<f64>,
    /// Design variables switched on (`<joint>.<var>`, `<body>.position`).
    #[serde(default)]
    pub on: Vec<Spanned<String>>,
    /// Design variables switched off.
    #[serde(default)]
    pub off: Vec<Spanned<String>>,
}

/// One switch of one design variable.
#[derive(Debug, Clone, PartialEq)]
pub struct DesignFlagDecl {
    /// Session time, s.
    pub at_s: f64,
    /// Index into the model's [`design_vars`](crate::Layout::design_vars).
    pub var: usize,
    /// Its name.
    pub name: String,
    /// Switched on (true) or off.
    pub on: bool,
}

/// The index of the design variable `name` of `model`, or why not.
fn lookup(model: &Model, name: &str) -> Result<usize, String> {
    let vars = model.layout().design_vars();
    vars.iter().position(|d| d.name == name).ok_or_else(|| {
        let known: Vec<&str> = vars.iter().map(|d| d.name.as_str()).collect();
        if known.is_empty() {
            format!("`{name}` is not a design variable: the scene frees none (`free` on a joint or fixed body makes one)")
        } else {
            format!("`{name}` is not a design variable (free: {})", known.join(", "))
        }
    })
}

/// Sorts switches by time, file (and flag) order kept among equal times.
pub(super) fn sorted(mut v: Vec<DesignFlagDecl>) -> Vec<DesignFlagDecl> {
    v.sort_by(|a, b| a.at_s.total_cmp(&b.at_s));
    v
}

impl LoadedScene {
    /// The file's switches against the compiled `model`, sorted by time.
    pub(super) fn compile_design_flags(
        &self,
        model: &Model,
    ) -> Result<Vec<DesignFlagDecl>, SceneError> {
        let mut out = Vec::new();
        for f in &self.spec.design_flags {
            let at = *f.at.get_ref();
            if !(at.is_finite() && at >= 0.0) {
                return Err(self.error_at(
                    f.at.span(),
                    format!("`at` is {at}; expected a session time in seconds, finite and ≥ 0"),
                ));
            }
            if f.on.is_empty() && f.off.is_empty() {
                return Err(self.error_at(
                    f.at.span(),
                    "a design flag switches nothing: give `on` or `off` names",
                ));
            }
            for (names, on) in [(&f.off, false), (&f.on, true)] {
                for n in names {
                    let var = lookup(model, n.get_ref()).map_err(|m| self.error_at(n.span(), m))?;
                    if on && f.off.iter().any(|o| o.get_ref() == n.get_ref()) {
                        return Err(self.error_at(
                            n.span(),
                            format!("`{}` is switched both on and off at {at} s", n.get_ref()),
                        ));
                    }
                    out.push(DesignFlagDecl {
                        at_s: at,
                        var,
                        name: n.get_ref().clone(),
                        on,
                    });
                }
            }
        }
        Ok(sorted(out))
    }
}

/// One `--design-on` (`on`) or `--design-off` value, `NAME@SECONDS`, against
/// `model`; errors name the flag and point into its value.
pub fn design_switch(value: &str, on: bool, model: &Model) -> Result<DesignFlagDecl, SceneError> {
    let flag = if on { "--design-on" } else { "--design-off" };
    let err = |at: usize, message: String| SceneError {
        file: flag.to_string(),
        line: 1,
        column: value[..at.min(value.len())].chars().count() + 1,
        message,
        source_line: value.to_string(),
    };
    let Some((name, time)) = value.rsplit_once('@') else {
        return Err(err(
            0,
            "expected NAME@SECONDS, e.g. `left.length@2.5`".into(),
        ));
    };
    let at = name.len() + 1;
    let at_s: f64 = time
        .trim()
        .parse()
        .map_err(|_| err(at, format!("`{time}` is not a time in seconds")))?;
    if !(at_s.is_finite() && at_s >= 0.0) {
        return Err(err(at, format!("{at_s} s: expected a finite time ≥ 0")));
    }
    let var = lookup(model, name.trim()).map_err(|m| err(0, m))?;
    Ok(DesignFlagDecl {
        at_s,
        var,
        name: name.trim().to_string(),
        on,
    })
}

/// `switches` added to `existing`, sorted by time (command-line switches
/// after the file's at equal times).
pub fn with_switches(
    existing: &[DesignFlagDecl],
    switches: Vec<DesignFlagDecl>,
) -> Vec<DesignFlagDecl> {
    let mut v = existing.to_vec();
    v.extend(switches);
    sorted(v)
}
