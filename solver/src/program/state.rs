//! Moving state into a program: a placement result (`set_q`) or the state of
//! the program it replaces (`adopt_state`).

use super::{FingerOutput, Program, ProgramError};
use crate::BodyId;
use crate::reduced::History;

impl Program {
    /// Replaces q (e.g. with a Newton-KKT placement result). The motion history
    /// restarts at rest at the new q (a jump is not a motion, so it must not
    /// produce a velocity spike); multipliers are kept; the Eq. 7 matrix is
    /// refactored at the new q (the projected update steps with it). Outputs
    /// are zeroed until the next tick.
    ///
    /// # Real-time
    /// No allocation; one evaluation and one force solve (the cost of a
    /// tick's force part).
    pub fn set_q(&mut self, q: &[f64]) -> Result<(), ProgramError> {
        if q.len() != self.q.len() {
            return Err(ProgramError::Length {
                expected: self.q.len(),
                got: q.len(),
            });
        }
        if let Some(index) = q.iter().position(|v| !v.is_finite()) {
            return Err(ProgramError::NonFinite { index });
        }
        self.q.copy_from_slice(q);
        self.q_ref.copy_from_slice(q);
        self.anchor_rolling();
        self.feedback.motion.reset(q);
        self.reset_velocities();
        // A failed refresh (a q that cannot be evaluated) shows up as the
        // status of the next tick.
        let _ = self.refresh();
        self.outputs.fill(FingerOutput::default());
        self.joint_resync(History::Rest);
        Ok(())
    }

    /// Shifts q by `dq` as a *correction*, not a motion: q, the least-
    /// astonishment anchor and the motion history move together, so velocities
    /// and accelerations (and with them the Eq. 7 inertial force) carry on
    /// unchanged. This is how a re-projection computed on the slow thread for
    /// an earlier q is applied to the q the fast loop has moved on to. A failed
    /// refresh shows up as the next tick's status.
    ///
    /// # Real-time
    /// No allocation; one evaluation and one force solve.
    pub fn shift_q(&mut self, dq: &[f64]) -> Result<(), ProgramError> {
        if dq.len() != self.q.len() {
            return Err(ProgramError::Length {
                expected: self.q.len(),
                got: dq.len(),
            });
        }
        if let Some(index) = dq
            .iter()
            .zip(&self.q)
            .position(|(d, q)| !(d + q).is_finite())
        {
            return Err(ProgramError::NonFinite { index });
        }
        let nb = self.model.layout().body_coords();
        for (i, d) in dq.iter().enumerate() {
            // A re-projection never moves a switched-off design variable.
            if i >= nb && self.design_off_flags().get(i - nb) == Some(&true) {
                continue;
            }
            self.q[i] += d;
            self.q_ref[i] += d;
            self.feedback.motion.q_prev[i] += d;
        }
        self.anchor_rolling();
        let _ = self.refresh();
        self.joint_resync(History::Shift);
        Ok(())
    }

    /// Takes over from `old` at a hand-over (called on the fast thread): q, its
    /// motion history and the finger coupling history, matched body by body
    /// and finger by finger (same index first, else by name); the multipliers
    /// of every constraint that survives (same name, kind and row count; same
    /// index first, else the first such constraint by name). Bodies, design
    /// variables and constraints without a match keep this program's values
    /// (q0, zero multipliers). The last report and outputs are carried too.
    ///
    /// # Real-time
    /// No allocation. O(n) when the models share their structure (the usual
    /// case: `Model::with_inequalities` keeps every index); O(n²) string
    /// comparisons in the worst case of a re-ordered model; plus one
    /// evaluation and force solve (the new program's factor at the adopted q)
    /// unless the program was prepared for the hand-over on the slow thread
    /// ([`prepare_handover`](Self::prepare_handover)).
    pub fn adopt_state(&mut self, old: &Program) {
        // A reference count, not an allocation: keeps the model borrowable
        // while `self` is refreshed below.
        let model = std::sync::Arc::clone(&self.model);
        let (new_m, old_m) = (&*model, &*old.model);
        let mo = &old.feedback.motion;
        // Bodies: q, q_prev and velocity history.
        // `masses` lists the moving bodies in layout order.
        for (k, (id, no)) in new_m.layout().moving_bodies().enumerate() {
            let same = |i: usize, j: usize| new_m.bodies()[i].name == old_m.bodies()[j].name;
            let Some(from) = match_index(id.index(), old_m.bodies().len(), same) else {
                continue;
            };
            let Some(oo) = old_m.layout().body_offset(BodyId(from as u32)) else {
                continue;
            };
            self.q[no..no + 7].copy_from_slice(&old.q[oo..oo + 7]);
            if let Some(ok) = old.feedback.masses.iter().position(|m| m.offset == oo) {
                self.feedback.motion.copy_body(k, mo, ok);
                self.feedback.motion.q_prev[no..no + 7].copy_from_slice(&mo.q_prev[oo..oo + 7]);
                self.feedback.motion.copy_contact(no, mo, oo, 7);
                self.inertial.vel.copy_body(k, &old.inertial.vel, ok);
            }
        }
        self.adopt_inertial(old);
        // Design variables.
        let (nd, od) = (new_m.layout().design_vars(), old_m.layout().design_vars());
        for (i, d) in nd.iter().enumerate() {
            let found = match_index(i, od.len(), |a, b| nd[a].name == od[b].name);
            if let Some(j) = found.filter(|&j| od[j].width == d.width) {
                for c in 0..d.width {
                    self.q[d.offset + c] = old.q[od[j].offset + c];
                    self.feedback.motion.q_prev[d.offset + c] = mo.q_prev[od[j].offset + c];
                }
                let _ = self.set_design_active(i, old.design_active(j));
            }
        }
        // Auxiliary blocks (flexible deformations, surface parameters), by
        // name and width.
        let (na, oa) = (new_m.layout().aux_blocks(), old_m.layout().aux_blocks());
        let (n_start, o_start) = (self.feedback.motion.aux_start, mo.aux_start);
        for (i, b) in na.iter().enumerate() {
            let found = match_index(i, oa.len(), |a, c| na[a].name == oa[c].name);
            if let Some(j) = found.filter(|&j| oa[j].width == b.width) {
                let (n, o) = (b.offset, oa[j].offset);
                self.q[n..n + b.width].copy_from_slice(&old.q[o..o + b.width]);
                self.feedback.motion.q_prev[n..n + b.width]
                    .copy_from_slice(&mo.q_prev[o..o + b.width]);
                let (nm, om) = (n - n_start, o - o_start);
                let m = &mut self.feedback.motion;
                m.aux_v[nm..nm + b.width].copy_from_slice(&mo.aux_v[om..om + b.width]);
                m.aux_a[nm..nm + b.width].copy_from_slice(&mo.aux_a[om..om + b.width]);
            }
        }
        self.feedback.motion.ticks = mo.ticks;
        self.q_ref.copy_from_slice(&self.q);
        // Multipliers of surviving constraints.
        let (nc, oc) = (new_m.constraints(), old_m.constraints());
        self.lambda.fill(0.0);
        for (i, c) in nc.iter().enumerate() {
            let same = |a: usize, b: usize| {
                nc[a].name == oc[b].name
                    && nc[a].kind == oc[b].kind
                    && nc[a].rows.len() == oc[b].rows.len()
            };
            if let Some(j) = match_index(i, oc.len(), same) {
                for (r_new, r_old) in c.rows.clone().zip(oc[j].rows.clone()) {
                    self.lambda[r_new] = old.lambda[r_old];
                }
            }
        }
        self.saved_lambda.copy_from_slice(&self.lambda);
        // Fingers.
        let (nf, of) = (new_m.fingers(), old_m.fingers());
        for k in 0..nf.len() {
            if let Some(j) = match_index(k, of.len(), |a, b| nf[a].name == of[b].name) {
                self.last_targets[k] = old.last_targets[j];
            }
        }
        // Coupling histories before the refresh: a proxy's coupling rate is
        // a difference with them.
        for k in 0..nf.len() {
            if let Some(j) = match_index(k, of.len(), |a, b| nf[a].name == of[b].name) {
                self.feedback.copy_finger(k, &old.feedback, j);
                self.outputs[k] = old.outputs[j];
            }
        }
        self.set_static_shift(old.static_shift());
        self.adopt_friction(old);
        self.adopt_semantic(old);
        // A factor prepared on the slow thread for a recent snapshot
        // (`prepare_handover`) is kept: the fast thread does not refactor.
        if !std::mem::take(&mut self.prepared) {
            let _ = self.refresh();
        }
        self.measure_objectives();
        self.report = old.report;
        self.joint_adopt(old);
    }

    /// Friction contacts that survive a hand-over (same fingertip, same
    /// touched body) keep their stick state and anchors: a new set of pairs
    /// elsewhere in the scene must not make a held object slip.
    ///
    /// # Real-time
    /// No allocation; O(friction pairs²) name comparisons.
    fn adopt_friction(&mut self, old: &Program) {
        let (nm, om) = (&*self.model, &*old.model);
        fn name(m: &crate::Model, b: crate::BodyId) -> &str {
            m.bodies()[b.index()].name.as_str()
        }
        for k in 0..self.feedback.friction.len() {
            let np = &nm.contact().pairs[self.friction_pair[k]];
            let Some(j) = (0..old.feedback.friction.len()).find(|&j| {
                let op = &om.contact().pairs[old.friction_pair[j]];
                name(nm, np.bodies[0]) == name(om, op.bodies[0])
                    && name(nm, np.bodies[1]) == name(om, op.bodies[1])
            }) else {
                continue;
            };
            let (n, o) = (self.feedback.friction[k], old.feedback.friction[j]);
            self.inertial.slip[k] = old.inertial.slip[j];
            let pairs = n
                .all_rows()
                .zip(o.all_rows())
                .zip(n.all_slots().zip(o.all_slots()));
            for ((rn, ro), (sn, so)) in pairs {
                self.feedback.stick[rn] = old.feedback.stick[ro];
                let w = old.ev.witnesses()[so];
                self.ev.witnesses_mut()[sn] = w;
            }
        }
    }
}

/// Index in the old table of the item matching new item `i`: `i` itself when
/// it matches, else the first match by `same(i, j)`.
fn match_index(i: usize, n_old: usize, same: impl Fn(usize, usize) -> bool) -> Option<usize> {
    if i < n_old && same(i, i) {
        return Some(i);
    }
    (0..n_old).find(|&j| same(i, j))
}
