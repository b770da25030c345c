//! Semantic constraints in the fast loop (Gösele & Stuerzlinger, felt
//! through the device): the slow loop decides which surface constraints are
//! satisfied and hands a program with their rows over; here the program
//!
//! - **ramps each new constraint's snap offsets** to zero. A constraint
//!   satisfied at some misalignment starts with its rows' margins equal to
//!   their values at the hand-over (nothing jumps), then the largest of them
//!   shrinks at [`SnapSettings::speed_m_per_s`](crate::SnapSettings) and the
//!   others in proportion, so the binding area travels onto the offer area
//!   along a straight path. The ramp **pauses** while any finger's force
//!   differs from what it was when the snap began by more than
//!   [`SnapSettings::force_limit_n`](crate::SnapSettings), counting the pull
//!   its braking will still add (k v² / 2a through the coupling): the snap
//!   pulls the user's hand with a bounded force that grows at a bounded rate
//!   (one tick's ramp through the coupling), and a hand that resists holds it;
//! - **carries grouped objects** (§4 dynamic grouping): a body bound to a
//!   moving offer body has its least-astonishment anchor moved with that
//!   parent's last motion, so dragging the table carries the cup (the
//!   objective is measured in the parent's frame) while the cup can still be
//!   slid on the table by itself. A body on several moving parents follows
//!   the one that moved most (§6.1: it is made a successor of the object
//!   being moved). With inertial motion (`dynamics`) the bound rows and the
//!   bodies' momentum carry it and nothing is added.
//!
//! # Real-time
//! No allocation: every buffer is sized by `Program::new`. Per tick
//! O(semantic rows + fingers × ramping surfaces + carried bodies).

use nalgebra::{Quaternion, UnitQuaternion, Vector3};

use super::Program;
use crate::constraint::witness::Witness;
use crate::model::SnapSettings;
use crate::{BodyId, Model};

/// Time a snap's ramp takes to reach its speed (and to brake from it), s:
/// the pull starts and stops with an acceleration of speed / this, so the
/// inertial force of a bound body (Eq. 7) stays small (a 200 g cup at the
/// default 5 cm/s: 0.2 N).
pub const SNAP_RISE_S: f64 = 0.05;

/// A surface whose offsets ramp.
#[derive(Debug, Clone, Copy)]
struct Ramp {
    /// Index of its first row in the evaluation's witness table.
    first: usize,
    /// Its rows (3 plane rows, then inclusion rows).
    slots: usize,
    /// Index of its first row among the semantic slots (`initial`).
    tail: usize,
    /// Fraction of the initial offsets still applied, 1 → 0.
    progress: f64,
    /// The largest |initial offset|, m.
    scale_m: f64,
    /// Speed of the largest offset, m/s.
    speed: f64,
}

/// A body carried with its parents.
#[derive(Debug, Clone, Copy)]
struct Carried {
    /// Its q offset.
    offset: usize,
    /// Its parents: `parents[start..end]` index `Carry::parents`.
    start: usize,
    end: usize,
}

/// The program's semantic state (see the module docs).
#[derive(Debug, Clone)]
pub(super) struct SemanticState {
    snap: SnapSettings,
    ramps: Vec<Ramp>,
    /// Initial offset of each semantic slot, m.
    initial: Vec<f64>,
    /// Per ramp and finger: the finger's force when the snap began, N.
    force_ref: Vec<Vector3<f64>>,
    fingers: usize,
    /// Moving offer bodies with a moving bound body: their q offsets.
    parents: Vec<usize>,
    /// Each parent's pose at the start of the last tick.
    parent_prev: Vec<[f64; 7]>,
    /// Each parent's motion over the last tick (m, rotation at the length scale).
    parent_moved: Vec<f64>,
    /// Indices into `parents`, grouped per carried body.
    parent_of: Vec<usize>,
    carried: Vec<Carried>,
    /// Ticks on which some ramp was paused by the force limit.
    paused_ticks: u64,
}

impl SemanticState {
    /// For a program of `model` starting at q0; `None` without semantic rows.
    /// Allocates.
    pub fn new(model: &Model) -> Option<Self> {
        let sem = model.semantic();
        if sem.is_empty() {
            return None;
        }
        let head = model.contact().slots;
        let ramps = sem
            .surfaces
            .iter()
            .map(|s| Ramp {
                first: head + s.first_slot,
                slots: s.slots,
                tail: s.first_slot,
                progress: 0.0,
                scale_m: 0.0,
                speed: 0.0,
            })
            .collect::<Vec<_>>();
        let fingers = model.fingers().len();
        let col = |b: BodyId| model.layout().body_offset(b);
        let mut parents: Vec<usize> = Vec::new();
        let mut carried: Vec<Carried> = Vec::new();
        let mut parent_of = Vec::new();
        let mut children: Vec<usize> = sem
            .surfaces
            .iter()
            .filter_map(|s| col(s.binding).filter(|_| col(s.offer).is_some()))
            .collect();
        children.sort_unstable();
        children.dedup();
        for child in children {
            let start = parent_of.len();
            for s in &sem.surfaces {
                if col(s.binding) != Some(child) {
                    continue;
                }
                let Some(p) = col(s.offer) else { continue };
                let k = match parents.iter().position(|&x| x == p) {
                    Some(k) => k,
                    None => {
                        parents.push(p);
                        parents.len() - 1
                    }
                };
                if !parent_of[start..].contains(&k) {
                    parent_of.push(k);
                }
            }
            carried.push(Carried {
                offset: child,
                start,
                end: parent_of.len(),
            });
        }
        let mut st = Self {
            snap: sem.snap,
            initial: vec![0.0; sem.slots.len()],
            force_ref: vec![Vector3::zeros(); ramps.len() * fingers],
            ramps,
            fingers,
            parent_prev: vec![[0.0; 7]; parents.len()],
            parent_moved: vec![0.0; parents.len()],
            parents,
            parent_of,
            carried,
            paused_ticks: 0,
        };
        st.reset_parents(model.q0());
        Some(st)
    }

    /// Every parent's last pose := its pose in `q`.
    fn reset_parents(&mut self, q: &[f64]) {
        for (prev, &o) in self.parent_prev.iter_mut().zip(&self.parents) {
            prev.copy_from_slice(&q[o..o + 7]);
        }
        self.parent_moved.fill(0.0);
    }
}

/// The value of a surface row (margin 0) at `q`, m.
fn raw_value(model: &Model, q: &[f64], w: &Witness, ends: [BodyId; 2]) -> f64 {
    let Witness::Plane(p) = w else {
        return 0.0;
    };
    let (Some(a), Some(b)) = (model.body_frame(q, ends[0]), model.body_frame(q, ends[1])) else {
        return 0.0;
    };
    let d = a.point(&p.point) - b.point(&p.plane_point);
    (b.rot * p.normal).dot(&d)
}

impl Program {
    /// At a hand-over: surfaces that `old` ran keep their ramp (offsets,
    /// progress, force reference); new ones start a snap from their
    /// misalignment at the adopted q (equality rows: their value; inclusion
    /// rows: their violation, if any) with `old`'s finger forces as the
    /// reference. Parents' last poses restart at the adopted q.
    ///
    /// # Real-time
    /// No allocation; O(surfaces² name comparisons + rows).
    pub(super) fn adopt_semantic(&mut self, old: &Program) {
        let Some(st) = &mut self.semantic else {
            return;
        };
        let model = &*self.model;
        let sem = model.semantic();
        let old_sem = old.model.semantic();
        for (k, s) in sem.surfaces.iter().enumerate() {
            let r = st.ramps[k];
            let found = old_sem
                .surfaces
                .iter()
                .position(|o| o.name == s.name && o.slots == s.slots);
            let fr = &mut st.force_ref[k * st.fingers..(k + 1) * st.fingers];
            match (found, &old.semantic) {
                (Some(j), Some(os)) => {
                    let or = os.ramps[j];
                    st.ramps[k].progress = or.progress;
                    st.ramps[k].scale_m = or.scale_m;
                    st.ramps[k].speed = or.speed;
                    st.initial[r.tail..r.tail + r.slots]
                        .copy_from_slice(&os.initial[or.tail..or.tail + or.slots]);
                    if os.fingers == st.fingers {
                        fr.copy_from_slice(&os.force_ref[j * os.fingers..(j + 1) * os.fingers]);
                    }
                }
                _ => {
                    let mut scale: f64 = 0.0;
                    for i in 0..r.slots {
                        let w = sem.slots[r.tail + i];
                        let v = raw_value(model, &self.q, &Witness::Plane(w), [s.binding, s.offer]);
                        // Plane rows hold their value; inclusion rows only
                        // a violation.
                        let o = if i < 3 { v } else { v.min(0.0) };
                        st.initial[r.tail + i] = o;
                        scale = scale.max(o.abs());
                    }
                    st.ramps[k].scale_m = scale;
                    st.ramps[k].speed = 0.0;
                    st.ramps[k].progress = if scale > 1e-12 { 1.0 } else { 0.0 };
                    for (f, out) in fr.iter_mut().zip(&old.outputs) {
                        *f = out.force_n;
                    }
                }
            }
        }
        st.reset_parents(&self.q);
        set_margins(st, self.ev.witnesses_mut());
    }

    /// One tick of every ramp (see the module docs).
    ///
    /// # Real-time
    /// No allocation; O(ramping surfaces × (fingers + rows)).
    pub(super) fn ramp_snaps(&mut self, dt_s: f64) {
        let Some(st) = &mut self.semantic else {
            return;
        };
        let v_max = st.snap.speed_m_per_s;
        let accel = v_max / SNAP_RISE_S;
        let k_c = self.settings.coupling_stiffness_n_per_m;
        let mut paused = false;
        for (k, r) in st.ramps.iter_mut().enumerate() {
            if r.progress <= 0.0 {
                continue;
            }
            // The pull the coupling would add while the ramp brakes to rest
            // from its speed: k v² / 2a.
            let braking = k_c * r.speed * r.speed / (2.0 * accel);
            let fr = &st.force_ref[k * st.fingers..(k + 1) * st.fingers];
            let calm = self
                .outputs
                .iter()
                .zip(fr)
                .all(|(o, f)| (o.force_n - f).norm() + braking <= st.snap.force_limit_n);
            paused |= !calm;
            let target = if calm { v_max } else { 0.0 };
            r.speed = if target > r.speed {
                (r.speed + accel * dt_s).min(target)
            } else {
                (r.speed - accel * dt_s).max(target)
            };
            // Arrive at rest: never faster than braking allows.
            let remaining = r.progress * r.scale_m;
            r.speed = r.speed.min((2.0 * accel * remaining).sqrt());
            r.progress = (r.progress - r.speed * dt_s / r.scale_m).max(0.0);
            if r.progress == 0.0 {
                r.speed = 0.0;
            }
        }
        st.paused_ticks += u64::from(paused);
        set_margins(st, self.ev.witnesses_mut());
    }

    /// Moves each carried body's anchor q₀ with its parent's last motion (see
    /// the module docs).
    ///
    /// # Real-time
    /// No allocation; O(parents + carried bodies).
    pub(super) fn carry_groups(&mut self) {
        let Some(st) = &mut self.semantic else {
            return;
        };
        if st.parents.is_empty() {
            return;
        }
        let l = self.scaling.length_m;
        for (k, &o) in st.parents.iter().enumerate() {
            let (now, prev) = (&self.q_ref[o..o + 7], &st.parent_prev[k]);
            let dr = (0..3).map(|c| (now[c] - prev[c]).powi(2)).sum::<f64>();
            let turn = delta(prev, now).angle();
            st.parent_moved[k] = dr.sqrt() + l * turn;
        }
        if !self.settings.dynamics {
            for c in &st.carried {
                let Some(k) = st.parent_of[c.start..c.end]
                    .iter()
                    .copied()
                    .filter(|&k| st.parent_moved[k] > 0.0)
                    .max_by(|&a, &b| st.parent_moved[a].total_cmp(&st.parent_moved[b]))
                else {
                    continue;
                };
                let o = st.parents[k];
                let (prev, now) = (st.parent_prev[k], &self.q_ref[o..o + 7]);
                let d = delta(&prev, now);
                let g = &mut self.q_goal[c.offset..c.offset + 7];
                let rel = Vector3::new(g[0] - prev[0], g[1] - prev[1], g[2] - prev[2]);
                let r = Vector3::new(now[0], now[1], now[2]) + d * rel;
                let e = d.quaternion() * Quaternion::new(g[3], g[4], g[5], g[6]);
                g.copy_from_slice(&[r.x, r.y, r.z, e.w, e.i, e.j, e.k]);
            }
        }
        for (prev, &o) in st.parent_prev.iter_mut().zip(&st.parents) {
            prev.copy_from_slice(&self.q_ref[o..o + 7]);
        }
    }

    /// Satisfied surface constraints whose snap is still ramping.
    pub fn snaps_ramping(&self) -> usize {
        self.semantic
            .as_ref()
            .map_or(0, |s| s.ramps.iter().filter(|r| r.progress > 0.0).count())
    }

    /// Ticks (since this program was built) on which a snap's ramp paused
    /// because a finger's force had moved by the limit.
    pub fn snap_paused_ticks(&self) -> u64 {
        self.semantic.as_ref().map_or(0, |s| s.paused_ticks)
    }
}

/// The rotation from pose `a` to pose `b` (q blocks r, e).
fn delta(a: &[f64], b: &[f64]) -> UnitQuaternion<f64> {
    let ea = UnitQuaternion::from_quaternion(Quaternion::new(a[3], a[4], a[5], a[6]));
    let eb = UnitQuaternion::from_quaternion(Quaternion::new(b[3], b[4], b[5], b[6]));
    eb * ea.inverse()
}

/// Writes progress × initial offset into every semantic row's margin.
fn set_margins(st: &SemanticState, table: &mut [Witness]) {
    for r in &st.ramps {
        for i in 0..r.slots {
            if let Some(Witness::Plane(w)) = table.get_mut(r.first + i) {
                w.margin = r.progress * st.initial[r.tail + i];
            }
        }
    }
}
