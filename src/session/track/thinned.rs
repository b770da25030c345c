//! [`Thinned`]: samples kept at a fixed period of session time within a
//! memory budget. When the budget fills, every second sample is dropped and
//! the period doubles, so a session of any length keeps between half and
//! all of the budget, evenly spaced: the first [`budget_seconds`] of a run
//! at the full rate, then half of it, and so on.

/// Session time between two kept samples at the full rate: 10 ms (100 Hz,
/// smooth at any replay speed a person watches).
pub const SAMPLE_PERIOD_S: f64 = 0.01;

/// Bytes of samples a series keeps at most (each series: the bodies', the
/// fingers').
pub const BUDGET_BYTES: usize = 16 << 20;

/// Seconds of session a series with samples of `bytes_per_sample` keeps
/// at the full rate before its period first doubles.
pub fn budget_seconds(bytes_per_sample: usize) -> f64 {
    (BUDGET_BYTES / bytes_per_sample.max(1)) as f64 * SAMPLE_PERIOD_S
}

/// Samples of `T` with their session time (see the module docs).
#[derive(Debug, Clone)]
pub struct Thinned<T> {
    /// The kept samples, in time order: (session time s, sample, bytes).
    samples: Vec<(f64, T, usize)>,
    bytes: usize,
    period_s: f64,
    next_s: f64,
}

impl<T> Default for Thinned<T> {
    fn default() -> Self {
        Self {
            samples: Vec::new(),
            bytes: 0,
            period_s: SAMPLE_PERIOD_S,
            next_s: 0.0,
        }
    }
}

impl<T> Thinned<T> {
    /// True if a sample at `t_s` would be kept: its time has reached the
    /// next slot of the current period (offered samples may come at any
    /// rate; the first at or after each slot is kept).
    pub fn wants(&self, t_s: f64) -> bool {
        t_s >= self.next_s - 1e-9
    }

    /// Keeps `sample` (of about `bytes` bytes) at `t_s` if [`wants`](Self::wants)
    /// says so; thins the series first when the budget is full.
    pub fn offer(&mut self, t_s: f64, bytes: usize, sample: impl FnOnce() -> T) {
        if !self.wants(t_s) {
            return;
        }
        if self.bytes + bytes > BUDGET_BYTES && self.samples.len() >= 2 {
            self.period_s *= 2.0;
            let mut k = 0;
            let mut freed = 0;
            self.samples.retain(|s| {
                k += 1;
                let keep = k % 2 == 1;
                if !keep {
                    freed += s.2;
                }
                keep
            });
            self.bytes -= freed;
            let last = self.samples.last().map_or(0.0, |s| s.0);
            self.next_s = last + self.period_s;
            if !self.wants(t_s) {
                return;
            }
        }
        // The next slot is one period after this slot (not after this
        // sample), so a slightly late offer does not drift the grid.
        let slot = (t_s / self.period_s + 1e-9).floor() * self.period_s;
        self.next_s = slot + self.period_s;
        self.bytes += bytes;
        self.samples.push((t_s, sample(), bytes));
    }

    /// The kept samples: (session time s, sample).
    pub fn iter(&self) -> impl Iterator<Item = (f64, &T)> {
        self.samples.iter().map(|(t, s, _)| (*t, s))
    }

    /// Number of kept samples.
    pub fn len(&self) -> usize {
        self.samples.len()
    }

    /// True if nothing was kept.
    pub fn is_empty(&self) -> bool {
        self.samples.is_empty()
    }

    /// The newest kept sample.
    pub fn last(&self) -> Option<(f64, &T)> {
        self.samples.last().map(|(t, s, _)| (*t, s))
    }

    /// Session time between kept samples now, s.
    pub fn period_s(&self) -> f64 {
        self.period_s
    }

    /// Bytes kept.
    pub fn bytes(&self) -> usize {
        self.bytes
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Offered every 5 ms (the slow loop's period), kept every 10 ms; past
    /// the budget the series thins to even 20 ms spacing and stays bounded.
    #[test]
    fn a_long_series_keeps_the_full_rate_then_thins_evenly_within_its_budget() {
        let mut t: Thinned<u64> = Thinned::default();
        let bytes = 1 << 12;
        let full = budget_seconds(bytes);
        let mut k = 0u64;
        while (k as f64) * 0.005 < full * 0.9 {
            t.offer(k as f64 * 0.005, bytes, || k);
            k += 1;
        }
        let gaps: Vec<f64> = t
            .iter()
            .map(|s| s.0)
            .collect::<Vec<_>>()
            .windows(2)
            .map(|w| w[1] - w[0])
            .collect();
        assert!(
            gaps.iter().all(|g| (g - SAMPLE_PERIOD_S).abs() < 1e-9),
            "full rate: {:?}",
            &gaps[..4]
        );
        while (k as f64) * 0.005 < full * 3.0 {
            t.offer(k as f64 * 0.005, bytes, || k);
            k += 1;
        }
        assert!(
            t.bytes() <= BUDGET_BYTES && t.bytes() >= BUDGET_BYTES / 4,
            "{}",
            t.bytes()
        );
        assert!(t.period_s() > SAMPLE_PERIOD_S);
        let times: Vec<f64> = t.iter().map(|s| s.0).collect();
        let gaps: Vec<f64> = times.windows(2).map(|w| w[1] - w[0]).collect();
        let (lo, hi) = gaps
            .iter()
            .fold((f64::MAX, 0.0f64), |(a, b), g| (a.min(*g), b.max(*g)));
        // Even spacing except the newest samples, taken at the new period.
        assert!(
            hi <= t.period_s() + 1e-9 && lo >= SAMPLE_PERIOD_S * 2.0 - 1e-9,
            "{lo} {hi}"
        );
        assert_eq!(times[0], 0.0);
        assert!(times.last().unwrap() + t.period_s() + 0.005 >= (k - 1) as f64 * 0.005);
    }
}
