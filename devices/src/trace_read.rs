//! Reading a device trace back ([`Trace::load`], [`Trace::parse_from`]):
//! streaming, line by line, within [`MAX_TRACE_BYTES`] and
//! [`MAX_TRACE_ROWS`], and every value checked against the device model and
//! rate the header names (the format is in [`crate::trace`]).

use std::io::BufRead;
use std::path::Path;
use std::time::Duration;

use nalgebra::Vector3;

use crate::device::DeviceInfo;
use crate::error::{TraceError, check_not_truncated, next_line, open_limited, quote};
use crate::phantom::PhantomModel;
use crate::trace::{COLUMNS, FIELDS, MAGIC, Trace, TraceHeader, TraceRow};
use crate::virtual_device::{VIRTUAL_MODEL, VirtualParams};

impl Trace {
    /// Reads a trace file of at most [`MAX_TRACE_BYTES`], streaming (the
    /// text is never held whole); see [`Trace::parse`] for what is checked.
    pub fn load(path: &Path) -> Result<Self, TraceError> {
        const WHAT: &str = "a device trace";
        let mut reader = open_limited(path, WHAT, MAX_TRACE_BYTES)?;
        let parsed = Self::parse_from(&mut reader, &path.display().to_string());
        // A file cut at the limit fails to parse on its last line: the size
        // is the reason, not that line.
        check_not_truncated(path, WHAT, MAX_TRACE_BYTES, reader.limit())?;
        parsed
    }

    /// Parses the text format; `source_name` labels errors.
    pub fn parse(text: &str, source_name: &str) -> Result<Self, TraceError> {
        Self::parse_from(&mut text.as_bytes(), source_name)
    }

    /// Parses the text format line by line from `reader`. Every value read
    /// back is checked: the header (`scene`, `model` of a known device,
    /// `rate_hz` > 0) comes before the column names; times are whole
    /// periods of the rate and increase; counts are within half a turn;
    /// every force, offset and orientation component is finite; a command
    /// is at most [`MAX_COMMAND_N`], a force sent to the device at most the
    /// model's peak force (the safety layer's clamp), the orientation a unit
    /// quaternion; at most [`MAX_TRACE_ROWS`] rows.
    pub fn parse_from(reader: &mut impl BufRead, source_name: &str) -> Result<Self, TraceError> {
        let err = |line: usize, msg: String| TraceError::parse(source_name, line, msg);
        let (mut bytes, mut line) = (Vec::new(), String::new());
        let mut n = 1;
        if !next_line(reader, &mut bytes, &mut line, source_name, n)? {
            return Err(err(1, "empty file".into()));
        }
        if line.trim() != MAGIC {
            return Err(err(
                1,
                format!("expected `{MAGIC}`, found `{}`", quote(&line)),
            ));
        }
        let (mut scene, mut model, mut rate_hz, mut dropped) = (None, None, None, 0u64);
        let mut rows: Vec<TraceRow> = Vec::new();
        let mut check: Option<RowCheck> = None;
        loop {
            n += 1;
            if !next_line(reader, &mut bytes, &mut line, source_name, n)? {
                break;
            }
            let line = line.trim();
            if line.is_empty() {
                continue;
            }
            if let Some(meta) = line.strip_prefix('#') {
                if let Some((k, v)) = meta.split_once(':') {
                    let v = v.trim();
                    match k.trim() {
                        "scene" => scene = Some(v.to_owned()),
                        "model" => {
                            let m = model_info(v).map_err(|e| err(n, e))?;
                            model = Some((v.to_owned(), m));
                        }
                        "rate_hz" => {
                            rate_hz =
                                Some(v.parse::<u32>().ok().filter(|r| *r > 0).ok_or_else(|| {
                                    err(
                                        n,
                                        format!("rate_hz `{}` is not a positive integer", quote(v)),
                                    )
                                })?)
                        }
                        "dropped_rows" => {
                            dropped = v.parse().map_err(|_| {
                                err(n, format!("dropped_rows `{}` is not an integer", quote(v)))
                            })?
                        }
                        _ => {}
                    }
                }
                continue;
            }
            if check.is_none() {
                if line != COLUMNS {
                    return Err(err(
                        n,
                        format!(
                            "expected column header `{COLUMNS}`, found `{}`",
                            quote(line)
                        ),
                    ));
                }
                let (Some((_, m)), Some(r)) = (&model, rate_hz) else {
                    return Err(err(
                        n,
                        "the header must give `# model:` and `# rate_hz:` before the column names"
                            .into(),
                    ));
                };
                check = Some(RowCheck::new(*m, r));
                continue;
            }
            let Some(c) = check.as_ref() else { continue };
            if rows.len() >= MAX_TRACE_ROWS {
                return Err(err(
                    n,
                    format!(
                        "more than {MAX_TRACE_ROWS} rows: a device trace holds at most that many"
                    ),
                ));
            }
            let row = parse_row(line).and_then(|r| c.check(&r).map(|()| r));
            let row = row.map_err(|m| err(n, m))?;
            if let Some(last) = rows.last().map(|r: &TraceRow| r.time)
                && row.time <= last
            {
                return Err(err(
                    n,
                    format!(
                        "t_ns {} does not follow the previous row's {}: times must increase",
                        row.time.as_nanos(),
                        last.as_nanos()
                    ),
                ));
            }
            rows.push(row);
        }
        let scene = scene.ok_or_else(|| err(1, "header has no `# scene:` line".into()))?;
        let model = model.ok_or_else(|| err(1, "header has no `# model:` line".into()))?;
        let rate_hz = rate_hz.ok_or_else(|| err(1, "header has no `# rate_hz:` line".into()))?;
        if check.is_none() {
            return Err(err(n, format!("no column header `{COLUMNS}`")));
        }
        Ok(Self {
            header: TraceHeader {
                scene,
                model: model.0,
                rate_hz,
            },
            rows,
            dropped,
        })
    }
}

/// Largest device-trace file [`Trace::load`] reads: 512 MiB.
pub const MAX_TRACE_BYTES: u64 = 512 << 20;
/// Most rows a device trace may hold: 2²¹ = 2 097 152, 35 minutes at 1 kHz
/// (held in memory for the replay: 136 bytes each, 285 MB at most).
pub const MAX_TRACE_ROWS: usize = 1 << 21;
/// Largest force command a trace row may hold, N: no haptic command comes
/// near it (the safety layer clamps to a few newtons), so a larger one means
/// the file is not a recording.
pub const MAX_COMMAND_N: f64 = 1e6;

/// The description of a trace's `model`: a PHANToM, or `virtual` (whose
/// counts are the tip's micrometres, within its notional half turn).
fn model_info(name: &str) -> Result<DeviceInfo, String> {
    if name == VIRTUAL_MODEL {
        return Ok(VirtualParams::default().info());
    }
    PhantomModel::by_name(name)
        .map(PhantomModel::info)
        .map_err(|e| format!("{e} (or `{VIRTUAL_MODEL}`)"))
}

/// What every row of a trace of one model at one rate must satisfy.
struct RowCheck {
    model: DeviceInfo,
    period_ns: u64,
}

impl RowCheck {
    fn new(model: DeviceInfo, rate_hz: u32) -> Self {
        Self {
            model,
            period_ns: 1_000_000_000 / u64::from(rate_hz),
        }
    }

    fn check(&self, r: &TraceRow) -> Result<(), String> {
        let t = r.time.as_nanos() as u64;
        if !t.is_multiple_of(self.period_ns) {
            return Err(format!(
                "t_ns {t} is not a whole number of periods ({} ns at this trace's rate_hz)",
                self.period_ns
            ));
        }
        let half_turn = |j: usize| i64::from(self.model.counts_per_rev[j] / 2);
        if let Some(j) = (0..3).find(|&j| i64::from(r.counts[j]).abs() > half_turn(j)) {
            return Err(format!(
                "c{j} = {} is more than half a turn ({} counts of the {})",
                r.counts[j],
                half_turn(j),
                self.model.model
            ));
        }
        let columns = COLUMNS.split(',').collect::<Vec<_>>();
        let named = |k: usize| format!("column {} (`{}`)", k + 1, columns[k]);
        let values = [
            (4, r.command_n_device),
            (7, r.output_n_device),
            (10, r.hand_offset_m_device),
        ];
        for (k0, v) in values {
            if let Some(i) = (0..3).find(|&i| !v[i].is_finite()) {
                return Err(format!(
                    "{} is {}: every value must be finite",
                    named(k0 + i),
                    v[i]
                ));
            }
        }
        let q = r.orientation_wxyz;
        if let Some(i) = (0..4).find(|&i| !q[i].is_finite()) {
            return Err(format!(
                "{} is {}: every value must be finite",
                named(13 + i),
                q[i]
            ));
        }
        let cmd = r.command_n_device.norm();
        if cmd > MAX_COMMAND_N {
            return Err(format!(
                "the command cmd_* has magnitude {cmd:e} N, above {MAX_COMMAND_N:e} N: not a recorded command"
            ));
        }
        let out = r.output_n_device.norm();
        let peak = self.model.limits.peak_force_n;
        if out > peak * (1.0 + 1e-9) {
            return Err(format!(
                "the force sent out_* has magnitude {out} N, above the {}'s peak of {peak} N \
                 (the safety layer clamps to it)",
                self.model.model
            ));
        }
        let norm = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]).sqrt();
        if (norm - 1.0).abs() > 1e-6 {
            return Err(format!(
                "the orientation qw..qz has norm {norm}, not 1: not a rotation"
            ));
        }
        Ok(())
    }
}

fn parse_row(line: &str) -> Result<TraceRow, String> {
    let fields: Vec<&str> = line.split(',').map(str::trim).collect();
    if fields.len() != FIELDS {
        return Err(format!("expected {FIELDS} columns, found {}", fields.len()));
    }
    let int = |k: usize| {
        fields[k]
            .parse::<i64>()
            .map_err(|_| format!("column {} `{}` is not an integer", k + 1, quote(fields[k])))
    };
    let float = |k: usize| {
        fields[k]
            .parse::<f64>()
            .map_err(|_| format!("column {} `{}` is not a number", k + 1, quote(fields[k])))
    };
    let t_ns = fields[0]
        .parse::<u64>()
        .map_err(|_| format!("t_ns `{}` is not a non-negative integer", quote(fields[0])))?;
    let count = |k: usize| {
        int(k).and_then(|v| i32::try_from(v).map_err(|_| format!("count `{v}` out of range")))
    };
    let vec3 = |k: usize| -> Result<Vector3<f64>, String> {
        Ok(Vector3::new(float(k)?, float(k + 1)?, float(k + 2)?))
    };
    Ok(TraceRow {
        time: Duration::from_nanos(t_ns),
        counts: [count(1)?, count(2)?, count(3)?],
        command_n_device: vec3(4)?,
        output_n_device: vec3(7)?,
        hand_offset_m_device: vec3(10)?,
        orientation_wxyz: [float(13)?, float(14)?, float(15)?, float(16)?],
    })
}
