//! The poses of a scene's shaped bodies over a session, sampled by the slow
//! loop from the fast loop's snapshots, for `bodies.csv` and the scene plot.
//!
//! Memory is bounded whatever the session's length: when the buffer holds
//! [`MAX_SAMPLES`] samples, every second one is dropped and the sampling
//! stride doubles, so a session keeps between half and all of
//! `MAX_SAMPLES`, evenly spaced.

use haptloop_solver::geometry::{Pose3, Shape};
use nalgebra::{Quaternion, UnitQuaternion};

/// Most samples kept.
pub const MAX_SAMPLES: usize = 4096;

/// One sample: session time and one pose per tracked body.
#[derive(Debug, Clone)]
pub struct TrackSample {
    /// Session time of the snapshot, s.
    pub t_s: f64,
    /// World position (m) and unit quaternion `[w, x, y, z]` per tracked
    /// body, in [`BodyTrack::bodies`] order.
    pub poses: Vec<([f64; 3], [f64; 4])>,
}

/// Sampled poses of the shaped bodies (see the module docs).
#[derive(Debug, Clone, Default)]
pub struct BodyTrack {
    /// Model indices and names of the tracked bodies (moving, with a shape).
    pub bodies: Vec<(u32, String)>,
    /// The shape of each tracked body, same order.
    pub shapes: Vec<Shape>,
    /// Fixed shaped bodies: name, shape, pose (they never move).
    pub fixed: Vec<(String, Shape, Pose3)>,
    /// Indices into `bodies` of contact fingertips.
    pub fingertips: Vec<usize>,
    /// The samples, in time order.
    pub samples: Vec<TrackSample>,
    stride: u64,
    offered: u64,
}

impl BodyTrack {
    /// Tracks the shaped bodies of `model` (moving ones sampled, fixed ones
    /// kept at their pose).
    pub fn of_model(model: &haptloop_solver::Model) -> Self {
        let mut t = Self::new(Vec::new());
        for (i, b) in model.bodies().iter().enumerate() {
            let Some(shape) = &b.shape else { continue };
            if b.fixed {
                let id = haptloop_solver::BodyId(i as u32);
                let q = model.q0();
                if let (Some(r), Some(rot)) =
                    (model.body_position(q, id), model.body_rotation(q, id))
                {
                    t.fixed
                        .push((b.name.clone(), shape.clone(), Pose3 { r, rot }));
                }
            } else {
                if b.fingertip {
                    t.fingertips.push(t.bodies.len());
                }
                t.bodies.push((i as u32, b.name.clone()));
                t.shapes.push(shape.clone());
            }
        }
        t
    }

    /// Tracks `bodies` (model index, name), without shapes.
    pub fn new(bodies: Vec<(u32, String)>) -> Self {
        Self {
            bodies,
            shapes: Vec::new(),
            fixed: Vec::new(),
            fingertips: Vec::new(),
            samples: Vec::new(),
            stride: 1,
            offered: 0,
        }
    }

    /// Offers the poses of every model body at time `t_s`; kept every
    /// `stride`-th offer.
    pub fn offer(&mut self, t_s: f64, poses: &[Pose3]) {
        if self.bodies.is_empty() {
            return;
        }
        let keep = self.offered.is_multiple_of(self.stride);
        self.offered += 1;
        if !keep {
            return;
        }
        if self.samples.len() >= MAX_SAMPLES {
            let mut k = 0;
            self.samples.retain(|_| {
                k += 1;
                k % 2 == 1
            });
            self.stride *= 2;
            if !(self.offered - 1).is_multiple_of(self.stride) {
                return;
            }
        }
        let poses = self
            .bodies
            .iter()
            .map(|&(i, _)| {
                let p = &poses[i as usize];
                let q: UnitQuaternion<f64> = UnitQuaternion::from_matrix(&p.rot);
                let q: Quaternion<f64> = q.into_inner();
                ([p.r.x, p.r.y, p.r.z], [q.w, q.i, q.j, q.k])
            })
            .collect();
        self.samples.push(TrackSample { t_s, poses });
    }

    /// `bodies.csv`: `t_s,body,x_m,y_m,z_m,qw,qx,qy,qz`, one row per body
    /// per sample.
    pub fn csv(&self) -> String {
        let mut out = String::from("t_s,body,x_m,y_m,z_m,qw,qx,qy,qz\n");
        for s in &self.samples {
            for ((_, name), (r, q)) in self.bodies.iter().zip(&s.poses) {
                out += &format!(
                    "{:.6},{name},{:e},{:e},{:e},{:e},{:e},{:e},{:e}\n",
                    s.t_s, r[0], r[1], r[2], q[0], q[1], q[2], q[3]
                );
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Matrix3, Vector3};

    #[test]
    fn a_long_session_keeps_a_bounded_evenly_spaced_track() {
        let mut t = BodyTrack::new(vec![(0, "box".into())]);
        let n = 3 * MAX_SAMPLES as u64 + 17;
        for k in 0..n {
            t.offer(
                k as f64,
                &[Pose3 {
                    r: Vector3::new(k as f64, 0.0, 0.0),
                    rot: Matrix3::identity(),
                }],
            );
        }
        assert!(t.samples.len() <= MAX_SAMPLES && t.samples.len() >= MAX_SAMPLES / 2);
        let gaps: Vec<f64> = t.samples.windows(2).map(|w| w[1].t_s - w[0].t_s).collect();
        assert!(gaps.iter().all(|g| *g == gaps[0]), "uneven: {gaps:?}");
        assert_eq!(t.samples[0].t_s, 0.0);
        // The last sample is no older than one stride.
        assert!(t.samples.last().unwrap().t_s >= (n - gaps[0] as u64) as f64);
        assert_eq!(t.samples[5].poses[0].0[0], t.samples[5].t_s);
    }
}
