//! What a run looked like, for `view.html`, the live viewer and the files
//! behind them: every moving body's pose (fixed bodies once), the active
//! contact points and normals and the largest violation, sampled by the slow
//! loop from the fast loop's snapshots ([`BodyTrack`]); each finger's device
//! point, fingertip and rendered force, sampled by the reporter from the
//! trace queue ([`FingerTrack`]). Both keep 100 Hz of session time within a
//! memory budget ([`thinned`]). The file format is `docs/run-files.md`.

mod contacts;
mod fingers;
pub mod thinned;

pub use contacts::{ACTIVE_GAP_M, ContactPoint, contact_points};
pub use fingers::{FingerSample, FingerTrack};
pub use thinned::{BUDGET_BYTES, SAMPLE_PERIOD_S, Thinned};

use haptloop_solver::geometry::{Pose3, Shape};
use haptloop_solver::{BodyId, Model};
use nalgebra::{Quaternion, UnitQuaternion};

/// One body the track follows.
#[derive(Debug, Clone)]
pub struct TrackedBody {
    /// Model body index.
    pub index: u32,
    /// Name.
    pub name: String,
    /// Collision shape, if any.
    pub shape: Option<Shape>,
    /// A contact finger's fingertip.
    pub fingertip: bool,
}

/// One sample of the slow loop: the moving bodies' poses, the active
/// contacts and the largest violation since the last sample.
#[derive(Debug, Clone, Default)]
pub struct TrackSample {
    /// World position (m) and unit quaternion `[w, x, y, z]` per moving
    /// body, in [`BodyTrack::bodies`] order.
    pub poses: Vec<([f64; 3], [f64; 4])>,
    /// Contact points within [`ACTIVE_GAP_M`] of touching.
    pub contacts: Vec<ContactPoint>,
    /// Largest length-row violation of the ticks since the slow loop's last
    /// look, m (NaN: the snapshot's solve failed).
    pub violation_m: f64,
    /// Each finger's force as the solver asked for it (before the safety
    /// layer and the device's limits), N, model order.
    pub asked_n: Vec<[f64; 3]>,
}

impl TrackSample {
    fn bytes(&self) -> usize {
        std::mem::size_of::<Self>()
            + self.poses.len() * std::mem::size_of::<([f64; 3], [f64; 4])>()
            + self.contacts.len() * std::mem::size_of::<ContactPoint>()
            + self.asked_n.len() * std::mem::size_of::<[f64; 3]>()
    }
}

/// The bodies of a session over time (see the module docs).
#[derive(Debug, Clone, Default)]
pub struct BodyTrack {
    /// The moving bodies, model order.
    pub bodies: Vec<TrackedBody>,
    /// Fixed bodies: name, shape, pose (they never move).
    pub fixed: Vec<(String, Option<Shape>, Pose3)>,
    /// The samples.
    pub samples: Thinned<TrackSample>,
}

/// A body's pose as position and unit quaternion `[w, x, y, z]`.
pub fn pose_parts(p: &Pose3) -> ([f64; 3], [f64; 4]) {
    let q: Quaternion<f64> = UnitQuaternion::from_matrix(&p.rot).into_inner();
    ([p.r.x, p.r.y, p.r.z], [q.w, q.i, q.j, q.k])
}

/// Every body's pose at `q` (fixed bodies at theirs), model order.
pub fn poses_at(model: &Model, q: &[f64], out: &mut Vec<Pose3>) {
    out.clear();
    for i in 0..model.bodies().len() {
        let id = BodyId(i as u32);
        let pose = match (model.body_position(q, id), model.body_rotation(q, id)) {
            (Some(r), Some(rot)) => Pose3 { r, rot },
            _ => Pose3 {
                r: nalgebra::Vector3::repeat(f64::NAN),
                rot: nalgebra::Matrix3::identity(),
            },
        };
        out.push(pose);
    }
}

impl BodyTrack {
    /// Tracks every body of `model`: moving ones sampled, fixed ones kept
    /// at their pose.
    pub fn of_model(model: &Model) -> Self {
        let mut t = Self::default();
        for (i, b) in model.bodies().iter().enumerate() {
            if b.fixed {
                let id = BodyId(i as u32);
                let q = model.q0();
                if let (Some(r), Some(rot)) =
                    (model.body_position(q, id), model.body_rotation(q, id))
                {
                    t.fixed
                        .push((b.name.clone(), b.shape.clone(), Pose3 { r, rot }));
                }
            } else {
                t.bodies.push(TrackedBody {
                    index: i as u32,
                    name: b.name.clone(),
                    shape: b.shape.clone(),
                    fingertip: b.fingertip,
                });
            }
        }
        t
    }

    /// True if a sample at `t_s` would be kept (callers skip the work of
    /// building one otherwise).
    pub fn wants(&self, t_s: f64) -> bool {
        self.samples.wants(t_s)
    }

    /// Offers the poses of every model body (model order), the contacts,
    /// the violation and the fingers' asked forces at `t_s`.
    pub fn offer(
        &mut self,
        t_s: f64,
        poses: &[Pose3],
        contacts: &[ContactPoint],
        violation_m: f64,
        asked_n: &[[f64; 3]],
    ) {
        if !self.wants(t_s) {
            return;
        }
        let mut sample = self.sample(poses, contacts, violation_m);
        sample.asked_n = asked_n.to_vec();
        self.samples.offer(t_s, sample.bytes(), || sample);
    }

    /// A sample of the moving bodies at `poses` (model order).
    pub fn sample(
        &self,
        poses: &[Pose3],
        contacts: &[ContactPoint],
        violation_m: f64,
    ) -> TrackSample {
        TrackSample {
            poses: self
                .bodies
                .iter()
                .map(|b| pose_parts(&poses[b.index as usize]))
                .collect(),
            contacts: contacts.to_vec(),
            violation_m,
            asked_n: Vec::new(),
        }
    }

    /// `bodies.csv`: `t_s,body,x_m,y_m,z_m,qw,qx,qy,qz`: the fixed bodies
    /// once at t = 0, then one row per moving body per sample.
    pub fn csv(&self) -> String {
        let mut out = String::from("t_s,body,x_m,y_m,z_m,qw,qx,qy,qz\n");
        let row = |out: &mut String, t: f64, name: &str, (r, q): ([f64; 3], [f64; 4])| {
            *out += &format!(
                "{t:.6},{name},{:e},{:e},{:e},{:e},{:e},{:e},{:e}\n",
                r[0], r[1], r[2], q[0], q[1], q[2], q[3]
            );
        };
        for (name, _, pose) in &self.fixed {
            row(&mut out, 0.0, name, pose_parts(pose));
        }
        for (t, s) in self.samples.iter() {
            for (b, pose) in self.bodies.iter().zip(&s.poses) {
                row(&mut out, t, &b.name, *pose);
            }
        }
        out
    }

    /// `contacts.csv`: `t_s,body_a,body_b,x_m,y_m,z_m,nx,ny,nz,gap_m`, one
    /// row per active contact point per sample.
    pub fn contacts_csv(&self, names: &[String]) -> String {
        let mut out = String::from("t_s,body_a,body_b,x_m,y_m,z_m,nx,ny,nz,gap_m\n");
        for (t, s) in self.samples.iter() {
            for c in &s.contacts {
                let [a, b] = c
                    .bodies
                    .map(|i| names.get(i as usize).map_or("?", String::as_str));
                let (p, n) = (c.point_m, c.normal);
                out += &format!(
                    "{t:.6},{a},{b},{:e},{:e},{:e},{:e},{:e},{:e},{:e}\n",
                    p[0], p[1], p[2], n[0], n[1], n[2], c.gap_m
                );
            }
        }
        out
    }

    /// (session time, largest violation) per sample.
    pub fn violations(&self) -> impl Iterator<Item = (f64, f64)> + '_ {
        self.samples.iter().map(|(t, s)| (t, s.violation_m))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scenes::resolve;

    /// A mechanism without any shape is tracked too: every moving body of
    /// the four-bar, its fixed ground once, poses equal to the model's.
    #[test]
    fn a_mechanism_without_shapes_is_tracked_body_by_body() {
        let scene = resolve("four-bar").unwrap();
        let model = &scene.compiled.model;
        let mut t = BodyTrack::of_model(model);
        let moving = model.bodies().iter().filter(|b| !b.fixed).count();
        assert_eq!(t.bodies.len(), moving);
        assert_eq!(t.fixed.len(), model.bodies().len() - moving);
        let mut poses = Vec::new();
        poses_at(model, model.q0(), &mut poses);
        for k in 0..10 {
            t.offer(k as f64 * 0.005, &poses, &[], 0.0, &[]);
        }
        assert_eq!(t.samples.len(), 5, "10 offers every 5 ms, kept every 10 ms");
        let csv = t.csv();
        assert_eq!(csv.lines().count(), 1 + t.fixed.len() + 5 * moving);
        let b = &t.bodies[0];
        let r = model.body_position(model.q0(), BodyId(b.index)).unwrap();
        let row = csv
            .lines()
            .find(|l| l.contains(&format!(",{},", b.name)))
            .unwrap();
        let x: f64 = row.split(',').nth(2).unwrap().parse().unwrap();
        assert_eq!(x, r.x);
    }
}
