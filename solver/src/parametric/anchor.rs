//! Setting the rolling rows' tick-start anchors (`rolling`): the program
//! calls [`Evaluation::anchor_rolling`] with the configuration a tick
//! starts from, before any of its steps.

use nalgebra::Vector3;

use super::rolling::{RollAnchor, Rolling};
use crate::constraint::Geometry;
use crate::constraint::block::Param3;
use crate::rotation::BodyFrame;
use crate::{Evaluation, Model};

impl Evaluation {
    /// Sets every rolling constraint's anchor from configuration `q` (the
    /// start of a tick): the ball's centre and orientation, the contact
    /// normal and tangents at the surface contact's (u, v). A configuration
    /// that cannot be read (wrong length, degenerate quaternion) leaves the
    /// anchors off.
    ///
    /// # Real-time
    /// No allocation; O(rolling constraints).
    pub fn anchor_rolling(&mut self, model: &Model, q: &[f64]) {
        for (slot, &k) in model.rolling.iter().enumerate() {
            let a = match (&model.geometry[k], q.len() == model.n_coords()) {
                (Geometry::Rolling(r), true) => anchor(model, &self.frames, q, r),
                _ => None,
            };
            self.rolling[slot] = a.unwrap_or(RollAnchor::OFF);
        }
    }
}

fn anchor(model: &Model, frames: &[BodyFrame], q: &[f64], r: &Rolling) -> Option<RollAnchor> {
    let o = r.pair.col[0]?;
    let f = BodyFrame::new(
        Vector3::new(q[o], q[o + 1], q[o + 2]),
        [q[o + 3], q[o + 4], q[o + 5], q[o + 6]],
    )?;
    let Param3::Const(k) = r.pair.anchor[0] else {
        return None;
    };
    let sc = model.surfaces.get(r.contact as usize)?;
    let fj = frames.get(r.pair.frame[1])?;
    let sp = sc.surface.offset(q[sc.uv_col], q[sc.uv_col + 1], 0.0);
    let n = fj.rot * sp.n;
    let t1 = fj.rot * sp.pu;
    let t1 = (t1 - n * n.dot(&t1)).try_normalize(1e-12)?;
    Some(RollAnchor {
        on: true,
        centre: f.point(&k),
        rot_t: f.rot.transpose(),
        rho: -n * sc.radius_m,
        tangents: [t1, n.cross(&t1)],
    })
}
