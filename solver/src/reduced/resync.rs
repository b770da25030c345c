//! Moving a [`JointTick`] to a configuration it did not tick to (a
//! placement, a correction, a hand-over, a failed tick's restore), without
//! allocating: the fast loop's `Program` calls it wherever it changes q
//! outside a tick.

use nalgebra::Vector3;

use super::ReducedError;
use super::stage::{Stage, pose};
use super::tick::JointTick;
use crate::FingerTarget;
use crate::rotation::BodyFrame;

/// What a [`JointTick::resync`] does with the motion history (each body's
/// pose, velocity and acceleration estimates, the coupling's last error).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum History {
    /// Restart at rest at the new q (a jump is not a motion: `set_q`,
    /// `assemble`, a failed tick).
    Rest,
    /// Move the poses with q and keep the velocities and accelerations (a
    /// correction, not a motion: `shift_q`).
    Shift,
    /// Leave it as it is (q moved by steps the next tick should see as
    /// motion: `iterate`; or q did not move).
    Keep,
}

impl JointTick {
    /// Moves the tick to `q`: its frames, the loop and finger rows' values
    /// and D J_r S at q, the force stage's factors (the next tick's chord),
    /// `values` (every model row at q, from the augmented evaluation) kept
    /// for the rows the tick never evaluates (tree joints, quaternion
    /// norms: they hold by construction from here). Outputs are untouched.
    ///
    /// # Real-time
    /// No allocation; one end-of-tick evaluation and factorisation.
    ///
    /// # Errors
    /// A degenerate quaternion in q, a factor that is not positive
    /// definite; the tick is then unusable until a resync succeeds.
    pub fn resync(
        &mut self,
        q: &[f64],
        values: &[f64],
        targets: &[FingerTarget],
        history: History,
    ) -> Result<(), ReducedError> {
        self.q.copy_from_slice(q);
        self.q_s.copy_from_slice(q);
        self.values.copy_from_slice(values);
        for (b, o) in self.model.layout().moving_bodies() {
            self.frames[b.index()] = BodyFrame::new(
                Vector3::new(q[o], q[o + 1], q[o + 2]),
                [q[o + 3], q[o + 4], q[o + 5], q[o + 6]],
            )
            .ok_or(ReducedError::Degenerate(b.index()))?;
        }
        match history {
            History::Rest => self.stage.rest(q),
            History::Shift => self.stage.shift(q),
            History::Keep => {}
        }
        self.evaluate_end(targets, false)?;
        self.force_end(targets, 1e-3, false)
    }

    /// Takes the motion history of `old` (a joint tick of a model with
    /// the same moving bodies, e.g. the program this one replaces at a
    /// hand-over); false, and nothing taken, if the bodies differ.
    ///
    /// # Real-time
    /// No allocation.
    pub fn adopt_history(&mut self, old: &JointTick) -> bool {
        let (a, b) = (&mut self.stage, &old.stage);
        let same = a.bodies.len() == b.bodies.len()
            && a.bodies.iter().zip(&b.bodies).all(|(x, y)| x.0 == y.0)
            && a.prev_error.len() == b.prev_error.len();
        if same {
            a.bodies.copy_from_slice(&b.bodies);
            a.prev_error.copy_from_slice(&b.prev_error);
            a.ticks = b.ticks;
        }
        same
    }

    /// The model rows each tick evaluates (every row of the loop-closing
    /// and finger constraints); the others keep their value at the last
    /// resync. Allocates.
    pub fn evaluated_rows(&self) -> Vec<usize> {
        self.set
            .evaluated()
            .chain(self.limits.rows().iter().copied())
            .collect()
    }

    /// Every model row's last value: the loop and finger rows' at the last
    /// tick's end, the others' (tree joints, norms) at the last resync.
    pub fn values(&self) -> &[f64] {
        &self.values
    }
}

/// The motion history in `force::motion`'s layout ([`JointTick::export_history`]).
pub struct MotionOut<'a> {
    /// q at the previous tick (the bodies' columns are written).
    pub q_prev: &'a mut [f64],
    /// Per moving body (slots of `force::motion`): velocity.
    pub v: &'a mut [Vector3<f64>],
    /// Angular velocity.
    pub w: &'a mut [Vector3<f64>],
    /// Acceleration.
    pub a: &'a mut [Vector3<f64>],
    /// Angular acceleration.
    pub alpha: &'a mut [Vector3<f64>],
    /// Per finger: the coupling's last error.
    pub prev_error: &'a mut [Vector3<f64>],
}

impl JointTick {
    /// Writes the motion history into `out`, body `k` of this tick into
    /// slot `slot(first column)`; returns the ticks since its last reset.
    ///
    /// # Real-time
    /// No allocation; O(bodies × slots) at worst.
    pub fn export_history(&self, slot: impl Fn(usize) -> Option<usize>, out: MotionOut<'_>) -> u32 {
        for (_, o, h) in &self.stage.bodies {
            let Some(k) = slot(*o) else { continue };
            out.q_prev[*o..*o + 3].copy_from_slice(h.r.as_slice());
            let e = h.e.quaternion();
            out.q_prev[*o + 3..*o + 7].copy_from_slice(&[e.w, e.i, e.j, e.k]);
            (out.v[k], out.w[k], out.a[k], out.alpha[k]) = (h.v, h.w, h.a, h.alpha);
        }
        out.prev_error.copy_from_slice(&self.stage.prev_error);
        self.stage.ticks
    }
}

impl Stage {
    /// The motion history at rest at q.
    fn rest(&mut self, q: &[f64]) {
        for (_, o, h) in self.bodies.iter_mut() {
            (h.r, h.e) = pose(q, *o);
            h.v = Vector3::zeros();
            h.w = Vector3::zeros();
            h.a = Vector3::zeros();
            h.alpha = Vector3::zeros();
        }
        self.prev_error.fill(Vector3::zeros());
        self.ticks = 0;
    }

    /// The poses moved to q, the rates kept.
    fn shift(&mut self, q: &[f64]) {
        for (_, o, h) in self.bodies.iter_mut() {
            (h.r, h.e) = pose(q, *o);
        }
    }
}
