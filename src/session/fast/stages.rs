//! The fast loop's tick stages (see `fast`'s module docs): handover,
//! device read, solve, safety and write, bookkeeping; each `#[inline]`
//! into `FastLoop::tick`.

use super::*;

/// What one tick's solve produced, for the stages after it.
#[derive(Clone, Copy)]
pub(super) struct Solved {
    pub(super) report: TickReport,
    /// The solve converged to a finite, intact state (neither the linkage nor
    /// the world came apart).
    pub(super) solved: bool,
    /// The solve was finite but a penetration exceeded the broken bound.
    pub(super) apart: bool,
    /// The step simulated.
    pub(super) dt: Duration,
}

impl<C: Clock> FastLoop<C> {
    /// Handover stage: swaps in a program the slow loop sent, applies witness
    /// tables, the contact budget, design switches and refreshed factors.
    #[inline]
    pub(super) fn take_over(&mut self, tick: &Tick, now: Duration) {
        let mut prepared = 0;
        let swapped = self.programs.try_swap(&mut self.program, |old, new| {
            prepared += u64::from(new.program.is_prepared());
            new.take_over(old);
        });
        self.stats.programs_swapped += swapped as u64;
        self.stats.contact.prepared_programs += prepared;
        if swapped > 0 {
            self.swapped_in(tick);
        }
        if let Some(inbox) = &mut self.inbox
            && let Some(got) = inbox.apply(&mut self.program.program)
        {
            if got.table {
                self.stats
                    .contact
                    .record_latency(tick.index.saturating_sub(got.tick));
            }
            if let Some(age) = &mut self.witness_age {
                age.table_from(got.motion);
            }
        }
        if let Some(age) = &mut self.witness_age {
            self.program.program.set_contact_budget(age.budget());
            self.stats.contact.stale_stopped_ticks = age.stopped_ticks;
            self.stats.contact.max_witness_age = age.max_age;
        }
        self.switches
            .apply(now.as_secs_f64(), &mut self.program.program);
        if let Some(r) = &mut self.refresh {
            r.apply(&mut self.program.program);
        }
    }

    /// Bookkeeping for a program just swapped in: its latency, the age of its
    /// witness rows, the inbox generation, and a force cut if it was built
    /// from a broken world.
    #[inline]
    pub(super) fn swapped_in(&mut self, tick: &Tick) {
        if let Some(at) = self.program.snapshot_tick {
            self.stats
                .contact
                .record_latency(tick.index.saturating_sub(at));
        }
        if let Some(age) = &mut self.witness_age {
            match self.program.rows {
                RowsStamp::Keep => {}
                RowsStamp::At(motion) => age.rows_from(motion),
                RowsStamp::Fresh => age.rows_fresh(),
            }
        }
        if let (Some(g), Some(inbox)) = (self.program.generation, &mut self.inbox) {
            inbox.taken_over(g);
        }
        if self.program.broken {
            // The slow loop saw the world come apart: no force from
            // it until the backup has settled.
            self.cut_forces(tick.index);
            self.stats.contact.broken_handovers += 1;
        }
    }

    /// Device-read stage: every finger's target (scene frame), and each
    /// device's encoder counts and gimbal orientation for the recorders.
    #[inline]
    pub(super) fn read_devices(&mut self, now: Duration) {
        for i in 0..self.targets.len() {
            let dev = &mut self.rig.devices[self.rig.finger_device[i]];
            let r = dev.read_scene(now);
            let d = self.rig.finger_device[i];
            self.counts[d] = r.reading.joint_counts;
            let q = r.reading.orientation_device.quaternion();
            self.orientations[d] = [q.w, q.i, q.j, q.k];
            self.targets[i] = self.rig.target(i, r.tip_m_scene, r.orientation_scene);
        }
    }

    /// Update stage: steps the program one period towards the targets (after
    /// a stall, through the catch-up) and judges whether the result may be
    /// rendered.
    #[inline]
    pub(super) fn solve(&mut self, tick: &Tick) -> Solved {
        let steps = self
            .last_index
            .map_or(1, |last| tick.index.saturating_sub(last).max(1));
        self.last_index = Some(tick.index);
        // After skipped slots the world is stepped one period, not the gap:
        // the devices were read at grid time (the hand is where it is), but
        // every per-tick bound of the program (the contact speed limit, the
        // inertial allowance, the active set's reach over a slow-loop
        // cycle, the activation budget) is sized for one period, and a
        // longer step lets bodies pass through each other. The periods not
        // simulated are counted: the world's time runs that far behind.
        let simulated = steps.min(MAX_SIMULATED_PERIODS);
        self.stats.stalls.record(steps, steps - simulated);
        let lag = self.catch_up.apply(&mut self.targets, steps, simulated);
        self.stats.stalls.record_lag(lag);
        let dt = self.periods(simulated);
        if let Some(r) = &mut self.reference {
            r.before(tick.index, &self.program.program);
            // Saving the state is bookkeeping, not the update's time.
            self.timer.lap(Stage::Bookkeeping);
        }
        let report = self
            .program
            .program
            .tick_marked(&self.targets, dt, &mut self.timer);
        // A finite but absurd violation (a linkage that came apart) or
        // penetration (bodies inside each other) is a failure too: never
        // render forces computed from it.
        let ok = matches!(report.status, TickOutcome::Ok);
        let apart = ok && report.max_penetration_m > self.broken_penetration_m;
        let solved = ok && report.max_violation_m <= self.broken_m && !apart;
        if let Some(age) = &mut self.witness_age
            && solved
        {
            age.moved(self.program.program.last_contact_motion());
        }
        Solved {
            report,
            solved,
            apart,
            dt,
        }
    }

    /// Safety-and-write stage: each finger's force (zero while `cut`) through
    /// its device's safety layer; records the device traffic. Returns a
    /// device fault latched this tick, if any.
    #[inline]
    pub(super) fn write_forces(&mut self, now: Duration, cut: bool) -> Option<SessionFault> {
        let mut fault = None;
        for i in 0..self.targets.len() {
            let d = self.rig.finger_device[i];
            let out = self.program.program.finger_outputs()[i];
            let command = if cut { Vector3::zeros() } else { out.force_n };
            let dev = &mut self.rig.devices[d];
            let written = dev.write_scene(command, now);
            // What the user feels: the motors' output after the safety layer
            // and the device's own limits (saturation, thermal cut).
            self.rendered[i] = dev.mount.force_to_scene(&written.motor.force_n_device);
            self.commanded[i] = command;
            if let Some(rec) = self.recorders.get_mut(d) {
                rec.record(TraceRow {
                    time: now,
                    counts: self.counts[d],
                    command_n_device: dev.mount.force_to_device(&command),
                    output_n_device: written.force_n_device,
                    hand_offset_m_device: dev.device.device().hand_offset_m_device(now),
                    orientation_wxyz: self.orientations[d],
                });
            }
            let health = dev.device.health();
            if let Health::Fault(kind) = health
                && self.health[d] != health
            {
                fault = Some(SessionFault::Device {
                    device: d as u16,
                    kind,
                });
            }
            self.health[d] = health;
        }
        fault
    }

    /// Per-finger statistics and one trace row per finger (to the lock-free
    /// queue; a full queue drops the row).
    #[inline]
    pub(super) fn record_fingers(&mut self, t_s: f64, s: &Solved) {
        for i in 0..self.targets.len() {
            let out = &self.program.program.finger_outputs()[i];
            let fs: &mut FingerStats = &mut self.stats.fingers[i];
            // A failed solve's attachment point means nothing: its tracking
            // error is not a measurement (the tick is counted as failed).
            let tracking = if s.solved {
                out.tracking_error_m
            } else {
                f64::NAN
            };
            fs.record(&self.commanded[i], &self.rendered[i], tracking);
            let _ = self.trace.push(TraceSample {
                t_s,
                finger: i as u16,
                target_m: self.targets[i].position_m.into(),
                position_m: out.attachment_m.into(),
                force_n: self.rendered[i].into(),
                violation_m: s.report.max_violation_m,
                failed: !s.solved,
            });
        }
    }

    /// Publishes the tick's snapshot (state, violations, forces, speeds) to
    /// the slow loop and the reporter, into its preallocated buffers.
    #[inline]
    pub(super) fn publish(&mut self, tick: &Tick, now: Duration, s: &Solved) {
        let program = &self.program.program;
        let report = &s.report;
        let solved = s.solved;
        let v = report.max_violation_m;
        self.violation_peak_m = if self.snapshot.reader_is_current() || v.is_nan() {
            v
        } else {
            self.violation_peak_m.max(v)
        };
        let peak = self.violation_peak_m;
        let motion = self.witness_age.as_ref().map_or(0.0, |a| a.motion());
        self.snapshot.publish_with(|s| {
            s.tick = tick.index;
            s.time = now;
            s.q.clear();
            s.q.extend_from_slice(program.q());
            s.max_violation_m = report.max_violation_m;
            s.max_violation_rad = report.max_violation_rad;
            s.solved = solved;
            s.finger_force_n.clear();
            s.finger_force_n.extend(
                program
                    .finger_outputs()
                    .iter()
                    .map(|o| <[f64; 3]>::from(o.force_n)),
            );
            s.peak_violation_m = peak;
            s.contact_motion = motion;
            program.body_speeds(&mut s.speeds);
        });
    }
}
