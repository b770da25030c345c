//! The slow loop: watches the fast loop's newest snapshot, re-projects the
//! mechanism with Newton-KKT placement when the fast loop's violation exceeds
//! its threshold, hands the result over through the program queue, and
//! collects (and drops, here, off the real-time thread) the programs the fast
//! loop hands back. It never blocks the fast loop: it only polls the mailbox
//! and the queue.

use super::messages::{Correction, Handover, RowsStamp, Snapshot};
use haptloop_rt::clock::{Clock, MonotonicClock};
use haptloop_rt::exchange::{MailboxReader, ProgramSender};
use haptloop_rt::hist::{LatencyHistogram, Summary};
use haptloop_solver::{Model, Placement, Program, SolveInfo, SolveStatus, SolverSettings};
use std::sync::Arc;

/// What the slow loop saw and did.
#[derive(Debug, Clone, Copy, Default)]
pub struct SlowStats {
    /// Steps run.
    pub steps: u64,
    /// Snapshots that were newer than the previous step's.
    pub fresh_snapshots: u64,
    /// Largest violation seen in a snapshot, m.
    pub max_seen_violation_m: f64,
    /// Re-projections started (violation over the threshold).
    pub reprojections: u64,
    /// Re-projections from the last good configuration (the snapshot was broken).
    pub recoveries: u64,
    /// Placements that did not converge (the result was still sent if finite).
    pub placements_not_converged: u64,
    /// Programs sent to the fast loop.
    pub programs_sent: u64,
    /// Force factors refreshed and sent to the fast loop (the matvec-only
    /// tick).
    pub factor_refreshes: u64,
    /// Replaced programs collected back and dropped here.
    pub programs_dropped: u64,
    /// The last placement's outcome.
    pub last_placement: Option<SolveInfo>,
    /// The fast loop's force error against the converged reference.
    pub reference: super::reference::ReferenceStats,
    /// Why the force error is not measured in this scene, if it is not.
    pub reference_unsupported: Option<&'static str>,
    /// The contact active set's figures (`None`: no contact machinery).
    pub contact: Option<super::contact::ContactSlowStats>,
    /// Wall time of one step, ns (monotonic clock).
    pub step_ns: Summary,
}

/// The slow loop's state.
pub struct SlowLoop {
    pub(super) snapshots: MailboxReader<Snapshot>,
    pub(super) programs: ProgramSender<Handover>,
    /// Refreshes the running program's force factor (the matvec-only tick).
    pub(super) refresh: Option<super::refresh::RefreshSender>,
    pub(super) model: Arc<Model>,
    /// The same mechanism without fingers (same q layout): re-projection finds
    /// the nearest assembled configuration and lets the fingers land where
    /// they land (holding a finger where a 1-DOF linkage cannot reach would
    /// make the problem infeasible).
    pub(super) joints_only: Model,
    pub(super) settings: SolverSettings,
    /// The scene's design objectives (every program handed over carries them).
    pub(super) objectives: Arc<haptloop_solver::Objectives>,
    /// Placement analysed for `joints_only`.
    pub(super) placement: Placement,
    /// Violation above which the fast loop's configuration is re-projected, m.
    pub(super) threshold_m: f64,
    /// Violation above which a snapshot is considered broken, m.
    pub(super) broken_m: f64,
    pub(super) last_good: Vec<f64>,
    pub(super) stats: SlowStats,
    /// The converged reference of sampled ticks (scenes it supports).
    pub(super) reference: Option<super::reference::ReferenceCheck>,
    /// The contact active set, for scenes with shapes that can touch.
    pub(super) contact: Option<super::contact::ContactLoop>,
    /// Semantic constraints and the hand's holds (scenes with areas or
    /// holds).
    pub(super) semantic: Option<super::semantic::SemanticLoop>,
    /// Wall time of each step, ns.
    pub(super) step_times: LatencyHistogram,
    /// What the run looked like, sampled from the snapshots.
    pub(super) track: super::track::BodyTrack,
    /// The scene's model, whose q layout every snapshot shares (poses).
    pub(super) track_model: Arc<Model>,
    /// Scratch: every body's pose, the contact points.
    pub(super) poses: Vec<haptloop_solver::geometry::Pose3>,
    pub(super) contact_points: Vec<super::track::ContactPoint>,
    /// The live viewer's frame (`--live`).
    pub(super) live: Option<haptloop_rt::exchange::MailboxWriter<super::live::LiveFrame>>,
    /// This step read a new snapshot.
    pub(super) fresh: bool,
}

impl SlowLoop {
    /// One pass: collect returned programs, read the newest snapshot, and
    /// re-project if the fast loop has drifted past the threshold. Its wall
    /// time goes into [`SlowStats::step_ns`].
    pub fn step(&mut self) {
        let clock = MonotonicClock::new();
        let start = clock.now();
        self.fresh = false;
        self.step_untimed();
        self.observe();
        self.step_times.record((clock.now() - start).0);
    }

    /// Samples the newest snapshot into the track and, live, into the
    /// viewer's frame: poses of every body, the active contacts, the
    /// largest violation since the last look.
    fn observe(&mut self) {
        let snap = self.snapshots.latest();
        let t_s = snap.time.as_secs_f64();
        if !self.fresh || !(self.track.wants(t_s) || self.live.is_some()) {
            return;
        }
        let violation = if snap.solved {
            snap.peak_violation_m.max(snap.max_violation_m)
        } else {
            f64::NAN
        };
        super::track::poses_at(&self.track_model, &snap.q, &mut self.poses);
        self.contact_points.clear();
        if let Some(c) = &self.contact {
            c.contacts(&mut self.contact_points);
        }
        let snap = self.snapshots.latest();
        self.track.offer(
            t_s,
            &self.poses,
            &self.contact_points,
            violation,
            &snap.finger_force_n,
        );
        if let Some(live) = &mut self.live {
            let sample = self
                .track
                .sample(&self.poses, &self.contact_points, violation);
            let events = self.semantic.as_ref().map_or(&[][..], |s| s.events());
            live.publish_with(|f| {
                f.t_s = t_s;
                f.sample = sample;
                if f.events.len() != events.len() {
                    f.events = events.to_vec();
                }
            });
        }
    }

    fn step_untimed(&mut self) {
        self.stats.steps += 1;
        self.check_reference();
        while let Some(spent) = self.programs.collect() {
            self.stats.programs_dropped += 1;
            if let Some(c) = &mut self.contact {
                c.recycle(spent.program);
            }
        }
        if !self.snapshots.refresh() {
            return;
        }
        self.fresh = true;
        self.stats.fresh_snapshots += 1;
        if let Some(r) = &mut self.refresh {
            let snap = self.snapshots.latest();
            if snap.solved {
                r.step(&snap.q);
            }
            self.stats.factor_refreshes = r.sent;
        }
        if self.semantic.is_some() && self.semantic_step() {
            return;
        }
        let snap = self.snapshots.latest();
        if let Some(c) = &mut self.contact {
            let q = snap.q.clone();
            let at = super::contact::At {
                tick: snap.tick,
                motion: snap.contact_motion,
            };
            c.set_speeds(&snap.speeds);
            if c.step(&q, at, snap.solved, &mut self.programs) {
                return;
            }
        }
        let snap = self.snapshots.latest();
        let v = snap.max_violation_m;
        // Over every tick since the last look, not just the newest: a
        // violation cycling with the look's own period would alias away.
        let peak = snap.peak_violation_m;
        self.stats.max_seen_violation_m = self.stats.max_seen_violation_m.max(v.max(peak));
        let finite = v.is_finite() && snap.q.iter().all(|x| x.is_finite());
        if snap.solved && finite && v <= self.threshold_m && peak <= self.threshold_m {
            self.last_good.clear();
            self.last_good.extend_from_slice(&snap.q);
            return;
        }
        // One re-projection in flight at a time: wait until the fast loop has
        // swapped the last one in and handed its predecessor back.
        if self.programs.in_flight() > 0 {
            return;
        }
        let broken = !(snap.solved && finite && v <= self.broken_m);
        let recover = broken && !self.last_good.is_empty();
        let snapshot_q = snap.q.clone();
        self.reproject(&snapshot_q, recover);
    }

    /// Compares the newest sampled tick with its converged reference
    /// (`session::reference`), if there is a new one.
    pub fn check_reference(&mut self) {
        if let Some(r) = &mut self.reference {
            r.check();
        }
    }

    fn reproject(&mut self, snapshot_q: &[f64], recover: bool) {
        self.stats.reprojections += 1;
        self.stats.recoveries += u64::from(recover);
        let mut q = if recover {
            self.last_good.clone()
        } else {
            snapshot_q.to_vec()
        };
        let q_ref = q.clone();
        let info = match self.placement.solve(&self.joints_only, &mut q, &q_ref, &[]) {
            Ok(info) => info,
            Err(_) => return,
        };
        self.stats.last_placement = Some(info);
        if info.status != SolveStatus::Converged {
            self.stats.placements_not_converged += 1;
        }
        if !q.iter().all(|x| x.is_finite()) {
            return;
        }
        let correction = if recover {
            Correction::Reset(q)
        } else {
            Correction::Shift(q.iter().zip(snapshot_q).map(|(a, b)| a - b).collect())
        };
        let program = match &self.contact {
            Some(c) => c.program_for_current(),
            None => {
                Program::with_objectives(self.model.clone(), self.objectives.clone(), self.settings)
                    .ok()
            }
        };
        let Some(program) = program else {
            return;
        };
        if let Some(r) = &mut self.refresh {
            r.follow(&program);
        }
        if self
            .programs
            .try_send(Box::new(Handover {
                program,
                correction,
                snapshot_tick: None,
                rows: RowsStamp::Keep,
                broken: false,
                generation: None,
            }))
            .is_ok()
        {
            self.stats.programs_sent += 1;
        }
    }

    /// The semantic cycle on the newest snapshot; when the satisfied
    /// constraints or holds changed and no program is in flight, a program
    /// with their rows is sent (returns true: the contact cycle and any
    /// re-projection wait for the next step).
    fn semantic_step(&mut self) -> bool {
        let snap = self.snapshots.latest();
        let (q, forces, t_s, solved) = (
            snap.q.clone(),
            snap.finger_force_n.clone(),
            snap.time.as_secs_f64(),
            snap.solved,
        );
        let Some(sem) = &mut self.semantic else {
            return false;
        };
        if solved {
            sem.step(&q, &forces, t_s);
        } else {
            sem.step_unsolved(t_s);
        }
        if !sem.dirty() || self.programs.in_flight() > 0 {
            return false;
        }
        let clock = haptloop_rt::clock::MonotonicClock::new();
        let start = haptloop_rt::clock::Clock::now(&clock);
        let Some(model) = sem.take_model() else {
            return false;
        };
        // Added bodies go where the scene placed them: the contact cycle
        // sees them there, and the fast loop's q is shifted there.
        let placed = sem.placed_q(&q);
        let at = placed.as_deref().unwrap_or(&q);
        let program = match &mut self.contact {
            Some(c) => {
                if sem.take_absent_changed() {
                    c.set_absent(&sem.absent_bodies());
                }
                c.rebase(model.clone(), at)
            }
            None => {
                // Re-projections hand over programs of this model from now on.
                self.model = model.clone();
                Program::with_objectives(model, self.objectives.clone(), self.settings).ok()
            }
        };
        let ns = (haptloop_rt::clock::Clock::now(&clock) - start).0;
        let correction = match &placed {
            Some(p) => Correction::Shift(p.iter().zip(&q).map(|(a, b)| a - b).collect()),
            None => Correction::None,
        };
        let sent = program.is_some_and(|program| {
            self.programs
                .try_send(Box::new(Handover {
                    program,
                    correction,
                    snapshot_tick: None,
                    rows: RowsStamp::Keep,
                    broken: false,
                    generation: None,
                }))
                .is_ok()
        });
        sem.placements_sent(sent);
        sem.note_program(sent, ns);
        self.stats.programs_sent += u64::from(sent);
        sent
    }

    /// What the semantic loop saw and did (scenes with areas or holds).
    pub fn semantic_report(&self) -> Option<super::semantic::SemanticReport> {
        self.semantic
            .as_ref()
            .map(super::semantic::SemanticLoop::report)
    }

    /// What the run looked like (every body, contacts, violation).
    pub fn track(&self) -> super::track::BodyTrack {
        self.track.clone()
    }

    /// What it saw and did.
    pub fn stats(&self) -> SlowStats {
        let mut s = self.stats;
        s.contact = self.contact.as_ref().map(|c| c.stats());
        if let Some(r) = &self.reference {
            s.reference = r.stats();
        }
        s.step_ns = self.step_times.summary();
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scenes::resolve;
    use crate::session::{Plan, SessionOptions, build};
    use haptloop_rt::clock::{MockClock, Nanos};
    use haptloop_rt::schedule::{Tick, TickBody};

    fn tick(fast: &mut super::super::FastLoop<MockClock>, k: u64) {
        let t = Nanos((k + 1) * 1_000_000);
        fast.tick(&Tick {
            index: k,
            deadline: t,
            start: t,
        });
    }

    fn joint_violation(model: &Model, q: &[f64]) -> f64 {
        let mut ev = model.evaluation();
        ev.evaluate_values(model, q, &[]).unwrap();
        ev.values().iter().fold(0.0, |a, v| a.max(v.abs()))
    }

    fn four_bar() -> (crate::scenes::Scene, Plan) {
        let scene = resolve("four-bar").unwrap();
        let options = SessionOptions {
            seconds: 1.0,
            deterministic: true,
            ..SessionOptions::default()
        };
        let plan = Plan::new(&scene, &options).unwrap();
        (scene, plan)
    }

    /// The fast loop's q is pushed 0.1 mm off its joints and published: the
    /// slow loop places the nearest assembled configuration and sends a shift;
    /// right after the hand-over (before any tick could repair it on its own)
    /// the fast loop's q is assembled again, close to where it was.
    #[test]
    fn a_violating_configuration_is_reprojected_and_shifted_in() {
        let (scene, plan) = four_bar();
        let mut b = build(&scene, &plan, MockClock::new(Nanos(0))).unwrap();
        for k in 0..10 {
            tick(&mut b.fast, k);
        }
        let assembled = b.fast.program().q().to_vec();
        let mut push = vec![0.0; assembled.len()];
        push[0] = 1e-4; // the crank's x: pulls the crank off its pivot
        b.fast.program.program.shift_q(&push).unwrap();
        let q = b.fast.program().q().to_vec();
        let v = joint_violation(&scene.compiled.joints_only, &q);
        assert!(v > 5e-5, "the push broke the joints: {v:e}");
        b.fast.snapshot.publish_with(|s| {
            s.q.clear();
            s.q.extend_from_slice(&q);
            s.max_violation_m = v;
            s.solved = true;
        });
        b.slow.step();
        let st = b.slow.stats();
        assert_eq!(
            (st.reprojections, st.recoveries, st.programs_sent),
            (1, 0, 1)
        );
        assert_eq!(st.last_placement.unwrap().status, SolveStatus::Converged);
        let swapped = b
            .fast
            .programs
            .try_swap(&mut b.fast.program, |old, new| new.take_over(old));
        assert_eq!(swapped, 1);
        let after = b.fast.program().q();
        assert!(
            joint_violation(&scene.compiled.joints_only, after) < 1e-12,
            "not assembled after the shift"
        );
        let moved = after
            .iter()
            .zip(&assembled)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(
            moved < 1e-4,
            "the nearest assembled configuration is near the old one: moved {moved:e}"
        );
    }

    /// A broken snapshot (violation beyond a tenth of the mechanism's size,
    /// solve failed): the slow loop re-places the last good configuration and
    /// sends a reset; the fast loop runs assembled again after the hand-over.
    #[test]
    fn a_broken_snapshot_is_recovered_from_the_last_good_configuration() {
        let (scene, plan) = four_bar();
        let mut b = build(&scene, &plan, MockClock::new(Nanos(0))).unwrap();
        for k in 0..10 {
            tick(&mut b.fast, k);
        }
        b.slow.step(); // records the last good configuration
        assert_eq!(b.slow.stats().reprojections, 0);
        let garbage = vec![1e3; b.fast.program().q().len()];
        b.fast.snapshot.publish_with(|s| {
            s.q.clear();
            s.q.extend_from_slice(&garbage);
            s.max_violation_m = 1e3;
            s.solved = false;
        });
        b.slow.step();
        let st = b.slow.stats();
        assert_eq!(
            (st.reprojections, st.recoveries, st.programs_sent),
            (1, 1, 1)
        );
        tick(&mut b.fast, 10);
        assert_eq!(
            b.fast.stats().programs_swapped,
            1,
            "swapped in at the tick boundary"
        );
        let q = b.fast.program().q();
        assert!(
            q.iter().all(|x| x.abs() < 1.0),
            "the reset replaced the broken q"
        );
        assert!(joint_violation(&scene.compiled.joints_only, q) < 1e-9);
        assert!(b.fast.program().last_report().max_violation_m < 1e-9);
    }
}
