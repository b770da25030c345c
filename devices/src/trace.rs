//! Device traces: record on the fast thread into a preallocated buffer, write
//! the file afterwards off the real-time thread, parse it back for replay.
//!
//! # File format (text, `haptloop-trace v1`)
//!
//! ```text
//! # haptloop-trace v1
//! # model: phantom-premium-1.5
//! # rate_hz: 1000
//! # units: t_ns = nanoseconds since session start; c0..c2 = encoder counts;
//! #   cmd_* = commanded force, N, device frame (before the safety layer);
//! #   out_* = force sent to the device, N, device frame (after it);
//! #   hand_* = hand target offset, m, device frame, from the tip's start
//! t_ns,c0,c1,c2,cmd_x,cmd_y,cmd_z,out_x,out_y,out_z,hand_x,hand_y,hand_z
//! 1000000,0,-3,2,0,-1.25,0,0,-0.00125,0,0,-0.005,0
//! ```
//!
//! Floats are written with Rust's shortest round-trip formatting, so parsing a
//! file gives back the recorded `f64` values bit for bit (NaN is written `NaN`).
//! The header lines are `# key: value`; `model` and `rate_hz` are required.

use std::io::Write;
use std::path::Path;
use std::time::Duration;

use nalgebra::Vector3;

use crate::device::ARM_JOINTS;
use crate::error::TraceError;

const MAGIC: &str = "# haptloop-trace v1";
const COLUMNS: &str = "t_ns,c0,c1,c2,cmd_x,cmd_y,cmd_z,out_x,out_y,out_z,hand_x,hand_y,hand_z";

/// Header of a trace.
#[derive(Debug, Clone, PartialEq)]
pub struct TraceHeader {
    /// Device model name (`phantom-premium-1.5`).
    pub model: String,
    /// Loop rate the trace was recorded at, ticks per second.
    pub rate_hz: u32,
}

/// One tick of a trace (`Copy`, fixed size).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TraceRow {
    /// Session time of the tick.
    pub time: Duration,
    /// Encoder counts read.
    pub counts: [i32; ARM_JOINTS],
    /// Force the loop commanded, newtons, device frame.
    pub command_n_device: Vector3<f64>,
    /// Force the safety layer sent to the device, newtons, device frame.
    pub output_n_device: Vector3<f64>,
    /// Hand target offset, metres, device frame.
    pub hand_offset_m_device: Vector3<f64>,
}

/// Records rows into a buffer allocated up front.
#[derive(Debug)]
pub struct TraceRecorder {
    header: TraceHeader,
    rows: Vec<TraceRow>,
    dropped: u64,
}

impl TraceRecorder {
    /// A recorder holding at most `capacity` rows (allocated now).
    pub fn with_capacity(header: TraceHeader, capacity: usize) -> Self {
        Self {
            header,
            rows: Vec::with_capacity(capacity),
            dropped: 0,
        }
    }

    /// Appends a row; when the buffer is full the row is dropped and counted.
    /// Returns whether the row was kept.
    ///
    /// # Real-time
    /// Never allocates (the buffer never grows), no I/O, O(1).
    pub fn record(&mut self, row: TraceRow) -> bool {
        if self.rows.len() < self.rows.capacity() {
            self.rows.push(row);
            true
        } else {
            self.dropped += 1;
            false
        }
    }

    /// Rows that did not fit.
    pub fn dropped(&self) -> u64 {
        self.dropped
    }

    /// Rows recorded so far.
    pub fn len(&self) -> usize {
        self.rows.len()
    }

    /// True when nothing was recorded.
    pub fn is_empty(&self) -> bool {
        self.rows.is_empty()
    }

    /// Ends recording (hand this to a non-real-time thread to write).
    pub fn finish(self) -> Trace {
        Trace {
            header: self.header,
            rows: self.rows,
            dropped: self.dropped,
        }
    }
}

/// A recorded trace.
#[derive(Debug, Clone, PartialEq)]
pub struct Trace {
    /// Header.
    pub header: TraceHeader,
    /// Rows in time order.
    pub rows: Vec<TraceRow>,
    /// Rows dropped while recording because the buffer was full.
    pub dropped: u64,
}

impl Trace {
    /// Writes the text format. Not for the real-time thread.
    pub fn write_to(&self, mut w: impl Write) -> Result<(), TraceError> {
        writeln!(w, "{MAGIC}")?;
        writeln!(w, "# model: {}", self.header.model)?;
        writeln!(w, "# rate_hz: {}", self.header.rate_hz)?;
        writeln!(w, "# dropped_rows: {}", self.dropped)?;
        writeln!(
            w,
            "# units: t_ns = nanoseconds since session start; c0..c2 = encoder counts;"
        )?;
        writeln!(
            w,
            "#   cmd_* = commanded force, N, device frame (before the safety layer);"
        )?;
        writeln!(
            w,
            "#   out_* = force sent to the device, N, device frame (after it);"
        )?;
        writeln!(
            w,
            "#   hand_* = hand target offset, m, device frame, from the tip's start"
        )?;
        writeln!(w, "{COLUMNS}")?;
        for r in &self.rows {
            let (c, f, o, h) = (
                r.counts,
                r.command_n_device,
                r.output_n_device,
                r.hand_offset_m_device,
            );
            writeln!(
                w,
                "{},{},{},{},{},{},{},{},{},{},{},{},{}",
                r.time.as_nanos(),
                c[0],
                c[1],
                c[2],
                f.x,
                f.y,
                f.z,
                o.x,
                o.y,
                o.z,
                h.x,
                h.y,
                h.z
            )?;
        }
        Ok(())
    }

    /// Writes the trace to `path`.
    pub fn save(&self, path: &Path) -> Result<(), TraceError> {
        let io = |source| TraceError::Io {
            path: path.to_owned(),
            source,
        };
        let file = std::fs::File::create(path).map_err(io)?;
        let mut w = std::io::BufWriter::new(file);
        self.write_to(&mut w)?;
        w.flush().map_err(io)
    }

    /// Reads a trace file.
    pub fn load(path: &Path) -> Result<Self, TraceError> {
        Self::parse(&TraceError::read(path)?, &path.display().to_string())
    }

    /// Parses the text format; `source_name` labels errors.
    pub fn parse(text: &str, source_name: &str) -> Result<Self, TraceError> {
        let err = |line: usize, msg: String| TraceError::parse(source_name, line, msg);
        let mut lines = text.lines().enumerate();
        match lines.next() {
            Some((_, l)) if l.trim() == MAGIC => {}
            Some((_, l)) => return Err(err(1, format!("expected `{MAGIC}`, found `{l}`"))),
            None => return Err(err(1, "empty file".into())),
        }
        let (mut model, mut rate_hz, mut dropped) = (None, None, 0u64);
        let mut rows = Vec::new();
        let mut columns_seen = false;
        for (i, raw) in lines {
            let (n, line) = (i + 1, raw.trim());
            if line.is_empty() {
                continue;
            }
            if let Some(meta) = line.strip_prefix('#') {
                if let Some((k, v)) = meta.split_once(':') {
                    let v = v.trim();
                    match k.trim() {
                        "model" => model = Some(v.to_owned()),
                        "rate_hz" => {
                            rate_hz = Some(v.parse::<u32>().map_err(|_| {
                                err(n, format!("rate_hz `{v}` is not a positive integer"))
                            })?)
                        }
                        "dropped_rows" => {
                            dropped = v.parse().map_err(|_| {
                                err(n, format!("dropped_rows `{v}` is not an integer"))
                            })?
                        }
                        _ => {}
                    }
                }
                continue;
            }
            if !columns_seen {
                if line != COLUMNS {
                    return Err(err(n, format!("expected column header `{COLUMNS}`")));
                }
                columns_seen = true;
                continue;
            }
            rows.push(parse_row(line).map_err(|m| err(n, m))?);
        }
        let model = model.ok_or_else(|| err(1, "header has no `# model:` line".into()))?;
        let rate_hz = rate_hz.ok_or_else(|| err(1, "header has no `# rate_hz:` line".into()))?;
        Ok(Self {
            header: TraceHeader { model, rate_hz },
            rows,
            dropped,
        })
    }
}

fn parse_row(line: &str) -> Result<TraceRow, String> {
    let fields: Vec<&str> = line.split(',').map(str::trim).collect();
    if fields.len() != 13 {
        return Err(format!("expected 13 columns, found {}", fields.len()));
    }
    let int = |k: usize| {
        fields[k]
            .parse::<i64>()
            .map_err(|_| format!("column {} `{}` is not an integer", k + 1, fields[k]))
    };
    let float = |k: usize| {
        fields[k]
            .parse::<f64>()
            .map_err(|_| format!("column {} `{}` is not a number", k + 1, fields[k]))
    };
    let t_ns = fields[0]
        .parse::<u64>()
        .map_err(|_| format!("t_ns `{}` is not a non-negative integer", fields[0]))?;
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
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(k: u64) -> TraceRow {
        TraceRow {
            time: Duration::from_millis(k),
            counts: [k as i32, -(k as i32), 7],
            command_n_device: Vector3::new(0.1 * k as f64, 1.0 / 3.0, f64::NAN),
            output_n_device: Vector3::new(-1e-300, 2.5, 0.0),
            hand_offset_m_device: Vector3::new(std::f64::consts::PI * 1e-3, 0.0, -0.0),
        }
    }

    #[test]
    fn text_round_trip_is_bit_exact_and_full_buffer_counts_drops() {
        let mut rec = TraceRecorder::with_capacity(
            TraceHeader {
                model: "phantom-omni".into(),
                rate_hz: 1000,
            },
            3,
        );
        for k in 0..5 {
            rec.record(row(k));
        }
        assert_eq!((rec.len(), rec.dropped()), (3, 2));
        let trace = rec.finish();
        let mut buf = Vec::new();
        trace.write_to(&mut buf).unwrap();
        let back = Trace::parse(std::str::from_utf8(&buf).unwrap(), "t.trace").unwrap();
        assert_eq!(back.header, trace.header);
        assert_eq!(back.dropped, 2);
        for (a, b) in trace.rows.iter().zip(&back.rows) {
            assert_eq!(a.time, b.time);
            assert_eq!(a.counts, b.counts);
            for (x, y) in a
                .command_n_device
                .iter()
                .chain(a.output_n_device.iter())
                .chain(a.hand_offset_m_device.iter())
                .zip(
                    b.command_n_device
                        .iter()
                        .chain(b.output_n_device.iter())
                        .chain(b.hand_offset_m_device.iter()),
                )
            {
                assert_eq!(x.to_bits(), y.to_bits(), "{x} vs {y}");
            }
        }
    }

    #[test]
    fn parse_errors_name_source_and_line() {
        let bad = format!("{MAGIC}\n# model: phantom-omni\n# rate_hz: 1000\n{COLUMNS}\n1,2,3\n");
        let e = Trace::parse(&bad, "x.trace").unwrap_err().to_string();
        assert!(e.starts_with("x.trace:5: expected 13 columns"), "{e}");
        let e = Trace::parse("hello\n", "x.trace").unwrap_err().to_string();
        assert!(
            e.starts_with("x.trace:1: expected `# haptloop-trace v1`"),
            "{e}"
        );
        let e = Trace::parse(&format!("{MAGIC}\n# rate_hz: 1000\n{COLUMNS}\n"), "x.trace")
            .unwrap_err()
            .to_string();
        assert!(e.contains("no `# model:`"), "{e}");
    }
}
