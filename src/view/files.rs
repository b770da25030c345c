//! The run files the viewer is made from, written by `haptloop run` and read
//! back by `haptloop view`: `scene.json` ([`SceneInfo`]), `bodies.csv`,
//! `fingers.csv`, `contacts.csv` (the session's tracks), with `trace.csv`
//! (force and violation per tick) and `summary.json` (semantic events).
//! Their columns are in `docs/run-files.md`. Every problem names the file
//! and line.

use super::scene::SceneInfo;
use crate::session::SessionOutcome;
use anyhow::{Context, Result, bail};
use std::io::{BufRead, BufReader};
use std::path::Path;

/// The files `haptloop view` needs, in the order it reads them.
pub const NEEDED: [&str; 6] = [
    "scene.json",
    "bodies.csv",
    "fingers.csv",
    "contacts.csv",
    "trace.csv",
    "summary.json",
];

/// The contents of `scene.json`, `bodies.csv`, `fingers.csv` and
/// `contacts.csv` for a finished session: (file name, text).
pub fn contents(info: &SceneInfo, o: &SessionOutcome) -> Result<Vec<(&'static str, String)>> {
    let names: Vec<String> = info.bodies.iter().map(|b| b.name.clone()).collect();
    Ok(vec![
        ("scene.json", serde_json::to_string_pretty(info)? + "\n"),
        ("bodies.csv", o.track.csv()),
        ("fingers.csv", o.recorder.fingers.csv()),
        ("contacts.csv", o.track.contacts_csv(&names)),
    ])
}

/// One CSV file's data rows: (line number, fields).
pub struct Csv {
    /// Path shown in messages.
    pub file: String,
    /// Rows after the header.
    pub rows: Vec<(usize, Vec<String>)>,
}

impl Csv {
    /// Reads `dir/name`, checking its header starts with `header`.
    pub fn read(dir: &Path, name: &str, header: &str) -> Result<Csv> {
        let path = dir.join(name);
        let file = path.display().to_string();
        let f = std::fs::File::open(&path).with_context(|| format!("reading {file}"))?;
        let mut rows = Vec::new();
        for (k, line) in BufReader::new(f).lines().enumerate() {
            let line = line.with_context(|| format!("{file}:{}: not text", k + 1))?;
            if k == 0 {
                if !line.starts_with(header) {
                    bail!("{file}:1: expected the header `{header}`, found `{line}`");
                }
                continue;
            }
            if line.is_empty() {
                continue;
            }
            rows.push((k + 1, line.split(',').map(str::to_owned).collect()));
        }
        Ok(Csv { file, rows })
    }

    /// Field `k` of the row at `line` as a number (an empty field: NaN).
    pub fn number(&self, line: usize, fields: &[String], k: usize) -> Result<f64> {
        let Some(v) = fields.get(k) else {
            bail!(
                "{}:{line}: expected at least {} fields, found {}",
                self.file,
                k + 1,
                fields.len()
            );
        };
        if v.is_empty() {
            return Ok(f64::NAN);
        }
        v.trim().parse().with_context(|| {
            format!(
                "{}:{line}: field {} `{v}` is not a number",
                self.file,
                k + 1
            )
        })
    }

    /// The `n` numbers at the end of a row whose name (which may hold
    /// commas) sits between the time and them: (t, name, numbers).
    pub fn named_row(
        &self,
        line: usize,
        fields: &[String],
        n: usize,
    ) -> Result<(f64, String, Vec<f64>)> {
        if fields.len() < n + 2 {
            bail!(
                "{}:{line}: expected {} fields, found {}",
                self.file,
                n + 2,
                fields.len()
            );
        }
        let t = self.number(line, fields, 0)?;
        let first = fields.len() - n;
        let name = fields[1..first].join(",");
        let values = (first..fields.len())
            .map(|k| self.number(line, fields, k))
            .collect::<Result<Vec<f64>>>()?;
        Ok((t, name, values))
    }
}

/// Refuses a run folder that lacks one of the [`NEEDED`] files, naming
/// every missing one.
pub fn check_dir(dir: &Path) -> Result<()> {
    if !dir.is_dir() {
        bail!(
            "{}: not a directory (give the run folder `haptloop run` wrote)",
            dir.display()
        );
    }
    let missing: Vec<&str> = NEEDED
        .iter()
        .copied()
        .filter(|f| !dir.join(f).is_file())
        .collect();
    if !missing.is_empty() {
        bail!(
            "{}: not a complete run folder: missing {} (a `haptloop run` with files writes them all; runs from before the viewer lack scene.json, fingers.csv and contacts.csv: run the scene again)",
            dir.display(),
            missing.join(", ")
        );
    }
    Ok(())
}
