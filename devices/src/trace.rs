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
//! back the recorded `f64` values bit for bit. Lines `# key: value` may appear
//! anywhere; `scene`, `model` and `rate_hz` are required, `model` and
//! `rate_hz` before the column names. Reading back checks every value
//! ([`Trace::parse_from`]): times are whole periods and increase strictly,
//! every number is finite and in range; a file is read streaming, at most
//! [`MAX_TRACE_BYTES`] and [`MAX_TRACE_ROWS`] rows (`trace_read.rs`).

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
pub use crate::trace_read::{MAX_COMMAND_N, MAX_TRACE_BYTES, MAX_TRACE_ROWS};

pub(crate) const MAGIC: &str = "# haptloop-trace v2";
pub(crate) const COLUMNS: &str =
    "t_ns,c0,c1,c2,cmd_x,cmd_y,cmd_z,out_x,out_y,out_z,hand_x,hand_y,hand_z,qw,qx,qy,qz";
/// Fields per row.
pub(crate) const FIELDS: usize = 17;

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
        let io = |source| TraceError::io(&partial, "write", source);
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
                write_row(w, &row).map_err(|source| TraceError::io(partial, "write", source))?;
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
            let io = |source| TraceError::io(&partial, "write", source);
            writeln!(w, "# dropped_rows: {dropped}").map_err(io)?;
            w.flush().map_err(io)?;
            drop(w);
            std::fs::rename(&partial, &path)
                .map_err(|source| TraceError::io(&path, "write", source))?;
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
        let io = |source| TraceError::io(path, "write", source);
        let file = std::fs::File::create(path).map_err(io)?;
        let mut w = std::io::BufWriter::new(file);
        self.write_to(&mut w)?;
        w.flush().map_err(io)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(k: u64) -> TraceRow {
        TraceRow {
            time: Duration::from_millis(k),
            counts: [k as i32, -(k as i32), 7],
            command_n_device: Vector3::new(0.1 * k as f64, 1.0 / 3.0, -7.25e4),
            output_n_device: Vector3::new(-1e-300, 2.5, 0.0),
            hand_offset_m_device: Vector3::new(std::f64::consts::PI * 1e-3, 0.0, -0.0),
            orientation_wxyz: [0.5, -0.5, 0.5, -0.5],
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
        let e = Trace::parse(
            &format!("{MAGIC}\n# model: phantom-omni\n# rate_hz: 1000\n{COLUMNS}\n"),
            "x.trace",
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("no `# scene:`"), "{e}");
        let row = |t: u64| format!("{t},0,0,0,0,0,0,0,0,0,0,0,0,1,0,0,0\n");
        let e = Trace::parse(
            &format!("{head}{}{}{}", row(0), row(2_000_000), row(1_000_000)),
            "x.trace",
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.starts_with("x.trace:8: t_ns 1000000 does not follow"),
            "{e}"
        );
    }

    /// Every value read back is checked, each refusal names the line and
    /// what is wrong; a binary line is quoted clipped, never whole.
    #[test]
    fn every_value_read_back_is_checked() {
        let head =
            format!("{MAGIC}\n# scene: s\n# model: phantom-omni\n# rate_hz: 1000\n{COLUMNS}\n");
        let good = "1000000,0,-3,2,0,-1.25,0,0,-0.5,0,0,-0.005,0,1,0,0,0";
        assert!(Trace::parse(&format!("{head}{good}\n"), "x.trace").is_ok());
        let field = |k: usize, v: &str| {
            let mut f: Vec<&str> = good.split(',').collect();
            f[k] = v;
            f.join(",")
        };
        let cases = [
            (field(4, "NaN"), "column 5 (`cmd_x`) is NaN"),
            (field(5, "inf"), "column 6 (`cmd_y`) is inf"),
            (field(6, "1e308"), "above 1e6 N"),
            (field(8, "5.0"), "above the phantom-omni's peak of 3.3 N"),
            (field(9, "-inf"), "column 10 (`out_z`) is -inf"),
            (field(11, "NaN"), "column 12 (`hand_y`) is NaN"),
            (field(13, "2"), "norm 2, not 1"),
            (field(2, "9000"), "more than half a turn"),
            (field(0, "1000001"), "not a whole number of periods"),
        ];
        for (row, want) in cases {
            let e = Trace::parse(&format!("{head}{row}\n"), "x.trace")
                .unwrap_err()
                .to_string();
            assert!(e.starts_with("x.trace:6: ") && e.contains(want), "{e}");
        }
        let binary = format!("{MAGIC}\n{}\n", "\u{1}x".repeat(100_000));
        let e = Trace::parse(&binary, "b.trace").unwrap_err().to_string();
        assert!(
            e.starts_with("b.trace:2: the line is longer than 4096 bytes"),
            "{e}"
        );
        assert!(e.len() < 400, "{} characters", e.len());
        let late = format!("{MAGIC}\n# scene: s\n{COLUMNS}\n# model: phantom-omni\n");
        let e = Trace::parse(&late, "x.trace").unwrap_err().to_string();
        assert!(e.starts_with("x.trace:3: the header must give"), "{e}");
    }
}
