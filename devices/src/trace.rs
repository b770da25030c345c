//! Device traces: record on the fast thread into a preallocated buffer, write
//! the file afterwards off the real-time thread, parse it back for replay.
//!
//! A session records by streaming: the fast thread pushes each row into a
//! bounded lock-free queue ([`TraceRecorder::streaming`]) and the reporting
//! thread drains it to the file as the run goes ([`TraceStream`]), so a long
//! or high-rate recording needs no memory for the whole run; when the disk
//! cannot keep up, the queue fills and rows are dropped and counted.
//!
//! # File format (text, `haptloop-trace v2`)
//!
//! ```text
//! # haptloop-trace v2
//! # scene: four-bar
//! # model: phantom-premium-1.5
//! # rate_hz: 1000
//! # units: t_ns = nanoseconds since session start; c0..c2 = encoder counts;
//! #   cmd_* = commanded force, N, device frame (before the safety layer);
//! #   out_* = force sent to the device, N, device frame (after it);
//! #   hand_* = hand target offset, m, device frame, from the tip's start;
//! #   q* = stylus orientation sensed by the gimbal (w, x, y, z), device frame
//! t_ns,c0,c1,c2,cmd_x,cmd_y,cmd_z,out_x,out_y,out_z,hand_x,hand_y,hand_z,qw,qx,qy,qz
//! 0,0,-3,2,0,0,0,0,0,0,0,0,0,1,0,0,0
//! 1000000,0,-3,2,0,-1.25,0,0,-0.00125,0,0,-0.005,0,1,0,0,0
//! # dropped_rows: 0
//! ```
//!
//! The row at t = 0 is the reading the device was registered with. Floats are
//! written with Rust's shortest round-trip formatting, so parsing a file gives
//! back the recorded `f64` values bit for bit (NaN is written `NaN`). Lines
//! `# key: value` may appear anywhere; `scene`, `model` and `rate_hz` are
//! required, times must increase strictly.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Duration;

use crossbeam::queue::ArrayQueue;

use nalgebra::Vector3;

use crate::device::ARM_JOINTS;
use crate::error::TraceError;

const MAGIC: &str = "# haptloop-trace v2";
const COLUMNS: &str =
    "t_ns,c0,c1,c2,cmd_x,cmd_y,cmd_z,out_x,out_y,out_z,hand_x,hand_y,hand_z,qw,qx,qy,qz";
/// Fields per row.
const FIELDS: usize = 17;

/// Header of a trace.
#[derive(Debug, Clone, PartialEq)]
pub struct TraceHeader {
    /// Scene the trace was recorded in.
    pub scene: String,
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
    /// Stylus orientation sensed by the gimbal, `[w, x, y, z]`, device frame.
    pub orientation_wxyz: [f64; 4],
}

/// Records rows on the fast thread: into a buffer allocated up front
/// ([`with_capacity`](Self::with_capacity)), or into a bounded queue that a
/// [`TraceStream`] drains to a file ([`streaming`](Self::streaming)).
#[derive(Debug)]
pub struct TraceRecorder {
    header: TraceHeader,
    sink: Sink,
    dropped: u64,
}

#[derive(Debug)]
enum Sink {
    Buffer(Vec<TraceRow>),
    Stream(Arc<TraceQueue>),
}

/// The queue between a streaming recorder and its [`TraceStream`].
#[derive(Debug)]
struct TraceQueue {
    rows: ArrayQueue<TraceRow>,
    dropped: AtomicU64,
}

impl TraceRecorder {
    /// A recorder holding at most `capacity` rows (allocated now).
    pub fn with_capacity(header: TraceHeader, capacity: usize) -> Self {
        Self {
            header,
            sink: Sink::Buffer(Vec::with_capacity(capacity)),
            dropped: 0,
        }
    }

    /// A recorder that pushes rows into a queue of `capacity` rows, and the
    /// stream that drains it (on another thread).
    pub fn streaming(header: TraceHeader, capacity: usize) -> (Self, TraceStream) {
        let queue = Arc::new(TraceQueue {
            rows: ArrayQueue::new(capacity.max(1)),
            dropped: AtomicU64::new(0),
        });
        let stream = TraceStream {
            queue: queue.clone(),
            header: header.clone(),
            file: None,
            written: 0,
        };
        let rec = Self {
            header,
            sink: Sink::Stream(queue),
            dropped: 0,
        };
        (rec, stream)
    }

    /// Appends a row; when the buffer or queue is full the row is dropped and
    /// counted. Returns whether the row was kept.
    ///
    /// # Real-time
    /// Never allocates (the buffer never grows; the queue is a fixed ring), no
    /// lock, no I/O, O(1).
    pub fn record(&mut self, row: TraceRow) -> bool {
        let kept = match &mut self.sink {
            Sink::Buffer(rows) if rows.len() < rows.capacity() => {
                rows.push(row);
                true
            }
            Sink::Buffer(_) => false,
            Sink::Stream(q) => {
                let kept = q.rows.push(row).is_ok();
                if !kept {
                    q.dropped.fetch_add(1, Ordering::Relaxed);
                }
                kept
            }
        };
        if !kept {
            self.dropped += 1;
        }
        kept
    }

    /// Rows that did not fit.
    pub fn dropped(&self) -> u64 {
        self.dropped
    }

    /// Rows held in the buffer (0 when streaming).
    pub fn len(&self) -> usize {
        match &self.sink {
            Sink::Buffer(rows) => rows.len(),
            Sink::Stream(_) => 0,
        }
    }

    /// True when nothing is held in the buffer.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Ends buffered recording (hand this to a non-real-time thread to
    /// write). A streaming recorder's rows are in its stream: the trace
    /// returned holds none.
    pub fn finish(self) -> Trace {
        let rows = match self.sink {
            Sink::Buffer(rows) => rows,
            Sink::Stream(_) => Vec::new(),
        };
        Trace {
            header: self.header,
            rows,
            dropped: self.dropped,
        }
    }
}

/// The draining end of a streaming [`TraceRecorder`]: writes rows to a file
/// as they arrive. Not for the real-time thread.
#[derive(Debug)]
pub struct TraceStream {
    queue: Arc<TraceQueue>,
    header: TraceHeader,
    /// The open file (under `<name>.partial`) and its final path.
    file: Option<(BufWriter<File>, PathBuf, PathBuf)>,
    written: u64,
}

impl TraceStream {
    /// Starts the file at `path` (written as `<path>.partial` and renamed by
    /// [`finish`](Self::finish), so a crash never leaves a half trace under
    /// the real name) and writes the header.
    pub fn create(mut self, path: &Path) -> Result<Self, TraceError> {
        let mut name = path.file_name().unwrap_or_default().to_os_string();
        name.push(".partial");
        let partial = path.with_file_name(name);
        let io = |source| TraceError::Io {
            path: partial.clone(),
            source,
        };
        let mut w = BufWriter::new(File::create(&partial).map_err(io)?);
        write_header(&mut w, &self.header).map_err(io)?;
        self.file = Some((w, partial, path.to_owned()));
        Ok(self)
    }

    /// Writes every row queued so far; returns how many.
    pub fn drain(&mut self) -> Result<u64, TraceError> {
        let mut n = 0;
        while let Some(row) = self.queue.rows.pop() {
            if let Some((w, partial, _)) = &mut self.file {
                write_row(w, &row).map_err(|source| TraceError::Io {
                    path: partial.clone(),
                    source,
                })?;
            }
            n += 1;
        }
        self.written += n;
        Ok(n)
    }

    /// Rows written so far.
    pub fn written(&self) -> u64 {
        self.written
    }

    /// Rows the recorder dropped because the queue was full.
    pub fn dropped(&self) -> u64 {
        self.queue.dropped.load(Ordering::Relaxed)
    }

    /// Drains the rest, writes the dropped-row count, flushes and gives the
    /// file its final name. Returns the rows dropped.
    pub fn finish(mut self) -> Result<u64, TraceError> {
        self.drain()?;
        let dropped = self.dropped();
        if let Some((mut w, partial, path)) = self.file.take() {
            let io = |source| TraceError::Io {
                path: partial.clone(),
                source,
            };
            writeln!(w, "# dropped_rows: {dropped}").map_err(io)?;
            w.flush().map_err(io)?;
            drop(w);
            std::fs::rename(&partial, &path).map_err(|source| TraceError::Io {
                path: path.clone(),
                source,
            })?;
        }
        Ok(dropped)
    }
}

fn write_header(w: &mut impl Write, h: &TraceHeader) -> std::io::Result<()> {
    writeln!(w, "{MAGIC}")?;
    writeln!(w, "# scene: {}", h.scene)?;
    writeln!(w, "# model: {}", h.model)?;
    writeln!(w, "# rate_hz: {}", h.rate_hz)?;
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
        "#   hand_* = hand target offset, m, device frame, from the tip's start;"
    )?;
    writeln!(
        w,
        "#   q* = stylus orientation sensed by the gimbal (w, x, y, z), device frame"
    )?;
    writeln!(w, "{COLUMNS}")
}

fn write_row(w: &mut impl Write, r: &TraceRow) -> std::io::Result<()> {
    let (c, f, o, h, q) = (
        r.counts,
        r.command_n_device,
        r.output_n_device,
        r.hand_offset_m_device,
        r.orientation_wxyz,
    );
    writeln!(
        w,
        "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
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
        h.z,
        q[0],
        q[1],
        q[2],
        q[3]
    )
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
        write_header(&mut w, &self.header)?;
        for r in &self.rows {
            write_row(&mut w, r)?;
        }
        writeln!(w, "# dropped_rows: {}", self.dropped)?;
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
        let (mut scene, mut model, mut rate_hz, mut dropped) = (None, None, None, 0u64);
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
                        "scene" => scene = Some(v.to_owned()),
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
            let row = parse_row(line).map_err(|m| err(n, m))?;
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
        Ok(Self {
            header: TraceHeader {
                scene,
                model,
                rate_hz,
            },
            rows,
            dropped,
        })
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
        orientation_wxyz: [float(13)?, float(14)?, float(15)?, float(16)?],
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
            orientation_wxyz: [0.5, -0.5, 0.5, 1.0 / 3.0],
        }
    }

    #[test]
    fn text_round_trip_is_bit_exact_and_full_buffer_counts_drops() {
        let mut rec = TraceRecorder::with_capacity(
            TraceHeader {
                scene: "four-bar".into(),
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
        let head =
            format!("{MAGIC}\n# scene: s\n# model: phantom-omni\n# rate_hz: 1000\n{COLUMNS}\n");
        let e = Trace::parse(&format!("{head}1,2,3\n"), "x.trace")
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("x.trace:6: expected 17 columns"), "{e}");
        let e = Trace::parse("hello\n", "x.trace").unwrap_err().to_string();
        assert!(
            e.starts_with("x.trace:1: expected `# haptloop-trace v2`"),
            "{e}"
        );
        let e = Trace::parse(&format!("{MAGIC}\n# rate_hz: 1000\n{COLUMNS}\n"), "x.trace")
            .unwrap_err()
            .to_string();
        assert!(e.contains("no `# scene:`"), "{e}");
        let row = |t: u64| format!("{t},0,0,0,0,0,0,0,0,0,0,0,0,1,0,0,0\n");
        let e = Trace::parse(&format!("{head}{}{}{}", row(0), row(2), row(1)), "x.trace")
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("x.trace:8: t_ns 1 does not follow"), "{e}");
    }
}
