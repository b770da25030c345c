//! The data a page draws, read from a run folder ([`PageData::read`]):
//! poses per moving body, the fingers, the contacts, the plots' series
//! (force per finger and violation from `trace.csv`, the largest of each
//! bin so a spike is never averaged away; penetration from the contacts)
//! and the semantic events. Numbers are `f32`: ample for drawing, and
//! half the page.

use super::files::{Csv, check_dir};
use super::scene::SceneInfo;
use anyhow::{Context, Result, bail};
use serde::Serialize;
use std::collections::HashMap;
use std::path::Path;

/// Bins of the plotted series over the run.
const PLOT_BINS: usize = 2000;

/// Everything a page needs (see the module docs).
#[derive(Debug, Clone, Serialize, Default)]
pub struct PageData {
    /// `scene.json`.
    pub scene: Option<SceneInfo>,
    /// Streamed by `run --live` (true) or replayed from files.
    pub live: bool,
    /// Indices into `scene.bodies` of the moving bodies, `poses` order.
    pub moving: Vec<usize>,
    /// Sample times of the bodies, s.
    pub t: Vec<f32>,
    /// Per moving body: x, y, z, qw, qx, qy, qz per sample.
    pub poses: Vec<Vec<f32>>,
    /// The fingers' samples.
    pub fingers: Fingers,
    /// Contact rows: t, x, y, z, nx, ny, nz, gap (8 numbers each).
    pub contacts: Vec<f32>,
    /// The plots.
    pub series: Series,
    /// Semantic events in time order.
    pub events: Vec<EventData>,
}

/// Each finger's device point, fingertip and force (3 numbers per sample).
#[derive(Debug, Clone, Serialize, Default)]
pub struct Fingers {
    /// Sample times, s.
    pub t: Vec<f32>,
    /// Per finger.
    pub device: Vec<Vec<f32>>,
    /// Per finger.
    pub tip: Vec<Vec<f32>>,
    /// Per finger.
    pub force: Vec<Vec<f32>>,
}

/// The side panel's plots.
#[derive(Debug, Clone, Serialize, Default)]
pub struct Series {
    /// Bin start times, s.
    pub t: Vec<f32>,
    /// Largest |F| per bin, per finger, N.
    pub force: Vec<Vec<f32>>,
    /// Largest violation per bin, m.
    pub violation: Vec<f32>,
    /// (t, deepest penetration) per contact sample, m.
    pub penetration: Vec<[f32; 2]>,
}

/// One semantic event.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct EventData {
    /// Session time, s.
    pub t_s: f64,
    /// `snap`, `break`, `hold`, `add`, `remove`, …
    pub kind: String,
    /// The bound body (for `add` and `remove`: the body brought in or
    /// taken out).
    pub body: String,
    /// In words.
    pub text: String,
}

impl PageData {
    /// Reads the run folder `dir` (every needed file, or an error naming
    /// what is missing or wrong, with file and line).
    pub fn read(dir: &Path) -> Result<PageData> {
        check_dir(dir)?;
        let path = dir.join("scene.json");
        let scene: SceneInfo = serde_json::from_str(
            &std::fs::read_to_string(&path)
                .with_context(|| format!("reading {}", path.display()))?,
        )
        .with_context(|| format!("{}: not a scene description", path.display()))?;
        let mut d = PageData::default();
        d.read_bodies(dir, &scene)?;
        d.read_fingers(dir, &scene)?;
        d.read_contacts(dir)?;
        d.read_trace(dir, &scene)?;
        d.events = events(dir)?;
        d.scene = Some(scene);
        Ok(d)
    }

    fn read_bodies(&mut self, dir: &Path, scene: &SceneInfo) -> Result<()> {
        let csv = Csv::read(dir, "bodies.csv", "t_s,body,x_m")?;
        let index: HashMap<&str, usize> = scene
            .bodies
            .iter()
            .enumerate()
            .map(|(k, b)| (b.name.as_str(), k))
            .collect();
        self.moving = (0..scene.bodies.len())
            .filter(|&k| !scene.bodies[k].fixed)
            .collect();
        let slot: HashMap<usize, usize> = self
            .moving
            .iter()
            .enumerate()
            .map(|(s, &k)| (k, s))
            .collect();
        self.poses = vec![Vec::new(); self.moving.len()];
        for (line, f) in &csv.rows {
            let (t, name, v) = csv.named_row(*line, f, 7)?;
            let Some(&k) = index.get(name.as_str()) else {
                bail!("{}:{line}: body `{name}` is not in scene.json", csv.file);
            };
            let Some(&s) = slot.get(&k) else { continue };
            if self.t.last() != Some(&(t as f32)) || self.poses[s].len() == 7 * self.t.len() {
                self.t.push(t as f32);
            }
            self.poses[s].extend(v.iter().map(|x| *x as f32));
        }
        for (s, p) in self.poses.iter_mut().enumerate() {
            if p.len() != 7 * self.t.len() {
                bail!(
                    "{}: body `{}` has {} samples of {}",
                    csv.file,
                    scene.bodies[self.moving[s]].name,
                    p.len() / 7,
                    self.t.len()
                );
            }
        }
        Ok(())
    }

    fn read_fingers(&mut self, dir: &Path, scene: &SceneInfo) -> Result<()> {
        let csv = Csv::read(dir, "fingers.csv", "t_s,finger,device_x_m")?;
        let n = scene.fingers.len();
        let f = &mut self.fingers;
        (f.device, f.tip, f.force) = (
            vec![Vec::new(); n],
            vec![Vec::new(); n],
            vec![Vec::new(); n],
        );
        for (line, fields) in &csv.rows {
            let (t, name, v) = csv.named_row(*line, fields, 9)?;
            let Some(k) = scene.fingers.iter().position(|x| x.name == name) else {
                bail!("{}:{line}: finger `{name}` is not in scene.json", csv.file);
            };
            if k == 0 {
                f.t.push(t as f32);
            }
            let v: Vec<f32> = v.iter().map(|x| *x as f32).collect();
            f.device[k].extend(&v[0..3]);
            f.tip[k].extend(&v[3..6]);
            f.force[k].extend(&v[6..9]);
        }
        Ok(())
    }

    fn read_contacts(&mut self, dir: &Path) -> Result<()> {
        let csv = Csv::read(dir, "contacts.csv", "t_s,body_a,body_b,x_m")?;
        for (line, fields) in &csv.rows {
            let t = csv.number(*line, fields, 0)?;
            let v = (fields.len().saturating_sub(7)..fields.len())
                .map(|k| csv.number(*line, fields, k))
                .collect::<Result<Vec<f64>>>()?;
            if fields.len() < 10 {
                bail!(
                    "{}:{line}: expected 10 fields, found {}",
                    csv.file,
                    fields.len()
                );
            }
            self.contacts.push(t as f32);
            self.contacts.extend(v.iter().map(|x| *x as f32));
            let pen = (-v[6]).max(0.0) as f32;
            match self.series.penetration.last_mut() {
                Some(last) if last[0] == t as f32 => last[1] = last[1].max(pen),
                _ => self.series.penetration.push([t as f32, pen]),
            }
        }
        Ok(())
    }

    /// Force per finger and violation from `trace.csv`, streamed (a long
    /// run's trace is large), binned by their largest value.
    fn read_trace(&mut self, dir: &Path, scene: &SceneInfo) -> Result<()> {
        let csv = Csv::read(dir, "trace.csv", "t_s,finger,target_x_m")?;
        let end = csv
            .rows
            .last()
            .map_or(0.0, |(l, f)| csv.number(*l, f, 0).unwrap_or(0.0));
        let width = (end / PLOT_BINS as f64).max(1e-9);
        let s = &mut self.series;
        s.t = (0..PLOT_BINS).map(|k| (k as f64 * width) as f32).collect();
        s.force = vec![vec![0.0; PLOT_BINS]; scene.fingers.len()];
        s.violation = vec![0.0; PLOT_BINS];
        let mut filled = vec![false; PLOT_BINS];
        for (line, fields) in &csv.rows {
            let t = csv.number(*line, fields, 0)?;
            let bin = ((t / width) as usize).min(PLOT_BINS - 1);
            filled[bin] = true;
            let Some(k) = scene.fingers.iter().position(|f| f.name == fields[1]) else {
                bail!(
                    "{}:{line}: finger `{}` is not in scene.json",
                    csv.file,
                    fields[1]
                );
            };
            let force = (8..11)
                .map(|c| csv.number(*line, fields, c).map(|x| x * x))
                .sum::<Result<f64>>()?
                .sqrt() as f32;
            let v = csv.number(*line, fields, 11)? as f32;
            s.force[k][bin] = s.force[k][bin].max(force);
            // NaN (a failed tick) stays visible: it wins the bin.
            if v.is_nan() || s.violation[bin].is_nan() {
                s.violation[bin] = f32::NAN;
            } else {
                s.violation[bin] = s.violation[bin].max(v);
            }
        }
        // A run with fewer ticks than bins leaves some bins without a
        // row: they hold the bin before (not a 0 that was never measured),
        // the ones before the first tick the first filled bin.
        let first = filled.iter().position(|f| *f).unwrap_or(0);
        for bin in (0..first).rev() {
            for f in &mut s.force {
                f[bin] = f[bin + 1];
            }
            s.violation[bin] = s.violation[bin + 1];
        }
        for bin in first + 1..PLOT_BINS {
            if !filled[bin] {
                for f in &mut s.force {
                    f[bin] = f[bin - 1];
                }
                s.violation[bin] = s.violation[bin - 1];
            }
        }
        Ok(())
    }
}

/// The semantic events of `summary.json` (constraint events and the
/// hand's), in time order.
fn events(dir: &Path) -> Result<Vec<EventData>> {
    let path = dir.join("summary.json");
    let v: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(&path).with_context(|| format!("reading {}", path.display()))?,
    )
    .with_context(|| format!("{}: not JSON", path.display()))?;
    let mut out = Vec::new();
    for key in ["events", "other_events"] {
        for e in v["semantic"][key].as_array().into_iter().flatten() {
            let s = |k: &str| e[k].as_str().unwrap_or("").to_owned();
            let (kind, a, b) = (s("kind"), s("binding_body"), s("offer_body"));
            out.push(EventData {
                t_s: e["t_s"].as_f64().unwrap_or(f64::NAN),
                text: if b.is_empty() {
                    format!("{kind} {a}")
                } else {
                    format!("{kind} {a} / {b}")
                },
                kind,
                body: a,
            });
        }
    }
    out.sort_by(|a, b| a.t_s.total_cmp(&b.t_s));
    Ok(out)
}
