//! Restitution: velocity-level impulses after the constrained step.
//!
//! The projection stops an impact: a ball that reaches the floor within a
//! tick ends it on the floor with the secant velocity of whatever part of
//! the tick it still fell. A contact row whose pair has restitution e > 0,
//! that pushed in the step and whose two bodies were closing at speed V
//! when they met, then gets an impulse that makes its rate (the rate of the
//! row's gap, J q̇) e V, separating. V is the exact speed at contact for
//! motion under the tick's constant acceleration:
//!
//! ```text
//! V² = ċ₀² − 2 c̈ c₀,   ċ₀ = J (q̂ − q)/dt − ½ c̈ dt,   c̈ = J g_q,   c₀ = C(q_end) − J (q_end − q)
//! ```
//!
//! (ċ₀ the gap's rate at the tick's start, c̈ gravity's share of its
//! acceleration, c₀ the gap then), so a ball dropped from h rebounds to
//! e² h up to round-off, whatever the instant of impact within the tick.
//! Several impacting rows (a box landing on its corners) share the impulse
//! by projected Gauss–Seidel ([`SWEEPS`] sweeps, impulses ≥ 0). A contact
//! closing slower than [`min_speed`] (two ticks of gravity: a body resting
//! on another, whose gap every prediction closes by g dt²) does not bounce.
//!
//! # Real-time
//! No allocation (buffers sized at construction); O(nnz) for the products
//! with the chord Jacobian, only on ticks where a pair with restitution
//! pushes; O(sweeps × impacting rows) for the impulses.

use nalgebra::{Matrix4, Vector3, Vector4};

use super::velocity::{Velocities, frame};
use crate::Jacobian;
use crate::force::inertia::BodyMass;

/// Projected Gauss–Seidel sweeps over the impacting rows.
pub const SWEEPS: usize = 8;

/// Speed of a gap below which it does not bounce, m/s: two ticks of gravity
/// along the row (`g_rate` m/s² of gap) plus 1 mm/s.
pub fn min_speed(g_rate: f64, dt_s: f64) -> f64 {
    2.0 * g_rate.abs() * dt_s + 1e-3
}

/// One impacting row.
#[derive(Debug, Clone, Copy)]
struct Impact {
    row: usize,
    /// Rate the row must reach, m/s (≥ 0: separating).
    target: f64,
    /// Impulse applied so far (in the row's unit × kg/s).
    p: f64,
}

/// Buffers of the restitution pass.
#[derive(Debug, Clone)]
pub(crate) struct Restitution {
    /// Per contact row of the model: its pair's restitution (0: none).
    pub row_e: Vec<f64>,
    /// Any row has e > 0.
    pub any: bool,
    /// Per column: the index in `masses` of its body and the body's first
    /// column (`usize::MAX`: a design variable).
    col_body: Vec<(usize, usize)>,
    /// Gravity as a q-space acceleration (weighing bodies' r columns).
    g_q: Vec<f64>,
    dq: Vec<f64>,
    jdq: Vec<f64>,
    jdq_pred: Vec<f64>,
    jg: Vec<f64>,
    qdot: Vec<f64>,
    minv: Vec<Matrix4<f64>>,
    impacts: Vec<Impact>,
}

impl Restitution {
    /// Buffers for `n` columns, `m` rows and `masses`; `row_e` per row.
    /// Allocates.
    pub fn new(n: usize, row_e: Vec<f64>, masses: &[BodyMass], g: &Vector3<f64>) -> Self {
        let mut col_body = vec![(usize::MAX, 0); n];
        let mut g_q = vec![0.0; n];
        for (k, m) in masses.iter().enumerate() {
            col_body[m.offset..m.offset + 7].fill((k, m.offset));
            if m.weighs {
                g_q[m.offset..m.offset + 3].copy_from_slice(g.as_slice());
            }
        }
        let m = row_e.len();
        let candidates = row_e.iter().filter(|&&e| e > 0.0).count();
        Self {
            any: candidates > 0,
            row_e,
            col_body,
            g_q,
            dq: vec![0.0; n],
            jdq: vec![0.0; m],
            jdq_pred: vec![0.0; m],
            jg: vec![0.0; m],
            qdot: vec![0.0; n],
            minv: vec![Matrix4::zeros(); masses.len()],
            impacts: Vec::with_capacity(candidates),
        }
    }

    /// Applies the restitution impulses of the step from `q_ref` to `q`
    /// (prediction `q_goal`; `values` = C(q); `lambda` the step's
    /// multipliers, ν ≥ 0 on contact rows) to `vel`, already finished for
    /// the step. Returns the number of rows that bounced.
    #[allow(clippy::too_many_arguments)]
    pub fn apply(
        &mut self,
        jac: &Jacobian,
        masses: &[BodyMass],
        q_ref: &[f64],
        q: &[f64],
        q_goal: &[f64],
        values: &[f64],
        lambda: &[f64],
        dt_s: f64,
        vel: &mut Velocities,
    ) -> u32 {
        if !self.any || !(0..self.row_e.len()).any(|i| self.row_e[i] > 0.0 && lambda[i] > 0.0) {
            return 0;
        }
        self.impacts.clear();
        for (d, (a, b)) in self.dq.iter_mut().zip(q_goal.iter().zip(q_ref)) {
            *d = a - b;
        }
        if jac.mul_vec(&self.dq, &mut self.jdq_pred).is_err()
            || jac.mul_vec(&self.g_q, &mut self.jg).is_err()
        {
            return 0;
        }
        for (d, (a, b)) in self.dq.iter_mut().zip(q.iter().zip(q_ref)) {
            *d = a - b;
        }
        if jac.mul_vec(&self.dq, &mut self.jdq).is_err() {
            return 0;
        }
        for i in 0..self.row_e.len() {
            let e = self.row_e[i];
            if e <= 0.0 || lambda[i] <= 0.0 || self.jdq_pred[i] >= 0.0 {
                continue;
            }
            let acc = self.jg[i];
            let rate0 = self.jdq_pred[i] / dt_s - 0.5 * acc * dt_s;
            let gap0 = (values[i] - self.jdq[i]).max(0.0);
            let speed = (rate0 * rate0 - 2.0 * acc * gap0).max(0.0).sqrt();
            if speed > min_speed(acc, dt_s) && self.impacts.len() < self.impacts.capacity() {
                // The velocity state is a step's (its middle, t + dt/2):
                // leaving the contact at e V, half a tick of gravity later.
                self.impacts.push(Impact {
                    row: i,
                    target: e * speed - 0.5 * acc * dt_s,
                    p: 0.0,
                });
            }
        }
        if self.impacts.is_empty() {
            return 0;
        }
        for (k, m) in masses.iter().enumerate() {
            let o = m.offset;
            let e = Vector4::new(q_ref[o + 3], q_ref[o + 4], q_ref[o + 5], q_ref[o + 6]);
            if let Some(f) = frame(q_ref, o) {
                self.minv[k] = m.inv_rotational_mass(&f, &e);
            }
        }
        for (v, d) in self.qdot.iter_mut().zip(&self.dq) {
            *v = d / dt_s;
        }
        for _ in 0..SWEEPS {
            for k in 0..self.impacts.len() {
                let Impact { row, target, p } = self.impacts[k];
                let rate = row_dot(jac, row, &self.qdot);
                let a = self.row_gram(jac, row, masses);
                if a <= 0.0 {
                    continue;
                }
                let p_new = (p + (target - rate) / a).max(0.0);
                self.add_impulse(jac, row, masses, p_new - p);
                self.impacts[k].p = p_new;
            }
        }
        for (k, m) in masses.iter().enumerate() {
            let o = m.offset;
            let d = |c: usize| self.qdot[o + c] - self.dq[o + c] / dt_s;
            let dv = Vector3::new(d(0), d(1), d(2));
            let de = Vector4::new(d(3), d(4), d(5), d(6));
            if dv.norm_squared() + de.norm_squared() == 0.0 {
                continue;
            }
            if let Some(f) = frame(q_ref, o) {
                vel.kick(k, m, &f, dv, f.omega * de);
            }
        }
        self.impacts.len() as u32
    }

    /// J_i M̃⁻¹ J_iᵀ of row `i`.
    fn row_gram(&self, jac: &Jacobian, i: usize, masses: &[BodyMass]) -> f64 {
        let mut sum = 0.0;
        self.each_body(jac, i, |k, o, g| {
            let m = &masses[k];
            let lin = (g[0] * g[0] + g[1] * g[1] + g[2] * g[2]) / m.mass;
            let ge = Vector4::new(g[3], g[4], g[5], g[6]);
            sum += lin + ge.dot(&(self.minv[k] * ge));
            let _ = o;
        });
        sum
    }

    /// q̇ += M̃⁻¹ J_iᵀ p.
    fn add_impulse(&mut self, jac: &Jacobian, i: usize, masses: &[BodyMass], p: f64) {
        if p == 0.0 {
            return;
        }
        let mut out = [(usize::MAX, [0.0; 7]); 2];
        let mut n = 0;
        self.each_body(jac, i, |k, o, g| {
            let m = &masses[k];
            let ge = self.minv[k] * Vector4::new(g[3], g[4], g[5], g[6]);
            let mut d = [0.0; 7];
            for c in 0..3 {
                d[c] = g[c] / m.mass * p;
            }
            for c in 0..4 {
                d[3 + c] = ge[c] * p;
            }
            if n < 2 {
                out[n] = (o, d);
                n += 1;
            }
        });
        for &(o, d) in &out[..n] {
            for (c, x) in d.iter().enumerate() {
                self.qdot[o + c] += x;
            }
        }
    }

    /// Calls `f(body, first column, gradient block)` for each body row `i`
    /// touches (at most two; a body's seven columns are contiguous).
    fn each_body(&self, jac: &Jacobian, i: usize, mut f: impl FnMut(usize, usize, &[f64; 7])) {
        let span = jac.row_ptr()[i]..jac.row_ptr()[i + 1];
        let mut cur: Option<(usize, usize, [f64; 7])> = None;
        for p in span {
            let col = jac.col_idx()[p];
            let (k, o) = self.col_body[col];
            if k == usize::MAX {
                continue;
            }
            match &mut cur {
                Some((kk, _, g)) if *kk == k => g[col - o] = jac.values()[p],
                _ => {
                    if let Some((kk, oo, g)) = cur.take() {
                        f(kk, oo, &g);
                    }
                    let mut g = [0.0; 7];
                    g[col - o] = jac.values()[p];
                    cur = Some((k, o, g));
                }
            }
        }
        if let Some((kk, oo, g)) = cur {
            f(kk, oo, &g);
        }
    }
}

/// J_i · x.
fn row_dot(jac: &Jacobian, i: usize, x: &[f64]) -> f64 {
    let span = jac.row_ptr()[i]..jac.row_ptr()[i + 1];
    span.map(|p| jac.values()[p] * x[jac.col_idx()[p]]).sum()
}
