//! The program's side of inertial motion (`crate::dynamics`): the prediction
//! q̂ of each tick, the Coulomb decisions on the step's forces, the
//! velocity update, restitution and the energy account.
//!
//! Without `dynamics` only the velocity update runs (the contact speed
//! limit reads it) and q̂ = q: Nelson & Cohen's least astonishment.

use nalgebra::Vector3;

use super::Program;
use crate::constraint::witness::Witness;
use crate::dynamics::coulomb::{self, Slip, Verdict};
use crate::dynamics::energy::{self, EnergySample};
use crate::dynamics::restitution::Restitution;
use crate::dynamics::velocity::{Velocities, frame};
use crate::force::inertia::BodyMass;
use crate::rotation::BodyFrame;
use crate::{BodyId, Model};

/// Inertial state and scratch of a program.
#[derive(Debug, Clone)]
pub(super) struct Inertial {
    pub vel: Velocities,
    /// Each body's frame at the tick's q (scratch).
    frames: Vec<BodyFrame>,
    /// Velocity damping per body, 1/s.
    damping: Vec<f64>,
    /// Per friction pair (`feedback.friction` order): its kinetic state.
    pub slip: Vec<Slip>,
    /// Per friction pair: slipping too slowly for an explicit kinetic force
    /// in the last decision (`arm_slow_slips`).
    slow: Vec<bool>,
    restitution: Restitution,
    /// Rows of the fingers (their work is the energy the hand puts in).
    finger_rows: Vec<usize>,
    /// Work of the fingers since the program's start, J.
    pub work_j: f64,
    /// The last tick's energy figures.
    pub energy: EnergySample,
    /// Ticks solved again for a friction transition.
    pub resolves: u64,
    /// Contact rows that bounced (restitution).
    pub bounces: u64,
    /// Per shaped moving body of the projected step's `reach`: its index in
    /// `masses`, and its radius.
    reach: Vec<(usize, f64)>,
    /// Per model body: its index in `masses` (`None`: fixed).
    body_mass: Vec<Option<usize>>,
}

impl Inertial {
    /// The state of `model` at rest. Allocates.
    pub fn new(
        model: &Model,
        masses: &[BodyMass],
        finger_rows: Vec<usize>,
        friction_pairs: usize,
        reach: &[(usize, f64)],
    ) -> Self {
        let body = |m: &BodyMass| {
            model
                .layout()
                .moving_bodies()
                .find(|&(_, o)| o == m.offset)
                .map(|(id, _)| &model.bodies()[id.index()])
        };
        let damping = masses
            .iter()
            .map(|m| body(m).map_or(0.0, |b| b.damping_per_s))
            .collect();
        let mut row_e = vec![0.0; model.n_rows()];
        for p in &model.contact().pairs {
            let e = p
                .bodies
                .iter()
                .map(|b| model.bodies()[b.index()].restitution)
                .fold(0.0, f64::max);
            for r in model.constraints()[p.normal.index()].rows.clone() {
                row_e[r] = e;
            }
        }
        Self {
            vel: Velocities::new(masses.len()),
            frames: vec![BodyFrame::IDENTITY; masses.len()],
            damping,
            slip: vec![Slip::default(); friction_pairs],
            slow: vec![false; friction_pairs],
            restitution: Restitution::new(model.n_coords(), row_e, masses, &model.gravity_m_s2()),
            finger_rows,
            work_j: 0.0,
            energy: EnergySample::default(),
            resolves: 0,
            bounces: 0,
            body_mass: (0..model.bodies().len())
                .map(|b| {
                    let o = model.layout().body_offset(BodyId(b as u32))?;
                    masses.iter().position(|m| m.offset == o)
                })
                .collect(),
            reach: reach
                .iter()
                .filter_map(|&(o, r)| masses.iter().position(|m| m.offset == o).map(|k| (k, r)))
                .collect(),
        }
    }
}

impl Program {
    /// Resets every body's velocity: the scene's initial velocities while the
    /// program has never ticked, else rest (a jump is not a motion).
    ///
    /// # Real-time
    /// No allocation; O(bodies).
    pub(super) fn reset_velocities(&mut self) {
        let ticked = self.inertial.vel.ticked;
        self.inertial.vel.rest();
        if ticked {
            return;
        }
        for (k, m) in self.feedback.masses.iter().enumerate() {
            let Some(b) = body_of(&self.model, m.offset) else {
                continue;
            };
            if let Some(f) = frame(&self.q, m.offset) {
                let b = &self.model.bodies()[b.index()];
                self.inertial
                    .vel
                    .set(k, m, &f, b.velocity_m_s, b.angular_velocity_rad_s);
            }
        }
    }

    /// Body `body`'s velocity (m/s) and angular velocity (rad/s), world
    /// frame, over the last tick (`None` for a fixed or unknown body).
    pub fn body_velocity(&self, body: BodyId) -> Option<(Vector3<f64>, Vector3<f64>)> {
        let o = self.model.layout().body_offset(body)?;
        let k = self.feedback.masses.iter().position(|m| m.offset == o)?;
        Some((self.inertial.vel.v[k], self.inertial.vel.w[k]))
    }

    /// Per model body, its speed (m/s) and angular speed (rad/s) over the
    /// last tick (fixed bodies: 0), into `out`.
    ///
    /// # Real-time
    /// No allocation when `out` holds a body count's capacity.
    pub fn body_speeds(&self, out: &mut Vec<[f64; 2]>) {
        out.clear();
        let vel = &self.inertial.vel;
        out.extend(
            self.inertial
                .body_mass
                .iter()
                .map(|k| k.map_or([0.0; 2], |k| [vel.v[k].norm(), vel.w[k].norm()])),
        );
    }

    /// The last tick's energy figures (`valid` only with inertial motion).
    pub fn energy(&self) -> EnergySample {
        self.inertial.energy
    }

    /// Ticks solved again because a friction pair changed between sticking
    /// and slipping, and contact rows that bounced, since the program's
    /// start (carried across hand-overs).
    pub fn transitions(&self) -> (u64, u64) {
        (self.inertial.resolves, self.inertial.bounces)
    }

    /// Sets each shaped body's contact speed allowance for this tick
    /// (`dynamics::allowance_m`). Only bodies with momentum (inertial
    /// motion) get more than `contact_step_m`: without it a body moves only
    /// as far as a finger drags it, and the fixed limit stays.
    ///
    /// # Real-time
    /// No allocation.
    pub(super) fn set_allowances(&mut self, dt_s: f64) {
        let base = self.contact_step_m;
        if !(base.is_finite() && self.settings.dynamics) {
            let all = std::iter::repeat(base);
            self.projected.set_allowances(all);
            return;
        }
        let g = self.model.gravity_m_s2().norm();
        let vel = &self.inertial.vel;
        let allow = self.inertial.reach.iter().map(|&(k, r)| {
            let speed = vel.v[k].norm() + r * vel.w[k].norm();
            crate::dynamics::allowance_m(base, speed, g, dt_s)
        });
        self.projected.set_allowances(allow);
    }

    /// Sets the least-astonishment anchor q̂ of this tick: q, or with
    /// inertial motion the prediction (`dynamics` module docs), kinetic
    /// friction of slipping pairs included.
    ///
    /// # Real-time
    /// No allocation; O(bodies + friction pairs).
    pub(super) fn predict(&mut self, dt_s: f64) {
        self.q_goal.copy_from_slice(&self.q);
        if !self.settings.dynamics {
            return;
        }
        let g = self.model.gravity_m_s2();
        {
            let st = &mut self.inertial;
            for (k, m) in self.feedback.masses.iter().enumerate() {
                st.frames[k] = frame(&self.q, m.offset).unwrap_or(BodyFrame::IDENTITY);
            }
            st.vel
                .predict(&self.feedback.masses, &st.frames, &st.damping, &g, dt_s);
        }
        self.feedback
            .applied
            .fill((Vector3::zeros(), Vector3::zeros()));
        for k in 0..self.feedback.friction.len() {
            let p = self.feedback.friction[k];
            let slip = self.inertial.slip[k];
            if self.feedback.stick[p.rows[0]] || slip.normal_n <= 0.0 {
                continue;
            }
            let Some(point) = contact_point(self, k, &self.q) else {
                continue;
            };
            let force = coulomb::kinetic(&slip, p.mu);
            let moment = self.twist_moment(k, &slip, dt_s);
            let (masses, st) = (&self.feedback.masses, &mut self.inertial);
            for ((kk, f), t) in self.friction_bodies[k]
                .into_iter()
                .zip([force, -force])
                .zip([moment, -moment])
            {
                if let Some(i) = kk {
                    st.vel
                        .push(i, &masses[i], &st.frames[i], &point, &(f * dt_s));
                    st.vel.turn(i, &masses[i], &st.frames[i], &(t * dt_s));
                    // The same force in Eq. 7's balance: a finger pushing a
                    // sliding body feels its friction.
                    let a = &mut self.feedback.applied[i];
                    a.0 += f;
                    a.1 += (point - st.frames[i].r).cross(&f) + t;
                }
            }
        }
        for (k, m) in self.feedback.masses.iter().enumerate() {
            (self.inertial.vel).write_goal(k, m.offset, &self.q, &mut self.q_goal, dt_s);
        }
    }

    /// Coulomb on the step just taken (inertial motion): decides each
    /// friction pair's state from the step's multipliers (`dynamics::coulomb`).
    /// Returns true when a pair changed state (the tick should be solved
    /// again).
    ///
    /// # Real-time
    /// No allocation; O(friction pairs × their rows).
    pub(super) fn decide_friction(&mut self, dt_s: f64) -> bool {
        let mut changed = false;
        self.inertial.slow.fill(false);
        let inv_dt2 = 1.0 / (dt_s * dt_s);
        for k in 0..self.feedback.friction.len() {
            let p = self.feedback.friction[k];
            // The contact's net normal force: the resultant of its rows
            // (a redundant support's rows may split it into pushes and
            // pulls; their pushes alone would overstate it).
            let y = self.projected.multipliers();
            let normal_n = ((p.normal_rows[0]..p.normal_rows[1])
                .filter(|&i| self.feedback.row_scale()[i] != 0.0)
                .map(|i| -y[i])
                .sum::<f64>()
                * inv_dt2)
                .max(0.0);
            let armed = self.ev.witnesses()[p.slots[0]].is_on();
            if !armed || normal_n <= 0.0 {
                for r in p.all_rows() {
                    self.feedback.stick[r] = false;
                }
                self.inertial.slip[k] = Slip::default();
                continue;
            }
            let twist_m = twist_radius(self, k);
            let pair = &self.model.contact().pairs[self.friction_pair[k]];
            let (Some(fb), Some(fa), Some(fa0), Some(fb0)) = (
                self.model.body_frame(&self.q, pair.bodies[1]),
                self.model.body_frame(&self.q, pair.bodies[0]),
                self.model.body_frame(&self.q_ref, pair.bodies[0]),
                self.model.body_frame(&self.q_ref, pair.bodies[1]),
            ) else {
                continue;
            };
            let table = self.ev.witnesses();
            if self.feedback.stick[p.rows[0]] {
                let mut f_a = Vector3::zeros();
                let mut twist_nm = 0.0;
                for (row, slot) in p.all_rows().zip(p.all_slots()) {
                    if let Witness::Plane(w) = table[slot] {
                        let f = -(fb.rot * w.normal) * (self.lambda[row] * inv_dt2);
                        f_a += f;
                        if Some(row) == p.twist.map(|t| t.0)
                            && let Witness::Plane(c) = table[p.slots[0]]
                        {
                            let arm = fa.point(&w.point) - fa.point(&c.point);
                            let n = crate::force::friction::normal(&self.model, &self.q, table, &p)
                                .unwrap_or_else(Vector3::zeros);
                            twist_nm = n.dot(&arm.cross(&f)).abs();
                        }
                    }
                }
                let verdict = coulomb::sticking(&f_a, twist_nm, p.mu, normal_n, twist_m);
                if verdict == Verdict::Slip {
                    for r in p.all_rows() {
                        self.feedback.stick[r] = false;
                    }
                    // A pair that was sliding slowly (and tried to stick
                    // this tick, `coulomb::slow`) keeps its sliding normal
                    // force: this attempt's includes the impulse of a stop.
                    let was = self.inertial.slip[k].normal_n;
                    self.inertial.slip[k] = Slip {
                        dir: f_a.try_normalize(0.0).unwrap_or_else(Vector3::zeros),
                        normal_n: if was > 0.0 { was } else { normal_n },
                        twist_m,
                    };
                    self.feedback.count_slip();
                    changed = true;
                } else {
                    self.inertial.slip[k] = Slip::default();
                }
                continue;
            }
            let Some(start) = contact_point(self, k, &self.q_ref) else {
                continue;
            };
            let on_a: Vector3<f64> = fa0.rot.tr_mul(&(start - fa0.r));
            let on_b: Vector3<f64> = fb0.rot.tr_mul(&(start - fb0.r));
            let s = (fa.point(&on_a) - fb.point(&on_b)) / dt_s;
            let n = crate::force::friction::normal(&self.model, &self.q, table, &p)
                .unwrap_or_else(Vector3::zeros);
            let s = s - n * n.dot(&s);
            match coulomb::slipping(&s, &self.inertial.slip[k].dir) {
                Verdict::Stick => {
                    self.anchor_at(k, &start, &fa0, &fb0);
                    self.inertial.slip[k] = Slip::default();
                    changed = true;
                }
                _ => {
                    self.inertial.slip[k] = Slip {
                        dir: -s.try_normalize(0.0).unwrap_or_else(Vector3::zeros),
                        normal_n,
                        twist_m,
                    };
                    self.inertial.slow[k] = {
                        let inv_mass: f64 = (self.friction_bodies[k].iter().flatten())
                            .map(|&i| 1.0 / self.feedback.masses[i].mass)
                            .sum();
                        coulomb::slow(s.norm(), p.mu, normal_n, dt_s, inv_mass)
                    };
                }
            }
        }
        changed
    }

    /// After the tick's last solve: each pair still slipping too slowly for
    /// an explicit kinetic force (`coulomb::slow`) tries to stick first on
    /// the next tick, anchored where it is now. (Not within the tick: a
    /// re-solve starts from the tick's start, where that anchor would
    /// fight the other contacts.)
    ///
    /// # Real-time
    /// No allocation; O(friction pairs).
    pub(super) fn arm_slow_slips(&mut self) {
        if !self.settings.dynamics {
            return;
        }
        for k in 0..self.feedback.friction.len() {
            let p = self.feedback.friction[k];
            if !std::mem::take(&mut self.inertial.slow[k]) || self.feedback.stick[p.rows[0]] {
                continue;
            }
            let pair = &self.model.contact().pairs[self.friction_pair[k]];
            let (Some(fa), Some(fb), Some(end)) = (
                self.model.body_frame(&self.q, pair.bodies[0]),
                self.model.body_frame(&self.q, pair.bodies[1]),
                contact_point(self, k, &self.q),
            ) else {
                continue;
            };
            self.anchor_at(k, &end, &fa, &fb);
        }
    }

    /// The kinetic moment of friction about the normal on end A of sliding
    /// pair `k` (`coulomb::twisting`), N·m, world (zero at a fingertip).
    fn twist_moment(&self, k: usize, slip: &Slip, dt_s: f64) -> Vector3<f64> {
        let p = self.feedback.friction[k];
        if slip.twist_m <= 0.0 {
            return Vector3::zeros();
        }
        let Some(n) = crate::force::friction::normal(&self.model, &self.q, self.ev.witnesses(), &p)
        else {
            return Vector3::zeros();
        };
        let vel = &self.inertial.vel;
        let (mut spin, mut inv) = (0.0, 0.0);
        for (kk, sign) in self.friction_bodies[k].into_iter().zip([1.0, -1.0]) {
            if let Some(i) = kk {
                let m = &self.feedback.masses[i];
                spin += sign * n.dot(&vel.w_pred[i]);
                let f = &self.inertial.frames[i];
                inv += n.dot(&(crate::dynamics::velocity::inverse_world_inertia(m, f) * n));
            }
        }
        let slip_m_s = {
            let v = |kk: Option<usize>| kk.map_or(Vector3::zeros(), |i| vel.v_pred[i]);
            let [a, b] = self.friction_bodies[k];
            let s = v(a) - v(b);
            (s - n * n.dot(&s)).norm()
        };
        n * coulomb::twisting(slip, p.mu, spin, slip_m_s, dt_s, inv)
    }

    /// Friction pair `k` sticks, its two points held where they were at the
    /// tick's start (`fa0`, `fb0`: its bodies' frames then): a fingertip's
    /// centre over the point of the body under it, two bodies together at
    /// `point` (world, their contact's centre then).
    fn anchor_at(&mut self, k: usize, point: &Vector3<f64>, fa0: &BodyFrame, fb0: &BodyFrame) {
        let p = self.feedback.friction[k];
        let table = self.ev.witnesses_mut();
        let Witness::Plane(w) = table[p.slots[0]] else {
            return;
        };
        let on_a = if p.finger.is_some() {
            w.point
        } else {
            fa0.rot.tr_mul(&(point - fa0.r))
        };
        let at = fa0.point(&on_a);
        let on_b: Vector3<f64> = fb0.rot.tr_mul(&(at - fb0.r));
        // The twist row keeps its arm, along the first tangent from here.
        let arm = match (p.twist, table[p.slots[0]]) {
            (Some((_, slot)), Witness::Plane(c)) => match table[slot] {
                Witness::Plane(t) => (t.point - c.point).norm(),
                _ => 0.0,
            },
            _ => 0.0,
        };
        let t1 = fb0.rot * w.normal;
        for s in p.slots {
            if let Witness::Plane(w) = &mut table[s] {
                w.point = on_a;
                w.plane_point = on_b;
            }
        }
        if let Some((_, slot)) = p.twist
            && let Witness::Plane(w) = &mut table[slot]
        {
            let there = at + t1 * arm;
            w.point = fa0.rot.tr_mul(&(there - fa0.r));
            w.plane_point = fb0.rot.tr_mul(&(there - fb0.r));
        }
        for r in p.all_rows() {
            self.feedback.stick[r] = true;
        }
    }

    /// After the tick's final step (q evaluated): each body's velocity from
    /// its motion; with inertial motion, restitution and the energy account.
    ///
    /// # Real-time
    /// No allocation; O(bodies + finger rows), O(nnz) on a bounce.
    pub(super) fn finish_motion(&mut self, dt_s: f64) {
        if crate::force::feedback::contact_forces_known(&self.settings) {
            self.feedback.take_contact_forces(
                &self.scaling,
                self.ev.jacobian(),
                self.projected.multipliers(),
                dt_s,
            );
        }
        let masses = &self.feedback.masses;
        let st = &mut self.inertial;
        st.vel.finish(masses, &self.q_ref, &self.q, dt_s);
        if !self.settings.dynamics {
            st.energy = EnergySample::default();
            return;
        }
        st.bounces += u64::from(st.restitution.apply(
            self.ev.jacobian(),
            masses,
            &self.q_ref,
            &self.q,
            &self.q_goal,
            self.ev.values(),
            &self.lambda,
            dt_s,
            &mut st.vel,
        ));
        // The step's displacement, in `g` (scratch of the same length).
        for ((d, a), b) in self.g.iter_mut().zip(&self.q).zip(&self.q_ref) {
            *d = a - b;
        }
        let work = energy::finger_work(
            self.ev.jacobian(),
            &st.finger_rows,
            self.projected.multipliers(),
            &self.g,
            dt_s,
        );
        let g = self.model.gravity_m_s2();
        st.energy = EnergySample {
            valid: true,
            energy_j: energy::mechanical(masses, &st.vel, &self.q_ref, &self.q, &g),
            finger_work_j: st.work_j + 0.5 * work,
        };
        st.work_j += work;
    }

    /// Takes the velocity flags and the energy account over from `old` (a
    /// hand-over; `adopt_state` copies the bodies' velocities as it matches
    /// them, `adopt_friction` the friction states).
    pub(super) fn adopt_inertial(&mut self, old: &Program) {
        self.inertial.vel.copy_flags(&old.inertial.vel);
        self.inertial.work_j = old.inertial.work_j;
        self.inertial.energy = old.inertial.energy;
        self.inertial.resolves = old.inertial.resolves;
        self.inertial.bounces = old.inertial.bounces;
    }
}

/// Where friction pair `k` acts at `q` (world): a fingertip's centre, or
/// for two bodies the centre of pressure of their contact rows in the last
/// step (the held points weighted by the rows' multipliers: the point a
/// sliding block's friction acts at moves with the block), else where its
/// stick rows hold.
fn contact_point(p: &Program, k: usize, q: &[f64]) -> Option<Vector3<f64>> {
    let f = p.feedback.friction[k];
    let pair = &p.model.contact().pairs[p.friction_pair[k]];
    let frames = [
        p.model.body_frame(q, pair.bodies[0])?,
        p.model.body_frame(q, pair.bodies[1])?,
    ];
    let table = p.ev.witnesses();
    let anchor = match table[f.slots[0]] {
        Witness::Plane(w) => Some(frames[0].point(&w.point)),
        _ => None,
    };
    if f.finger.is_some() {
        return anchor;
    }
    let (mut sum, mut weight) = (Vector3::zeros(), 0.0);
    for (r, i) in (f.normal_rows[0]..f.normal_rows[1]).enumerate() {
        let nu = p.lambda[i];
        if nu <= 0.0 {
            continue;
        }
        if let Witness::Plane(w) = table[pair.first_slot + r] {
            let e = usize::from(w.point_end.min(1));
            let held = frames[e].point(&w.point) - frames[1 - e].rot * w.normal * w.margin;
            sum += held * nu;
            weight += nu;
        }
    }
    if weight > 0.0 {
        Some(sum / weight)
    } else {
        anchor
    }
}

/// The torsional friction radius of friction pair `k`, m: two thirds of
/// the mean distance of its contact rows' held points from their centre,
/// weighted by the rows' multipliers (a uniformly pressed disc of radius R
/// resists twisting with μ N ⅔ R); 0 at a fingertip.
fn twist_radius(p: &Program, k: usize) -> f64 {
    let f = p.feedback.friction[k];
    if f.twist.is_none() {
        return 0.0;
    }
    let pair = &p.model.contact().pairs[p.friction_pair[k]];
    let (Some(fa), Some(fb), Some(c)) = (
        p.model.body_frame(&p.q, pair.bodies[0]),
        p.model.body_frame(&p.q, pair.bodies[1]),
        contact_point(p, k, &p.q),
    ) else {
        return 0.0;
    };
    let frames = [fa, fb];
    let (mut sum, mut weight) = (0.0, 0.0);
    for (r, i) in (f.normal_rows[0]..f.normal_rows[1]).enumerate() {
        let nu = p.lambda[i];
        if let (true, Witness::Plane(w)) = (nu > 0.0, p.ev.witnesses()[pair.first_slot + r]) {
            let e = usize::from(w.point_end.min(1));
            sum += (frames[e].point(&w.point) - c).norm() * nu;
            weight += nu;
        }
    }
    if weight > 0.0 {
        2.0 / 3.0 * sum / weight
    } else {
        0.0
    }
}

/// The body whose coordinates start at column `o`.
fn body_of(model: &Model, o: usize) -> Option<BodyId> {
    model
        .layout()
        .moving_bodies()
        .find(|&(_, off)| off == o)
        .map(|(id, _)| id)
}
