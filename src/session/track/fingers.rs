//! [`FingerTrack`]: each finger's device point, fingertip and rendered force
//! at 100 Hz of session time, taken by the reporter from the trace samples
//! it drains (the fast loop's own figures of those ticks: nothing is
//! recomputed, and the fast loop does no extra work for it).

use super::thinned::Thinned;
use crate::session::TraceSample;

/// One finger at one sampled tick, scene frame.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct FingerSample {
    /// The device's tip (the finger's target), m.
    pub device_m: [f64; 3],
    /// The finger's point on the mechanism (a contact finger's fingertip), m.
    pub tip_m: [f64; 3],
    /// The force the device rendered on the hand (after the safety layer
    /// and the device's limits), N.
    pub force_n: [f64; 3],
}

impl From<&TraceSample> for FingerSample {
    fn from(s: &TraceSample) -> Self {
        Self {
            device_m: s.target_m,
            tip_m: s.position_m,
            force_n: s.force_n,
        }
    }
}

/// Every finger's samples (see the module docs).
#[derive(Debug, Clone, Default)]
pub struct FingerTrack {
    /// Finger names, model order.
    pub names: Vec<String>,
    /// One entry per kept tick: every finger, model order.
    pub samples: Thinned<Vec<FingerSample>>,
    pending: Vec<FingerSample>,
    pending_t: Option<f64>,
}

impl FingerTrack {
    /// A track of the fingers `names`.
    pub fn new(names: &[String]) -> Self {
        Self {
            names: names.to_vec(),
            ..Self::default()
        }
    }

    /// Takes one trace sample (they come tick by tick, fingers in order).
    pub fn push(&mut self, s: &TraceSample) {
        if s.finger == 0 {
            self.pending.clear();
            self.pending_t = self.samples.wants(s.t_s).then_some(s.t_s);
        }
        if self.pending_t != Some(s.t_s) || usize::from(s.finger) != self.pending.len() {
            return;
        }
        self.pending.push(s.into());
        if self.pending.len() == self.names.len() {
            let row = std::mem::take(&mut self.pending);
            let bytes = std::mem::size_of::<Vec<FingerSample>>()
                + row.len() * std::mem::size_of::<FingerSample>();
            self.samples.offer(s.t_s, bytes, || row);
            self.pending_t = None;
        }
    }

    /// `fingers.csv`: `t_s,finger,device_{x,y,z}_m,tip_{x,y,z}_m,force_{x,y,z}_n`.
    pub fn csv(&self) -> String {
        let mut out = String::from(
            "t_s,finger,device_x_m,device_y_m,device_z_m,tip_x_m,tip_y_m,tip_z_m,force_x_n,force_y_n,force_z_n\n",
        );
        for (t, row) in self.samples.iter() {
            for (name, f) in self.names.iter().zip(row) {
                let (d, p, n) = (f.device_m, f.tip_m, f.force_n);
                out += &format!(
                    "{t:.6},{name},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e}\n",
                    d[0], d[1], d[2], p[0], p[1], p[2], n[0], n[1], n[2]
                );
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two fingers every 1 ms tick: kept every 10 ms, both fingers of the
    /// same tick in a row, the figures as the trace had them.
    #[test]
    fn fingers_are_kept_tick_by_tick_at_the_sample_period() {
        let names = vec!["a".to_string(), "b".to_string()];
        let mut t = FingerTrack::new(&names);
        for k in 0..100u32 {
            for f in 0..2u16 {
                t.push(&TraceSample {
                    t_s: f64::from(k + 1) * 1e-3,
                    finger: f,
                    target_m: [f64::from(k), f64::from(f), 0.0],
                    force_n: [0.0, 0.0, f64::from(k) * 0.1],
                    ..TraceSample::default()
                });
            }
        }
        // Ticks at 1, 2, … 100 ms: the first at or after each 10 ms slot
        // (1 ms, 10 ms, … 100 ms).
        assert_eq!(t.samples.len(), 11);
        for (time, row) in t.samples.iter() {
            assert_eq!(row.len(), 2);
            let k = (time * 1e3).round() - 1.0;
            assert_eq!(row[1].device_m, [k, 1.0, 0.0]);
            assert_eq!(row[0].force_n[2], k * 0.1);
        }
        assert_eq!(t.csv().lines().count(), 1 + 22);
    }
}
