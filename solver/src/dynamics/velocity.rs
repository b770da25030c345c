//! [`Velocities`]: the velocity state of every moving body, advanced by the
//! constrained step (see the [module docs](super)).
//!
//! Per moving body, world frame: v (m/s) and ω (rad/s) of the last step
//! (the secant (q_{n+1} − q_n)/dt, so the velocity of the half step
//! t_n + dt/2), and the angular momentum l = J_w(e_n) ω about the centre
//! of mass. Before the first step after a reset they are the velocity *at*
//! t_n instead (the scene's initial velocity, or rest), which the first
//! prediction integrates with ½ g dt² rather than g dt² (`started`).

use nalgebra::{Quaternion, UnitQuaternion, Vector3};

use crate::force::inertia::BodyMass;
use crate::rotation::BodyFrame;

/// Velocity state and this tick's prediction, one entry per moving body
/// (the order of the force pipeline's `masses`).
#[derive(Debug, Clone, Default)]
pub(crate) struct Velocities {
    /// m/s, world: the last step's velocity (or the instant's, before it).
    pub v: Vec<Vector3<f64>>,
    /// rad/s, world.
    pub w: Vec<Vector3<f64>>,
    /// Angular momentum about the centre of mass, kg·m²/s, world.
    pub l: Vec<Vector3<f64>>,
    /// This tick's predicted velocity (before the constraints act), m/s.
    pub v_pred: Vec<Vector3<f64>>,
    /// This tick's predicted angular velocity, rad/s.
    pub w_pred: Vec<Vector3<f64>>,
    /// This tick's predicted angular momentum, kg·m²/s.
    pub l_pred: Vec<Vector3<f64>>,
    /// `v`, `w` are a step's (false: an instant's, after a reset).
    pub started: bool,
    /// A tick has run since the program was built (a reset is then to rest,
    /// not to the scene's initial velocities).
    pub ticked: bool,
}

impl Velocities {
    /// At rest. Allocates.
    pub fn new(bodies: usize) -> Self {
        let z = vec![Vector3::zeros(); bodies];
        Self {
            v: z.clone(),
            w: z.clone(),
            l: z.clone(),
            v_pred: z.clone(),
            w_pred: z.clone(),
            l_pred: z,
            started: false,
            ticked: false,
        }
    }

    /// Sets body `k`'s velocity at an instant, its frame `f`.
    ///
    /// # Real-time
    /// No allocation.
    pub fn set(&mut self, k: usize, m: &BodyMass, f: &BodyFrame, v: Vector3<f64>, w: Vector3<f64>) {
        self.v[k] = v;
        self.w[k] = w;
        self.l[k] = m.world_inertia(f) * w;
    }

    /// Forgets the motion: every body at rest at an instant.
    ///
    /// # Real-time
    /// No allocation; O(bodies).
    pub fn rest(&mut self) {
        for x in [&mut self.v, &mut self.w, &mut self.l] {
            x.fill(Vector3::zeros());
        }
        self.started = false;
    }

    /// The predicted velocities of this tick, before any contact force:
    /// v̂ = v / (1 + c dt) + γ g dt and l̂ = l / (1 + c dt), ω̂ = J_w⁻¹ l̂, with
    /// γ = 1 after a step (leapfrog: the half-step velocity gains a whole
    /// tick of gravity) and ½ after a reset (the instant's velocity gains
    /// half of it, so that q̂ = q + v dt + ½ g dt² is exact). `frames`: each
    /// body's frame at q; `damping`: c per body, 1/s.
    ///
    /// # Real-time
    /// No allocation; O(bodies).
    pub fn predict(
        &mut self,
        masses: &[BodyMass],
        frames: &[BodyFrame],
        damping: &[f64],
        g: &Vector3<f64>,
        dt_s: f64,
    ) {
        let gamma = if self.started { 1.0 } else { 0.5 };
        for (k, m) in masses.iter().enumerate() {
            let keep = 1.0 / (1.0 + damping[k] * dt_s);
            let g = if m.weighs { *g } else { Vector3::zeros() };
            self.v_pred[k] = self.v[k] * keep + g * (gamma * dt_s);
            self.l_pred[k] = self.l[k] * keep;
            self.w_pred[k] = inverse_world_inertia(m, &frames[k]) * self.l_pred[k];
        }
    }

    /// Adds an impulse `j` (N·s, world) at the world point `p` to body `k`'s
    /// prediction.
    ///
    /// # Real-time
    /// No allocation.
    pub fn push(
        &mut self,
        k: usize,
        m: &BodyMass,
        f: &BodyFrame,
        p: &Vector3<f64>,
        j: &Vector3<f64>,
    ) {
        self.v_pred[k] += j / m.mass;
        self.l_pred[k] += (p - f.r).cross(j);
        self.w_pred[k] = inverse_world_inertia(m, f) * self.l_pred[k];
    }

    /// Adds an angular impulse `dl` (N·m·s, world) to body `k`'s prediction.
    ///
    /// # Real-time
    /// No allocation.
    pub fn turn(&mut self, k: usize, m: &BodyMass, f: &BodyFrame, dl: &Vector3<f64>) {
        self.l_pred[k] += dl;
        self.w_pred[k] = inverse_world_inertia(m, f) * self.l_pred[k];
    }

    /// Writes the prediction q̂ of body `k` (columns `o..o + 7`): r + v̂ dt,
    /// e turned by ω̂ dt.
    ///
    /// # Real-time
    /// No allocation.
    pub fn write_goal(&self, k: usize, o: usize, q: &[f64], goal: &mut [f64], dt_s: f64) {
        let dr = self.v_pred[k] * dt_s;
        for c in 0..3 {
            goal[o + c] = q[o + c] + dr[c];
        }
        let turn = UnitQuaternion::from_scaled_axis(self.w_pred[k] * dt_s);
        let e = turn.quaternion() * Quaternion::new(q[o + 3], q[o + 4], q[o + 5], q[o + 6]);
        goal[o + 3..o + 7].copy_from_slice(&[e.w, e.i, e.j, e.k]);
    }

    /// After the constrained step from `q_ref` to `q` over `dt_s`: each
    /// body's velocity is its secant, its angular momentum J_w(e_ref) ω.
    ///
    /// # Real-time
    /// No allocation; O(bodies).
    pub fn finish(&mut self, masses: &[BodyMass], q_ref: &[f64], q: &[f64], dt_s: f64) {
        for (k, m) in masses.iter().enumerate() {
            let o = m.offset;
            self.v[k] = Vector3::new(
                q[o] - q_ref[o],
                q[o + 1] - q_ref[o + 1],
                q[o + 2] - q_ref[o + 2],
            ) / dt_s;
            let (a, b) = (unit(q_ref, o), unit(q, o));
            self.w[k] = (b * a.inverse()).scaled_axis() / dt_s;
            if let Some(f) = frame(q_ref, o) {
                self.l[k] = m.world_inertia(&f) * self.w[k];
            }
        }
        self.started = true;
        self.ticked = true;
    }

    /// Adds Δv (m/s) and Δω (rad/s) to body `k`'s velocity after a step
    /// whose start frame was `f` (restitution).
    pub fn kick(
        &mut self,
        k: usize,
        m: &BodyMass,
        f: &BodyFrame,
        dv: Vector3<f64>,
        dw: Vector3<f64>,
    ) {
        self.v[k] += dv;
        self.w[k] += dw;
        self.l[k] += m.world_inertia(f) * dw;
    }

    /// Copies body `from` of `old` into body `to`.
    pub fn copy_body(&mut self, to: usize, old: &Velocities, from: usize) {
        self.v[to] = old.v[from];
        self.w[to] = old.w[from];
        self.l[to] = old.l[from];
    }

    /// Becomes a copy of `src`: no allocation when the two have the same
    /// number of bodies.
    pub fn copy_from(&mut self, src: &Velocities) {
        fn copy(dst: &mut Vec<Vector3<f64>>, src: &[Vector3<f64>]) {
            if dst.len() == src.len() {
                dst.copy_from_slice(src);
            } else {
                dst.clear();
                dst.extend_from_slice(src);
            }
        }
        copy(&mut self.v, &src.v);
        copy(&mut self.w, &src.w);
        copy(&mut self.l, &src.l);
        copy(&mut self.v_pred, &src.v_pred);
        copy(&mut self.w_pred, &src.w_pred);
        copy(&mut self.l_pred, &src.l_pred);
        self.copy_flags(src);
    }

    /// Copies the flags of `old`.
    pub fn copy_flags(&mut self, old: &Velocities) {
        self.started = old.started;
        self.ticked = old.ticked;
    }
}

/// J_w⁻¹ (world), 1/(kg·m²).
pub(crate) fn inverse_world_inertia(m: &BodyMass, f: &BodyFrame) -> nalgebra::Matrix3<f64> {
    f.rot * nalgebra::Matrix3::from_diagonal(&m.inv_inertia) * f.rot.transpose()
}

/// The unit quaternion of the body at column `o`.
fn unit(q: &[f64], o: usize) -> UnitQuaternion<f64> {
    UnitQuaternion::new_normalize(Quaternion::new(q[o + 3], q[o + 4], q[o + 5], q[o + 6]))
}

/// The frame of the body at column `o` of `q`.
pub(crate) fn frame(q: &[f64], o: usize) -> Option<BodyFrame> {
    BodyFrame::new(
        Vector3::new(q[o], q[o + 1], q[o + 2]),
        [q[o + 3], q[o + 4], q[o + 5], q[o + 6]],
    )
}
