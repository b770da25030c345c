//! Body velocities and accelerations from the history of q (Nelson & Cohen
//! §5.2: "q̈ and q̇ … may be obtained by observing how q … changes over time").
//!
//! Per moving body, world frame, at tick k with step dt:
//!
//! ```text
//! v_k = (r_k − r_{k−1}) / dt                      (centred at t_k − dt/2)
//! ω_k = log(e_k ⊗ e_{k−1}⁻¹) / dt                 (rotation vector of the step)
//! a_k = (v_k − v_{k−1}) / dt,  α_k = (ω_k − ω_{k−1}) / dt   (centred at t_k − dt)
//! ```
//!
//! i.e. backward differences of q: accelerations are O(dt²)-accurate for the
//! instant one tick back, so they lag by one tick. With
//! [`SolverSettings::velocity_filter`](crate::SolverSettings::velocity_filter)
//! τ > 0, v and ω pass a first-order low-pass y ← y + dt/(τ + dt) (x − y)
//! before differencing, adding a delay of about τ, and a and α pass a second
//! one of time constant τ_a = [`ACCELERATION_FILTER_FRACTION`] · τ after it:
//! an encoder count arriving is a step Δv in the raw velocity, which the
//! first stage alone turns into a doublet +Δv/τ, −Δv/τ·(1 − dt/τ) of
//! acceleration on two consecutive ticks (a buzz at half the tick rate);
//! the second stage spreads it over τ_a. Accelerations lag by about
//! τ + τ_a + dt.
//!
//! Auxiliary columns (a flexible body's deformation, `crate::flexible`) get
//! the same differences and filters per column: `aux_v`, `aux_a` (empty
//! for a model without them).
//!
//! History after a reset ([`Program::new`](crate::Program::new), `assemble`,
//! `set_q`): the program is taken to be at rest. The first tick's velocity is
//! measured against the reset configuration, but its acceleration is reported
//! as zero (a reset is a jump, not a motion); from the second tick on both are
//! differences.

use nalgebra::{Quaternion, UnitQuaternion, Vector3};

use super::inertia::BodyMass;

/// τ_a / τ: the time constant of the acceleration's own low-pass stage as
/// a fraction of the velocity filter's. Measured on the built-in scenes
/// (`haptloop run SCENE --deterministic`, RMS tick-to-tick change of the
/// rendered force; BENCHMARKS.md, issue 11): 1 (τ_a = τ) cuts the
/// encoder-count buzz 15–30× but delays the inertial force by 2τ, and a
/// 1000 kg four-bar (the stability matrix) then no longer settles within
/// its tolerance; 0.5 fails the same case; 0.25 passes it and cuts the buzz
/// 5–6× (default scene 0.226 → 0.043 N, Stewart 0.653 → 0.110 N).
pub(crate) const ACCELERATION_FILTER_FRACTION: f64 = 0.25;

/// Velocity and acceleration history of every moving body.
#[derive(Debug, Clone)]
pub(crate) struct Motion {
    /// q at the previous tick.
    pub q_prev: Vec<f64>,
    pub v: Vec<Vector3<f64>>,
    pub w: Vec<Vector3<f64>>,
    pub a: Vec<Vector3<f64>>,
    pub alpha: Vec<Vector3<f64>>,
    /// Ticks since the last reset (saturating).
    pub ticks: u32,
    tau_s: f64,
    /// First auxiliary column (all of them are at the end of q).
    pub aux_start: usize,
    /// Velocity and acceleration of each auxiliary column.
    pub aux_v: Vec<f64>,
    pub aux_a: Vec<f64>,
    /// Per coordinate: the generalized force the step's contact and
    /// friction rows applied (inertial motion), through the same two
    /// low-pass stages as the accelerations: `contact` after the first,
    /// `contact_a` after the second ([`Motion::advance_contact`]).
    pub contact: Vec<f64>,
    pub contact_a: Vec<f64>,
}

impl Motion {
    /// At rest at `q`, auxiliary columns from `aux_start` on. Allocates.
    pub fn new(q: &[f64], bodies: usize, aux_start: usize, tau_s: f64) -> Self {
        let z = vec![Vector3::zeros(); bodies];
        let n_aux = q.len() - aux_start;
        Self {
            q_prev: q.to_vec(),
            v: z.clone(),
            w: z.clone(),
            a: z.clone(),
            alpha: z,
            ticks: 0,
            tau_s,
            aux_start,
            aux_v: vec![0.0; n_aux],
            aux_a: vec![0.0; n_aux],
            contact: vec![0.0; q.len()],
            contact_a: vec![0.0; q.len()],
        }
    }

    /// Forgets the history: at rest at `q`.
    ///
    /// # Real-time
    /// No allocation; O(coordinates).
    pub fn reset(&mut self, q: &[f64]) {
        self.q_prev.copy_from_slice(q);
        for x in [&mut self.v, &mut self.w, &mut self.a, &mut self.alpha] {
            x.fill(Vector3::zeros());
        }
        self.aux_v.fill(0.0);
        self.aux_a.fill(0.0);
        self.contact.fill(0.0);
        self.contact_a.fill(0.0);
        self.ticks = 0;
    }

    /// Advances the history to `q`, `dt_s` seconds after the previous tick.
    ///
    /// # Real-time
    /// No allocation; O(bodies).
    pub fn advance(&mut self, masses: &[BodyMass], q: &[f64], dt_s: f64) {
        let (alpha_f, alpha_a) = self.alphas(dt_s);
        let first = self.ticks == 0;
        for (k, m) in masses.iter().enumerate() {
            let o = m.offset;
            let r = |q: &[f64]| Vector3::new(q[o], q[o + 1], q[o + 2]);
            let e = |q: &[f64]| {
                UnitQuaternion::new_normalize(Quaternion::new(
                    q[o + 3],
                    q[o + 4],
                    q[o + 5],
                    q[o + 6],
                ))
            };
            let v_raw = (r(q) - r(&self.q_prev)) / dt_s;
            let w_raw = (e(q) * e(&self.q_prev).inverse()).scaled_axis() / dt_s;
            let v = self.v[k] + (v_raw - self.v[k]) * alpha_f;
            let w = self.w[k] + (w_raw - self.w[k]) * alpha_f;
            if first {
                self.a[k] = Vector3::zeros();
                self.alpha[k] = Vector3::zeros();
            } else {
                // The difference of a filtered velocity still steps by
                // Δv/τ when an encoder count arrives, and back the next
                // tick: a period-2 buzz. A second low-pass stage on the
                // acceleration (time constant τ_a, module docs) damps it.
                let a_raw = (v - self.v[k]) / dt_s;
                let alpha_raw = (w - self.w[k]) / dt_s;
                let (a, al) = (self.a[k], self.alpha[k]);
                self.a[k] = a + (a_raw - a) * alpha_a;
                self.alpha[k] = al + (alpha_raw - al) * alpha_a;
            }
            self.v[k] = v;
            self.w[k] = w;
        }
        for (c, (v, a)) in self.aux_v.iter_mut().zip(&mut self.aux_a).enumerate() {
            let i = self.aux_start + c;
            let v_new = *v + ((q[i] - self.q_prev[i]) / dt_s - *v) * alpha_f;
            *a = if first {
                0.0
            } else {
                *a + ((v_new - *v) / dt_s - *a) * alpha_a
            };
            *v = v_new;
        }
        self.q_prev.copy_from_slice(q);
        self.ticks = self.ticks.saturating_add(1);
    }

    /// Passes this tick's generalized contact force `raw` (per coordinate,
    /// N or its Euler-parameter equivalent) through the two low-pass stages
    /// the accelerations pass (τ, then τ_a), so that Eq. 7 balances the
    /// filtered contact forces against the equally filtered M q̈: the
    /// step's velocity change of a body is exactly its forces' impulse, and
    /// a filter commutes with that sum (`Feedback::compute`).
    ///
    /// # Real-time
    /// No allocation; O(coordinates).
    pub fn advance_contact(&mut self, raw: &[f64], dt_s: f64) {
        let (alpha_f, alpha_a) = self.alphas(dt_s);
        for ((f, a), &x) in self.contact.iter_mut().zip(&mut self.contact_a).zip(raw) {
            *f += (x - *f) * alpha_f;
            *a += (*f - *a) * alpha_a;
        }
    }

    /// The two stages' smoothing factors for a tick of `dt_s`.
    pub fn alphas(&self, dt_s: f64) -> (f64, f64) {
        if self.tau_s > 0.0 {
            (
                dt_s / (self.tau_s + dt_s),
                dt_s / (ACCELERATION_FILTER_FRACTION * self.tau_s + dt_s),
            )
        } else {
            (1.0, 1.0)
        }
    }

    /// Copies the filtered contact force of the coordinates `from..from + n`
    /// of `old` into `to..to + n` of `self` (a hand-over).
    pub fn copy_contact(&mut self, to: usize, old: &Motion, from: usize, n: usize) {
        self.contact[to..to + n].copy_from_slice(&old.contact[from..from + n]);
        self.contact_a[to..to + n].copy_from_slice(&old.contact_a[from..from + n]);
    }

    /// Copies the history of body `from` of `old` into body `to` of `self`.
    pub fn copy_body(&mut self, to: usize, old: &Motion, from: usize) {
        self.v[to] = old.v[from];
        self.w[to] = old.w[from];
        self.a[to] = old.a[from];
        self.alpha[to] = old.alpha[from];
    }
}
