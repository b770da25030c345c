//! Windowed tip-speed estimate for the velocity limit.
//!
//! Speed = |p_now − p_then| / (t_now − t_then) with `then` the oldest sample
//! inside the window (a windowed difference like CHAI3D's and DHD's, which keeps
//! one-count quantisation steps from reading as large speeds).
//!
//! # Real-time
//! A fixed ring of [`VelocityEstimator::CAPACITY`] samples: no allocation;
//! `push` is O(1), `speed` is O(CAPACITY) in the worst case.

use std::time::Duration;

use nalgebra::Vector3;

/// Ring buffer of recent tip positions.
#[derive(Debug, Clone)]
pub struct VelocityEstimator {
    times_ns: [u64; Self::CAPACITY],
    positions: [Vector3<f64>; Self::CAPACITY],
    head: usize,
    len: usize,
    window_ns: u64,
}

impl VelocityEstimator {
    /// Samples kept (a 10 ms window at up to 12.8 kHz).
    pub const CAPACITY: usize = 128;

    /// An empty estimator with the given window.
    pub fn new(window: Duration) -> Self {
        Self {
            times_ns: [0; Self::CAPACITY],
            positions: [Vector3::zeros(); Self::CAPACITY],
            head: 0,
            len: 0,
            window_ns: window.as_nanos() as u64,
        }
    }

    /// Forgets all samples.
    pub fn clear(&mut self) {
        self.len = 0;
    }

    /// Adds a sample at `t`.
    pub fn push(&mut self, t: Duration, p: Vector3<f64>) {
        self.head = (self.head + 1) % Self::CAPACITY;
        self.times_ns[self.head] = t.as_nanos() as u64;
        self.positions[self.head] = p;
        self.len = (self.len + 1).min(Self::CAPACITY);
    }

    /// Estimated speed, m/s (0 with fewer than two samples).
    pub fn speed(&self) -> f64 {
        if self.len < 2 {
            return 0.0;
        }
        let t_now = self.times_ns[self.head];
        let mut oldest = self.head;
        for k in 1..self.len {
            let i = (self.head + Self::CAPACITY - k) % Self::CAPACITY;
            if t_now - self.times_ns[i] > self.window_ns {
                break;
            }
            oldest = i;
        }
        if oldest == self.head {
            // Window shorter than one period: use the previous sample.
            oldest = (self.head + Self::CAPACITY - 1) % Self::CAPACITY;
        }
        let dt = (t_now - self.times_ns[oldest]) as f64 * 1e-9;
        if dt <= 0.0 {
            0.0
        } else {
            (self.positions[self.head] - self.positions[oldest]).norm() / dt
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn constant_speed_is_recovered_over_the_window() {
        let mut v = VelocityEstimator::new(Duration::from_millis(10));
        for k in 0..50u64 {
            v.push(
                Duration::from_millis(k),
                Vector3::new(0.3 * k as f64 * 1e-3, 0.0, 0.4 * k as f64 * 1e-3),
            );
        }
        assert!((v.speed() - 0.5).abs() < 1e-9, "{}", v.speed());
    }
}
