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

use std::path::Path;
use std::time::Duration;

use nalgebra::Vector3;

use crate::error::TraceError;
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
        let mut times_s = Vec::new();
        let mut offsets_m = Vec::new();
        let mut header_seen = false;
        for (i, raw) in text.lines().enumerate() {
            let line_no = i + 1;
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
                        format!("expected header `t,dx,dy,dz`, found `{line}`"),
                    ));
                }
                header_seen = true;
                continue;
            }
            let mut vals = [0.0f64; 4];
            let mut n = 0;
            for (k, field) in line.split(',').enumerate() {
                if k >= 4 {
                    return Err(TraceError::parse(
                        source_name,
                        line_no,
                        format!("expected 4 columns, found more in `{line}`"),
                    ));
                }
                let f = field.trim();
                vals[k] = f.parse::<f64>().map_err(|_| {
                    TraceError::parse(
                        source_name,
                        line_no,
                        format!(
                            "column {} (`{}`): `{f}` is not a number",
                            k + 1,
                            ["t", "dx", "dy", "dz"][k]
                        ),
                    )
                })?;
                if !vals[k].is_finite() {
                    return Err(TraceError::parse(
                        source_name,
                        line_no,
                        format!("column {}: `{f}` is not finite", k + 1),
                    ));
                }
                n += 1;
            }
            if n != 4 {
                return Err(TraceError::parse(
                    source_name,
                    line_no,
                    format!("expected 4 columns, found {n} in `{line}`"),
                ));
            }
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
                text.lines().count().max(1),
                "hand trace has a header but no samples",
            ));
        }
        Ok(Self { times_s, offsets_m })
    }

    /// Reads and parses a CSV file.
    pub fn load(path: &Path) -> Result<Self, TraceError> {
        Self::parse(&TraceError::read(path)?, &path.display().to_string())
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.times_s.len()
    }

    /// Always false: a parsed trace has at least one sample.
    pub fn is_empty(&self) -> bool {
        self.times_s.is_empty()
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
