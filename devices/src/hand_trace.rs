//! Recorded hand paths: CSV with header `t,dx,dy,dz` (seconds, metres),
//! linearly interpolated, held before the first and after the last sample.
//!
//! ```text
//! t,dx,dy,dz
//! 0.0,0.0,0.0,0.0
//! 0.5,0.01,0.0,0.0
//! ```
//!
//! Blank lines and lines starting with `#` are ignored. Times must be finite,
//! ≥ 0 and strictly increasing; every error names the file and the line.

use std::io::BufRead;
use std::path::Path;
use std::time::Duration;

use nalgebra::Vector3;

use crate::error::{TraceError, check_not_truncated, next_line, open_limited, quote};
use crate::hand::TargetSample;

/// A recorded hand path (offsets from the anchor). Setup-time type: parsing
/// allocates; [`HandTrace::sample`] does not.
#[derive(Debug, Clone, PartialEq)]
pub struct HandTrace {
    times_s: Vec<f64>,
    offsets_m: Vec<Vector3<f64>>,
}

impl HandTrace {
    /// A trace from (time, offset) points; times must be strictly increasing
    /// and the list non-empty.
    pub fn from_points(points: &[(Duration, Vector3<f64>)]) -> Result<Self, TraceError> {
        let mut text = String::from("t,dx,dy,dz\n");
        for (t, o) in points {
            text.push_str(&format!("{},{},{},{}\n", t.as_secs_f64(), o.x, o.y, o.z));
        }
        Self::parse(&text, "<points>")
    }

    /// Parses CSV text; `source_name` (usually the file path) labels errors.
    pub fn parse(text: &str, source_name: &str) -> Result<Self, TraceError> {
        Self::parse_from(&mut text.as_bytes(), source_name)
    }

    /// Parses CSV line by line from `reader` (at most
    /// [`MAX_HAND_SAMPLES`] samples); `source_name` labels errors.
    pub fn parse_from(reader: &mut impl BufRead, source_name: &str) -> Result<Self, TraceError> {
        let mut times_s = Vec::new();
        let mut offsets_m = Vec::new();
        let mut header_seen = false;
        let (mut bytes, mut raw) = (Vec::new(), String::new());
        let mut line_no = 0;
        loop {
            line_no += 1;
            if !next_line(reader, &mut bytes, &mut raw, source_name, line_no)? {
                break;
            }
            let line = raw.trim();
            if line.is_empty() || line.starts_with('#') {
                continue;
            }
            if !header_seen {
                let cols: Vec<&str> = line.split(',').map(str::trim).collect();
                if cols != ["t", "dx", "dy", "dz"] {
                    return Err(TraceError::parse(
                        source_name,
                        line_no,
                        format!("expected header `t,dx,dy,dz`, found `{}`", quote(line)),
                    ));
                }
                header_seen = true;
                continue;
            }
            if times_s.len() >= MAX_HAND_SAMPLES {
                return Err(TraceError::parse(
                    source_name,
                    line_no,
                    format!(
                        "more than {MAX_HAND_SAMPLES} samples: a hand trace holds at most that many"
                    ),
                ));
            }
            let vals =
                parse_sample(line).map_err(|m| TraceError::parse(source_name, line_no, m))?;
            if vals[0] < 0.0 {
                return Err(TraceError::parse(
                    source_name,
                    line_no,
                    format!("time {} is negative", vals[0]),
                ));
            }
            if let Some(&last) = times_s.last()
                && vals[0] <= last
            {
                return Err(TraceError::parse(
                    source_name,
                    line_no,
                    format!("time {} does not increase (previous {last})", vals[0]),
                ));
            }
            times_s.push(vals[0]);
            offsets_m.push(Vector3::new(vals[1], vals[2], vals[3]));
        }
        if !header_seen {
            return Err(TraceError::parse(
                source_name,
                1,
                "empty hand trace: expected header `t,dx,dy,dz`",
            ));
        }
        if times_s.is_empty() {
            return Err(TraceError::parse(
                source_name,
                (line_no - 1).max(1),
                "hand trace has a header but no samples",
            ));
        }
        Ok(Self { times_s, offsets_m })
    }

    /// Reads and parses a CSV file of at most [`MAX_HAND_TRACE_BYTES`],
    /// streaming.
    pub fn load(path: &Path) -> Result<Self, TraceError> {
        const WHAT: &str = "a hand trace";
        let mut reader = open_limited(path, WHAT, MAX_HAND_TRACE_BYTES)?;
        let parsed = Self::parse_from(&mut reader, &path.display().to_string());
        check_not_truncated(path, WHAT, MAX_HAND_TRACE_BYTES, reader.limit())?;
        parsed
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.times_s.len()
    }

    /// Always false: a parsed trace has at least one sample.
    pub fn is_empty(&self) -> bool {
        self.times_s.is_empty()
    }

    /// The samples, (time s, offset m), in time order.
    pub fn points(&self) -> impl Iterator<Item = (f64, Vector3<f64>)> + '_ {
        self.times_s
            .iter()
            .copied()
            .zip(self.offsets_m.iter().copied())
    }

    /// Offset and velocity at session time `t`.
    ///
    /// # Real-time
    /// No allocation; O(log n) bisection.
    pub fn sample(&self, t: Duration) -> TargetSample {
        self.sample_s(t.as_secs_f64())
    }

    pub(crate) fn sample_s(&self, t: f64) -> TargetSample {
        let n = self.times_s.len();
        let k = self.times_s.partition_point(|&ti| ti <= t);
        let zero = Vector3::zeros();
        if k == 0 {
            return TargetSample {
                offset_m: self.offsets_m[0],
                velocity_m_per_s: zero,
            };
        }
        if k >= n {
            return TargetSample {
                offset_m: self.offsets_m[n - 1],
                velocity_m_per_s: zero,
            };
        }
        let (t0, t1) = (self.times_s[k - 1], self.times_s[k]);
        let (p0, p1) = (self.offsets_m[k - 1], self.offsets_m[k]);
        let s = (t - t0) / (t1 - t0);
        TargetSample {
            offset_m: p0 + (p1 - p0) * s,
            velocity_m_per_s: (p1 - p0) / (t1 - t0),
        }
    }

    /// The same trace with every offset mapped by `f`.
    pub fn map_offsets(&self, f: impl Fn(Vector3<f64>) -> Vector3<f64>) -> Self {
        Self {
            times_s: self.times_s.clone(),
            offsets_m: self.offsets_m.iter().map(|o| f(*o)).collect(),
        }
    }
}

/// Largest hand-trace file [`HandTrace::load`] reads: 64 MiB.
pub const MAX_HAND_TRACE_BYTES: u64 = 64 << 20;
/// Most samples a hand trace may hold: 2²⁰ = 1 048 576 (17 minutes at
/// 1 kHz; 32 bytes each in memory).
pub const MAX_HAND_SAMPLES: usize = 1 << 20;

/// One `t,dx,dy,dz` line: four finite numbers.
fn parse_sample(line: &str) -> Result<[f64; 4], String> {
    let mut vals = [0.0f64; 4];
    let mut n = 0;
    for (k, field) in line.split(',').enumerate() {
        if k >= 4 {
            return Err(format!(
                "expected 4 columns, found more in `{}`",
                quote(line)
            ));
        }
        let f = field.trim();
        vals[k] = f.parse::<f64>().map_err(|_| {
            format!(
                "column {} (`{}`): `{}` is not a number",
                k + 1,
                ["t", "dx", "dy", "dz"][k],
                quote(f)
            )
        })?;
        if !vals[k].is_finite() {
            return Err(format!("column {}: `{}` is not finite", k + 1, quote(f)));
        }
        n += 1;
    }
    if n != 4 {
        return Err(format!(
            "expected 4 columns, found {n} in `{}`",
            quote(line)
        ));
    }
    Ok(vals)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn interpolates_and_holds() {
        let t = HandTrace::parse(
            "# a comment\nt,dx,dy,dz\n0,0,0,0\n1.0,0.01,0,0\n2.0,0.01,0.02,0\n",
            "h.csv",
        )
        .unwrap();
        assert_eq!(t.len(), 3);
        let s = t.sample(Duration::from_millis(500));
        assert!((s.offset_m - Vector3::new(0.005, 0.0, 0.0)).norm() < 1e-15);
        assert!((s.velocity_m_per_s - Vector3::new(0.01, 0.0, 0.0)).norm() < 1e-15);
        let end = t.sample(Duration::from_secs(9));
        assert_eq!(end.offset_m, Vector3::new(0.01, 0.02, 0.0));
        assert_eq!(end.velocity_m_per_s, Vector3::zeros());
    }

    #[test]
    fn errors_name_file_and_line() {
        let cases = [
            ("x,y\n", "h.csv:1: expected header"),
            (
                "t,dx,dy,dz\n0,0,0,0\n0.5,0,abc,0\n",
                "h.csv:3: column 3 (`dy`): `abc` is not a number",
            ),
            (
                "t,dx,dy,dz\n0,0,0,0\n0,1,0,0\n",
                "h.csv:3: time 0 does not increase",
            ),
            (
                "t,dx,dy,dz\n0,0,0\n",
                "h.csv:2: expected 4 columns, found 3",
            ),
            (
                "t,dx,dy,dz\n0,0,0,NaN\n",
                "h.csv:2: column 4: `NaN` is not finite",
            ),
            (
                "t,dx,dy,dz\n",
                "h.csv:1: hand trace has a header but no samples",
            ),
        ];
        for (text, want) in cases {
            let err = HandTrace::parse(text, "h.csv").unwrap_err().to_string();
            assert!(err.starts_with(want), "`{err}` should start with `{want}`");
        }
    }

    #[test]
    fn load_missing_file_names_it() {
        let err = HandTrace::load(Path::new("no/such/hand.csv"))
            .unwrap_err()
            .to_string();
        assert!(err.starts_with("no/such/hand.csv:"), "{err}");
    }
}
