//! The reporter's side of the trace: drains the fast loop's lock-free queue of
//! [`TraceSample`]s into `trace.csv` (written as it goes) and into decimated
//! series for the plots; in scenes with design variables or objectives, each
//! row also gets the tick's design components and objective values
//! ([`DesignColumns`]). Runs off the real-time thread.

use super::design::DesignColumns;
use super::fast::TraceSample;
use super::live::FingerFrame;
use super::track::FingerTrack;
use anyhow::{Context, Result};
use crossbeam::queue::ArrayQueue;
use haptloop_devices::TraceStream;
use haptloop_rt::exchange::MailboxWriter;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// Most points kept per plotted series; beyond it every k-th sample is kept.
const MAX_POINTS: usize = 20_000;

/// One plotted series: (t, value).
#[derive(Debug, Clone, Default)]
pub struct Series {
    /// Points.
    pub points: Vec<(f64, f64)>,
    every: u64,
    seen: u64,
}

impl Series {
    fn with_budget(expected: u64) -> Self {
        Series {
            points: Vec::with_capacity(MAX_POINTS.min(expected as usize + 1)),
            every: (expected / MAX_POINTS as u64).max(1),
            seen: 0,
        }
    }

    fn push(&mut self, t: f64, v: f64) {
        if self.seen.is_multiple_of(self.every) && self.points.len() < MAX_POINTS * 2 {
            self.points.push((t, v));
        }
        self.seen += 1;
    }
}

/// The columns every `trace.csv` has. A failed tick (its solve failed and
/// zero force was commanded) has `failed` 1 and its position and violation
/// fields empty: they are not measurements. Target and force are (the
/// device's reading, and what its motors produced).
const TRACE_HEADER: &str = "t_s,finger,target_x_m,target_y_m,target_z_m,position_x_m,position_y_m,position_z_m,force_x_n,force_y_n,force_z_n,violation_m,failed";

/// Drains trace samples into a CSV file and plot series.
pub struct Recorder {
    /// The CSV being written (under `trace.csv.partial`) and its final path.
    csv: Option<(BufWriter<File>, PathBuf, PathBuf)>,
    /// The header is written with the first rows (design columns are known
    /// once the session is built).
    header_written: bool,
    /// The design trace (scenes with design variables or objectives).
    design: Option<DesignColumns>,
    /// Per design column (components, then objectives): value over time.
    pub design_series: Vec<Series>,
    /// Design column names, as in `trace.csv`.
    pub design_names: Vec<String>,
    /// How many of `design_series` are design components (the rest are
    /// objectives).
    pub design_variables: usize,
    /// How many of `design_series`, at the end, are joint torques.
    pub design_torques: usize,
    expected_ticks: u64,
    /// |force| per finger.
    pub force: Vec<Series>,
    /// Largest length-row violation per tick (from finger 0's rows).
    pub violation: Series,
    /// The newest sample per finger (for the status line).
    pub latest: Vec<TraceSample>,
    /// Samples drained.
    pub samples: u64,
    /// Device-trace streams being recorded (`--record`).
    device_traces: Vec<TraceStream>,
    /// Device-trace rows dropped because a queue was full (known at finish).
    pub device_trace_dropped: u64,
    /// Every finger's device point, fingertip and force at 100 Hz.
    pub fingers: FingerTrack,
    /// The live viewer's finger frame (`--live`).
    live: Option<MailboxWriter<FingerFrame>>,
}

impl Recorder {
    /// A recorder for `fingers` fingers over about `ticks` ticks, writing
    /// `trace.csv` into `dir` when given.
    pub fn new(fingers: &[String], ticks: u64, dir: Option<&Path>) -> Result<Self> {
        let csv = match dir {
            Some(d) => {
                let path = d.join("trace.csv");
                // Written under a temporary name and renamed when complete: a
                // crash never leaves a `trace.csv` with a cut-off last row.
                let partial = d.join("trace.csv.partial");
                let w = BufWriter::new(
                    File::create(&partial)
                        .with_context(|| format!("creating {}", partial.display()))?,
                );
                Some((w, partial, path))
            }
            None => None,
        };
        Ok(Recorder {
            csv,
            header_written: false,
            design: None,
            design_series: Vec::new(),
            design_names: Vec::new(),
            design_variables: 0,
            design_torques: 0,
            expected_ticks: ticks,
            force: fingers.iter().map(|_| Series::with_budget(ticks)).collect(),
            violation: Series::with_budget(ticks),
            latest: vec![TraceSample::default(); fingers.len()],
            samples: 0,
            device_traces: Vec::new(),
            device_trace_dropped: 0,
            fingers: FingerTrack::new(fingers),
            live: None,
        })
    }

    /// Publishes the newest figures of every finger to a live viewer after
    /// each [`drain`](Self::drain).
    pub(super) fn attach_live(&mut self, live: MailboxWriter<FingerFrame>) {
        self.live = Some(live);
    }

    /// Takes over the device-trace streams of a recording session; they are
    /// drained with every [`drain`](Self::drain).
    pub fn attach_device_traces(&mut self, streams: Vec<TraceStream>) {
        self.device_traces = streams;
    }

    /// Takes over the design trace of the session (before the first
    /// [`drain`](Self::drain)): `trace.csv` gains its columns.
    pub fn attach_design(&mut self, design: Option<DesignColumns>) -> Result<()> {
        if let Some(d) = &design {
            self.design_names = d.names.clone();
            self.design_variables = d.variables;
            self.design_torques = d.torques;
            self.design_series = d
                .names
                .iter()
                .map(|_| Series::with_budget(self.expected_ticks))
                .collect();
        }
        self.design = design;
        Ok(())
    }

    fn write_header(&mut self) -> Result<()> {
        if self.header_written {
            return Ok(());
        }
        self.header_written = true;
        if let Some((w, _, _)) = &mut self.csv {
            write!(w, "{TRACE_HEADER}")?;
            for n in &self.design_names {
                write!(w, ",{n}")?;
            }
            writeln!(w)?;
        }
        Ok(())
    }

    /// Moves every queued sample into the file and the series, and every
    /// queued device-trace row into its file.
    pub fn drain(&mut self, queue: &ArrayQueue<TraceSample>, names: &[String]) -> Result<()> {
        for t in &mut self.device_traces {
            t.drain()?;
        }
        self.write_header()?;
        while let Some(s) = queue.pop() {
            let i = usize::from(s.finger);
            let group = self.design.as_mut().and_then(|d| d.at(s.t_s));
            if let Some((w, _, _)) = &mut self.csv {
                let [tx, ty, tz] = s.target_m;
                let [px, py, pz] = s.position_m;
                let [fx, fy, fz] = s.force_n;
                write!(w, "{:.6},{},{tx:e},{ty:e},{tz:e},", s.t_s, names[i])?;
                if s.failed {
                    write!(w, ",,,{fx:e},{fy:e},{fz:e},,1")?;
                } else {
                    write!(
                        w,
                        "{px:e},{py:e},{pz:e},{fx:e},{fy:e},{fz:e},{:e},0",
                        s.violation_m
                    )?;
                }
                match group {
                    Some(g) => {
                        for v in g {
                            write!(w, ",{v:e}")?;
                        }
                    }
                    None => {
                        for _ in 0..self.design_names.len() {
                            write!(w, ",")?;
                        }
                    }
                }
                writeln!(w)?;
            }
            if i == 0
                && let Some(g) = group
            {
                for (series, &v) in self.design_series.iter_mut().zip(g) {
                    series.push(s.t_s, v);
                }
            }
            let f = s.force_n;
            self.force[i].push(s.t_s, (f[0] * f[0] + f[1] * f[1] + f[2] * f[2]).sqrt());
            if i == 0 && !s.failed {
                self.violation.push(s.t_s, s.violation_m);
            }
            self.fingers.push(&s);
            self.latest[i] = s;
            self.samples += 1;
        }
        if let Some(live) = &mut self.live {
            let latest = &self.latest;
            live.publish_with(|f| {
                f.t_s = latest.first().map_or(0.0, |s| s.t_s);
                f.fingers.clear();
                f.fingers
                    .extend(latest.iter().map(super::track::FingerSample::from));
            });
        }
        Ok(())
    }

    /// Flushes the CSV file and gives it its final name (`trace.csv`), and
    /// finishes every device trace.
    pub fn finish(&mut self) -> Result<()> {
        self.write_header()?;
        for t in std::mem::take(&mut self.device_traces) {
            self.device_trace_dropped += t.finish()?;
        }
        if let Some((mut w, partial, path)) = self.csv.take() {
            w.flush()
                .with_context(|| format!("writing {}", partial.display()))?;
            drop(w);
            std::fs::rename(&partial, &path)
                .with_context(|| format!("writing {}", path.display()))?;
        }
        Ok(())
    }
}
