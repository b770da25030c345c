//! Latency histograms: HDR histograms allocated up front, recorded without
//! allocation, summarised as percentiles and exported as HdrHistogram's
//! percentile-distribution text (`.hgrm`) and as JSON.
//!
//! [`LatencyHistogram`] wraps `hdrhistogram::Histogram<u64>` over 1 ns … 10 s
//! with 3 significant digits and auto-resize **off**; values beyond 10 s are
//! clamped into the top bucket, but the exact maximum and minimum are kept
//! beside the histogram so the printed `max` is never a clamped value.
//!
//! # Real-time
//! [`LatencyHistogram::record`] allocates nothing, takes no lock, makes no
//! syscall and runs in bounded time (an index computation and two compares).
//! Everything else here (summaries, export, merging) belongs off the fast thread.

use hdrhistogram::Histogram;
use serde::{Deserialize, Serialize};
use std::fmt::Write as _;

/// The largest value tracked without clamping: 10 s in nanoseconds.
pub const HIGHEST_TRACKABLE_NS: u64 = 10_000_000_000;
/// Significant decimal digits kept by every latency histogram.
pub const SIGNIFICANT_DIGITS: u8 = 3;

/// A nanosecond latency histogram with exact min/max. See the [module docs](self).
#[derive(Debug, Clone)]
pub struct LatencyHistogram {
    hist: Histogram<u64>,
    min: u64,
    max: u64,
}

impl Default for LatencyHistogram {
    fn default() -> Self {
        Self::new()
    }
}

impl LatencyHistogram {
    /// Allocates an empty histogram (≈ 200 KiB) covering 1 ns … 10 s.
    pub fn new() -> Self {
        let mut hist = Histogram::new_with_bounds(1, HIGHEST_TRACKABLE_NS, SIGNIFICANT_DIGITS)
            .expect("constant bounds are valid");
        hist.auto(false);
        LatencyHistogram {
            hist,
            min: u64::MAX,
            max: 0,
        }
    }

    /// Records one value in nanoseconds.
    ///
    /// # Real-time
    /// No allocation (auto-resize is off; out-of-range values are clamped).
    #[inline]
    pub fn record(&mut self, ns: u64) {
        self.hist.saturating_record(ns);
        self.min = self.min.min(ns);
        self.max = self.max.max(ns);
    }

    /// Number of recorded values.
    pub fn count(&self) -> u64 {
        self.hist.len()
    }

    /// Exact largest recorded value (0 when empty).
    pub fn max(&self) -> u64 {
        self.max
    }

    /// Exact smallest recorded value (0 when empty).
    pub fn min(&self) -> u64 {
        if self.count() == 0 { 0 } else { self.min }
    }

    /// The value at quantile `q` in `[0, 1]` (0 when empty). Never above the
    /// exact maximum, so a clamped top bucket cannot inflate a percentile.
    pub fn quantile(&self, q: f64) -> u64 {
        if self.count() == 0 {
            return 0;
        }
        self.hist.value_at_quantile(q).min(self.max)
    }

    /// Clears all counts, keeping the allocation. Off the fast thread.
    pub fn reset(&mut self) {
        self.hist.reset();
        self.min = u64::MAX;
        self.max = 0;
    }

    /// Adds every count of `other` into `self`. Never allocates: both have the
    /// same bounds.
    pub fn add(&mut self, other: &LatencyHistogram) {
        self.hist
            .add(&other.hist)
            .expect("histograms with identical bounds always add");
        if other.count() > 0 {
            self.min = self.min.min(other.min);
            self.max = self.max.max(other.max);
        }
    }

    /// The underlying HDR histogram (for serialisation with hdrhistogram's
    /// `V2DeflateSerializer` or interval logs).
    pub fn inner(&self) -> &Histogram<u64> {
        &self.hist
    }

    /// Count, mean and the percentiles every report prints.
    pub fn summary(&self) -> Summary {
        Summary {
            count: self.count(),
            min: self.min(),
            mean: if self.count() == 0 {
                0.0
            } else {
                self.hist.mean()
            },
            p50: self.quantile(0.50),
            p90: self.quantile(0.90),
            p99: self.quantile(0.99),
            p999: self.quantile(0.999),
            p9999: self.quantile(0.9999),
            max: self.max(),
        }
    }

    /// HdrHistogram's percentile-distribution text, as Java's
    /// `outputPercentileDistribution(out, 5, scale)` prints it: the format the
    /// usual HdrHistogram plotters read (`.hgrm` files). Values are divided by
    /// `scale` (1000.0 prints microseconds).
    pub fn percentile_distribution(&self, scale: f64) -> String {
        let digits = usize::from(SIGNIFICANT_DIGITS);
        let mut out = String::new();
        let _ = write!(
            out,
            "{:>12} {:>14} {:>10} {:>14}\n\n",
            "Value", "Percentile", "TotalCount", "1/(1-Percentile)"
        );
        let mut total = 0u64;
        if self.count() > 0 {
            for v in self.hist.iter_quantiles(5) {
                total += v.count_since_last_iteration();
                let value = v.value_iterated_to().min(self.max) as f64 / scale;
                let q = v.quantile_iterated_to();
                if q < 1.0 {
                    let _ = writeln!(
                        out,
                        "{value:>12.digits$} {q:>2.12} {total:>10} {:>14.2}",
                        1.0 / (1.0 - q)
                    );
                } else {
                    let _ = writeln!(out, "{value:>12.digits$} {q:>2.12} {total:>10}");
                }
            }
        }
        let s = self.summary();
        let stdev = if self.count() == 0 {
            0.0
        } else {
            self.hist.stdev()
        };
        let _ = writeln!(
            out,
            "#[Mean    = {:>12.digits$}, StdDeviation   = {:>12.digits$}]",
            s.mean / scale,
            stdev / scale
        );
        let _ = writeln!(
            out,
            "#[Max     = {:>12.digits$}, Total count    = {:>12}]",
            s.max as f64 / scale,
            s.count
        );
        let _ = writeln!(
            out,
            "#[Buckets = {:>12}, SubBuckets     = {:>12}]",
            self.hist.buckets(),
            2 * 10u64.pow(u32::from(SIGNIFICANT_DIGITS)).next_power_of_two()
        );
        out
    }
}

/// Count, mean and percentiles of one histogram, in nanoseconds.
#[derive(Debug, Default, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Summary {
    /// Number of recorded values.
    pub count: u64,
    /// Exact minimum.
    pub min: u64,
    /// Mean.
    pub mean: f64,
    /// Median.
    pub p50: u64,
    /// 90th percentile.
    pub p90: u64,
    /// 99th percentile.
    pub p99: u64,
    /// 99.9th percentile.
    pub p999: u64,
    /// 99.99th percentile.
    pub p9999: u64,
    /// Exact maximum.
    pub max: u64,
}

impl Summary {
    /// One line in microseconds: `p50 … p99 … p99.9 … p99.99 … max …`.
    pub fn line_us(&self) -> String {
        let us = |ns: u64| ns as f64 / 1e3;
        format!(
            "p50 {:>8.1}  p99 {:>8.1}  p99.9 {:>8.1}  p99.99 {:>8.1}  max {:>9.1} µs",
            us(self.p50),
            us(self.p99),
            us(self.p999),
            us(self.p9999),
            us(self.max)
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn percentiles_of_a_uniform_ramp() {
        let mut h = LatencyHistogram::new();
        for v in 1..=10_000u64 {
            h.record(v * 1000);
        }
        let s = h.summary();
        assert_eq!(s.count, 10_000);
        assert_eq!(s.min, 1000);
        assert_eq!(s.max, 10_000_000);
        // 3 significant digits: each percentile within 0.1 % of the exact value.
        for (got, want) in [
            (s.p50, 5_000_000.0),
            (s.p99, 9_900_000.0),
            (s.p999, 9_990_000.0),
        ] {
            let rel = (got as f64 - want).abs() / want;
            assert!(rel < 1e-3, "got {got}, want {want}");
        }
        assert!((s.mean - 5_000_500.0).abs() / 5_000_500.0 < 1e-3);
    }

    #[test]
    fn values_beyond_range_clamp_but_max_is_exact() {
        let mut h = LatencyHistogram::new();
        h.record(0);
        h.record(25_000_000_000);
        assert_eq!(h.count(), 2);
        assert_eq!(h.max(), 25_000_000_000);
        assert_eq!(h.min(), 0);
        assert!(h.quantile(1.0) <= h.max());
    }

    #[test]
    fn add_and_reset() {
        let mut a = LatencyHistogram::new();
        let mut b = LatencyHistogram::new();
        a.record(10);
        b.record(1_000);
        b.record(5);
        a.add(&b);
        assert_eq!((a.count(), a.min(), a.max()), (3, 5, 1_000));
        a.reset();
        assert_eq!((a.count(), a.min(), a.max()), (0, 0, 0));
        assert_eq!(a.summary().p99, 0);
    }

    #[test]
    fn percentile_distribution_has_the_hgrm_shape() {
        let mut h = LatencyHistogram::new();
        for v in 1..=1000u64 {
            h.record(v * 1000);
        }
        let text = h.percentile_distribution(1000.0);
        let mut lines = text.lines();
        assert!(lines.next().unwrap().contains("1/(1-Percentile)"));
        assert_eq!(lines.next(), Some(""));
        let rows: Vec<&str> = text
            .lines()
            .skip(2)
            .filter(|l| !l.starts_with('#'))
            .collect();
        assert!(rows.len() > 20, "too few rows: {}", rows.len());
        // Total counts are non-decreasing and end at the histogram's count; the
        // last row (percentile 1.0) has no 1/(1-p) column.
        let mut last = 0u64;
        for r in &rows {
            let cols: Vec<&str> = r.split_whitespace().collect();
            let total: u64 = cols[2].parse().unwrap();
            assert!(total >= last);
            last = total;
        }
        assert_eq!(last, 1000);
        assert_eq!(rows.last().unwrap().split_whitespace().count(), 3);
        assert!(text.contains("#[Max     =     1000.000, Total count    =         1000]"));
    }
}
