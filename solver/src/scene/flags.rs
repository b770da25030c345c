//! `haptloop run SCENE --free j.var --objective KIND:key=value,…`: design
//! variables and objectives added from the command line, without editing the
//! scene. Errors name the flag (`--free:1:7: …`, with the flag as the source
//! line), not a place in the file.
//!
//! `--objective` becomes an `[[objective]]` table appended to the scene's
//! text (so it is parsed, validated and compiled like any other, with the
//! same keys and errors: `docs/scene-format.md`); `--free` adds an entry to
//! a joint's or fixed body's `free` list.

use std::ops::Range;

use toml::Spanned;

use super::spec::{FreeSpec, JointKindSpec};
use super::{LoadedScene, SceneError};

/// A scene with command-line design flags applied, and what it takes to
/// attribute later errors to them.
#[derive(Debug, Clone)]
pub struct Flagged {
    /// The scene, flags applied (its text ends with the appended objectives).
    pub loaded: LoadedScene,
    /// Lines (1-based, end exclusive) of each `--objective`'s table, and the
    /// flag's value.
    objective_lines: Vec<(Range<usize>, String)>,
    /// Per appended line (1-based line number): for each character of the
    /// line, the character of the flag's value it came from (`kind = "…"`
    /// lines and the quotes added around bare words map to their
    /// neighbours), so an error's column becomes the flag's.
    columns: Vec<(usize, Vec<usize>)>,
}

fn flag_error(flag: &str, value: &str, at: usize, message: impl Into<String>) -> SceneError {
    SceneError {
        file: flag.to_string(),
        line: 1,
        column: value[..at.min(value.len())].chars().count() + 1,
        message: message.into(),
        source_line: value.to_string(),
    }
}

/// A joint kind as a scene spells it.
fn kind_name(k: JointKindSpec) -> &'static str {
    match k {
        JointKindSpec::Spherical => "spherical",
        JointKindSpec::Revolute => "revolute",
        JointKindSpec::Universal => "universal",
        JointKindSpec::Prismatic => "prismatic",
        JointKindSpec::Fixed => "fixed",
        JointKindSpec::Distance => "distance",
        JointKindSpec::Perpendicular => "perpendicular",
        JointKindSpec::PointOnPlane => "point_on_plane",
        JointKindSpec::OnSurface => "on_surface",
        JointKindSpec::Rolling => "rolling",
    }
}

/// Characters of `s` before byte `at`.
fn chars_before(s: &str, at: usize) -> usize {
    s[..at.min(s.len())].chars().count()
}

/// For each character of `quoted` (`original` with `"` inserted around bare
/// words by [`quote_words`]), the index of the character of `original` it
/// is or stands next to.
fn inserted_map(original: &str, quoted: &str) -> Vec<usize> {
    let orig: Vec<char> = original.chars().collect();
    let mut j = 0;
    quoted
        .chars()
        .map(|c| {
            if orig.get(j) == Some(&c) {
                j += 1;
                j - 1
            } else {
                j.min(orig.len().saturating_sub(1))
            }
        })
        .collect()
}

/// Splits `a=1,b=[x,y]` at the commas outside brackets and quotes.
fn split_pairs(s: &str) -> Vec<(usize, &str)> {
    let (mut out, mut depth, mut quoted, mut start) = (Vec::new(), 0i32, false, 0);
    for (i, c) in s.char_indices() {
        match c {
            '"' => quoted = !quoted,
            '[' | '{' if !quoted => depth += 1,
            ']' | '}' if !quoted => depth -= 1,
            ',' if !quoted && depth == 0 => {
                out.push((start, &s[start..i]));
                start = i + 1;
            }
            _ => {}
        }
    }
    out.push((start, &s[start..]));
    out
}

/// Quotes bare words in a TOML value (`[base, upper]` → `["base", "upper"]`)
/// so names need no shell-escaped quotes; numbers, booleans and quoted
/// strings are left alone. A word is any run of characters other than
/// whitespace and TOML's `[ ] { } , = "` (so `bäse` and `arm→2` are names
/// too, not syntax errors).
fn quote_words(v: &str) -> String {
    let mut out = String::with_capacity(v.len() + 8);
    let chars: Vec<char> = v.chars().collect();
    let (mut i, mut quoted) = (0, false);
    let word =
        |c: char| !(c.is_whitespace() || matches!(c, '[' | ']' | '{' | '}' | ',' | '=' | '"'));
    while i < chars.len() {
        let c = chars[i];
        if c == '"' {
            quoted = !quoted;
            out.push(c);
            i += 1;
            continue;
        }
        if quoted || !word(c) {
            out.push(c);
            i += 1;
            continue;
        }
        let end = (i..chars.len())
            .find(|&j| !word(chars[j]))
            .unwrap_or(chars.len());
        let w: String = chars[i..end].iter().collect();
        let bare = w.trim_start_matches(['+', '-']);
        let numeric = w.replace('_', "").parse::<f64>().is_ok()
            && bare.starts_with(|c: char| c.is_ascii_digit() || c == '.');
        if numeric || matches!(w.as_str(), "true" | "false") || matches!(bare, "inf" | "nan") {
            out.push_str(&w);
        } else {
            out.push('"');
            out.push_str(&w);
            out.push('"');
        }
        i = end;
    }
    out
}

impl LoadedScene {
    /// Applies `--objective` values (`KIND` or `KIND:key=value,…`, the keys
    /// of `[[objective]]`; bare words are names) and `--free` values
    /// (`<joint>.<length|anchor_i|anchor_j>` or `<fixed body>.position`).
    pub fn with_flags(self, free: &[String], objectives: &[String]) -> Result<Flagged, SceneError> {
        let mut text = self.text.clone();
        let mut objective_lines = Vec::new();
        let mut columns = Vec::new();
        for value in objectives {
            let (kind, rest) = value.split_once(':').unwrap_or((value.as_str(), ""));
            if kind.trim().is_empty() {
                return Err(flag_error(
                    "--objective",
                    value,
                    0,
                    "expected KIND or KIND:key=value,… (e.g. `dexterity:chain=[base,arm],point=[0.1,0,0]`)",
                ));
            }
            if !text.ends_with('\n') {
                text.push('\n');
            }
            let first = text.lines().count() + 1;
            let kind_line = format!("kind = \"{}\"", kind.trim());
            text.push_str(&format!(
                "\n# --objective {value}\n[[objective]]\n{kind_line}\n"
            ));
            // The `kind` line: every column at the kind's first character.
            let kind_at = chars_before(value, value.len() - value.trim_start().len());
            columns.push((first + 3, vec![kind_at; kind_line.chars().count() + 1]));
            let mut keys: Vec<&str> = Vec::new();
            for (at, pair) in split_pairs(rest)
                .into_iter()
                .filter(|(_, p)| !p.trim().is_empty())
            {
                let at = kind.len() + 1 + at;
                let Some((key, v)) = pair.split_once('=') else {
                    return Err(flag_error(
                        "--objective",
                        value,
                        at,
                        format!("`{}` is not key=value", pair.trim()),
                    ));
                };
                let key_at = at + (key.len() - key.trim_start().len());
                if keys.contains(&key.trim()) {
                    return Err(flag_error(
                        "--objective",
                        value,
                        key_at,
                        format!("key `{}` is given twice", key.trim()),
                    ));
                }
                keys.push(key.trim());
                let v_at = at + key.len() + 1 + (v.len() - v.trim_start().len());
                let quoted = quote_words(v.trim());
                let line = format!("{} = {quoted}", key.trim());
                let mut map = Vec::with_capacity(line.chars().count() + 1);
                let key_col = chars_before(value, key_at);
                map.extend(std::iter::repeat_n(key_col, key.trim().chars().count() + 3));
                let v_col = chars_before(value, v_at);
                map.extend(
                    inserted_map(v.trim(), &quoted)
                        .into_iter()
                        .map(|k| v_col + k),
                );
                map.push(map.last().copied().unwrap_or(0) + 1);
                text.push_str(&line);
                text.push('\n');
                columns.push((text.lines().count(), map));
            }
            objective_lines.push((first..text.lines().count() + 1, value.clone()));
        }
        let mut flagged = Flagged {
            loaded: self.clone(),
            objective_lines,
            columns,
        };
        if !objectives.is_empty() {
            flagged.loaded = super::parse(&self.file, &text, self.dir.as_deref())
                .map_err(|e| flagged.attribute(e))?;
        }
        for (k, value) in free.iter().enumerate() {
            if free[..k].contains(value) {
                return Err(flag_error(
                    "--free",
                    value,
                    0,
                    format!("`--free {value}` is given twice"),
                ));
            }
            flagged.free(value)?;
        }
        Ok(flagged)
    }
}

impl Flagged {
    /// Maps an error located in an appended objective's lines to its flag.
    pub fn attribute(&self, e: SceneError) -> SceneError {
        match self
            .objective_lines
            .iter()
            .find(|(r, _)| r.contains(&e.line))
        {
            Some((_, value)) => {
                let column = self
                    .columns
                    .iter()
                    .find(|(line, _)| *line == e.line)
                    .and_then(|(_, map)| map.get(e.column.saturating_sub(1)).copied())
                    .unwrap_or(0);
                SceneError {
                    file: "--objective".into(),
                    line: 1,
                    column: column + 1,
                    message: e.message,
                    source_line: value.clone(),
                }
            }
            None => e,
        }
    }

    /// One `--free` value.
    fn free(&mut self, value: &str) -> Result<(), SceneError> {
        let err = |at: usize, m: String| flag_error("--free", value, at, m);
        let Some((owner, var)) = value.rsplit_once('.') else {
            return Err(err(
                0,
                "expected <joint>.<variable> or <fixed body>.position, e.g. `left.length`".into(),
            ));
        };
        let at = owner.len() + 1;
        let param = match var {
            "length" => FreeSpec::Length,
            "anchor_i" => FreeSpec::AnchorI,
            "anchor_j" => FreeSpec::AnchorJ,
            "position" => FreeSpec::Position,
            other => {
                return Err(err(
                    at,
                    format!(
                        "unknown design variable `{other}`; expected one of length | anchor_i | anchor_j | position"
                    ),
                ));
            }
        };
        let spec = &mut self.loaded.spec;
        if param == FreeSpec::Position {
            let names: Vec<String> = spec
                .bodies
                .iter()
                .map(|b| b.name.get_ref().clone())
                .collect();
            let Some(b) = spec.bodies.iter_mut().find(|b| b.name.get_ref() == owner) else {
                return Err(err(
                    0,
                    format!("no body `{owner}` (bodies: {})", names.join(", ")),
                ));
            };
            if !b.fixed {
                return Err(err(
                    0,
                    format!(
                        "body `{owner}` is not fixed: a moving body's position is already free; `position` frees a fixed body's"
                    ),
                ));
            }
            if b.free.iter().any(|f| *f.get_ref() == param) {
                return Err(err(
                    0,
                    format!("`{value}` is already free in the scene file"),
                ));
            }
            b.free.push(Spanned::new(b.name.span(), param));
            return Ok(());
        }
        let names: Vec<String> = spec
            .joints
            .iter()
            .enumerate()
            .map(|(k, j)| {
                j.name
                    .as_ref()
                    .map_or(format!("#{}", k + 1), |n| n.get_ref().clone())
            })
            .collect();
        let Some(k) = names.iter().position(|n| n == owner) else {
            return Err(err(
                0,
                format!("no joint `{owner}` (joints: {})", names.join(", ")),
            ));
        };
        let j = &mut spec.joints[k];
        let kind = *j.kind.get_ref();
        let ok = match param {
            FreeSpec::Length => kind == JointKindSpec::Distance,
            _ => kind != JointKindSpec::Perpendicular,
        };
        if !ok {
            let has = if kind == JointKindSpec::Perpendicular {
                "none"
            } else {
                "anchor_i, anchor_j"
            };
            return Err(err(
                at,
                format!(
                    "joint `{owner}` ({}) has no design variable `{var}`; it has {has}",
                    kind_name(kind)
                ),
            ));
        }
        if j.free.iter().any(|f| *f.get_ref() == param) {
            return Err(err(
                0,
                format!("`{value}` is already free in the scene file"),
            ));
        }
        let span = j.name.as_ref().map_or(j.kind.span(), Spanned::span);
        j.free.push(Spanned::new(span, param));
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::{quote_words, split_pairs};

    #[test]
    fn bare_words_are_quoted_and_numbers_are_not() {
        assert_eq!(
            quote_words("[base, upper-arm, #3]"),
            r##"["base", "upper-arm", "#3"]"##
        );
        assert_eq!(
            quote_words("[1e-3, -0.5, +2E+4, inf]"),
            "[1e-3, -0.5, +2E+4, inf]"
        );
        assert_eq!(
            quote_words(r#"["quoted name", true]"#),
            r#"["quoted name", true]"#
        );
        assert_eq!(
            quote_words("[{body=link1,point=[0.1,0,0]}]"),
            r#"[{"body"="link1","point"=[0.1,0,0]}]"#
        );
        // Names that are not ASCII letters are names too.
        assert_eq!(
            quote_words("[bäse, arm→2, 2nd]"),
            r#"["bäse", "arm→2", "2nd"]"#
        );
    }

    #[test]
    fn pairs_split_at_top_level_commas_only() {
        let p: Vec<&str> = split_pairs("chain=[a,b],point=[1,0,0],name=\"x,y\"")
            .into_iter()
            .map(|(_, s)| s)
            .collect();
        assert_eq!(p, ["chain=[a,b]", "point=[1,0,0]", "name=\"x,y\""]);
    }
}
