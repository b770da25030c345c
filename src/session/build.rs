//! Building a session: the program (assembled, with its semantic and contact
//! rows), the devices, the exchange between the loops and every buffer the
//! fast loop will use, before the clock starts.

use std::sync::Arc;
use std::time::Duration;

use anyhow::{Context, Result};
use crossbeam::queue::ArrayQueue;
use haptloop_devices::{TraceHeader, TraceRecorder, TraceRow, TraceStream};
use haptloop_rt::clock::Clock;
use haptloop_rt::exchange::{MailboxReader, MailboxWriter, mailbox, program_channel};
use haptloop_solver::{Model, Objectives, Placement, PlacementOptions, Program, SolveInfo};
use nalgebra::Vector3;

use super::reference::{ReferenceCapture, ReferenceCheck};
use super::{
    Built, ContactLoop, DesignTracker, FastLoop, FingerFrame, Handover, LiveFrame, LivePointer,
    LiveSources, PROGRAM_QUEUE, Plan, RECORD_QUEUE, Rig, RunStats, SLOW_BUILD_ENV, SemanticLoop,
    SemanticPlan, SlowLoop, SlowStats, Snapshot, StageClock, TRACE_QUEUE, WitnessFrame,
    WitnessInbox, design, live, reference, refresh, track,
};
use crate::scenes::Scene;

mod start;

use start::{Start, assemble, with_contact, with_semantic};

/// Builds the program (and assembles the scene), the devices (registered on
/// their fingers), the exchange between the loops and every buffer the fast
/// loop will use. All allocation of a session happens here.
pub fn build<C: Clock>(scene: &Scene, plan: &Plan, clock: C) -> Result<Built<C>> {
    stretch_for_tests();
    let mut start = assemble(scene, plan)?;
    with_semantic(&mut start, scene, plan)?;
    with_contact(&mut start, scene, plan)?;
    let Start {
        model,
        mechanism,
        objectives,
        program,
        q,
        assembly,
        options,
        semantic,
        contact,
        inbox,
    } = start;
    // The converged reference of sampled ticks, where it applies.
    let reference_unsupported = reference::unsupported(contact.is_some());
    let (capture, check) = references(&program, plan, reference_unsupported)?;
    let program = Box::new(Handover::new(program));
    let rig = Rig::build(scene, plan.rate_hz, plan.replay.as_deref(), plan.duration())?;
    let n_fingers = model.fingers().len();
    let (snapshot, snapshots) = snapshot_mailbox(&model);
    let (programs_tx, programs_rx) = program_channel(PROGRAM_QUEUE);
    let (refresh_tx, refresh_rx) = refresh::channel(&program.program).unzip();
    let trace = Arc::new(ArrayQueue::new(TRACE_QUEUE));
    let (recorders, device_traces) = recording(scene, plan, &rig)?;
    let (design, design_columns) =
        DesignTracker::new(&model, &objectives, program.program.q()).unzip();
    let limits = Limits::of(&model, plan, inbox.is_some());
    let rig_devices = rig.devices.len();
    let fast = FastLoop {
        clock,
        period: plan.period(),
        program,
        broken_m: limits.broken_m,
        broken_penetration_m: limits.broken_penetration_m,
        witness_age: limits.witness_age,
        programs: programs_rx,
        refresh: refresh_rx,
        targets: model.initial_targets(),
        catch_up: super::catch_up::TargetCatchUp::new(n_fingers),
        snapshot,
        trace: trace.clone(),
        stats: RunStats::new(n_fingers),
        last_index: None,
        cut_until: 0,
        violation_peak_m: 0.0,
        health: vec![haptloop_devices::Health::Ok; rig_devices],
        counts: vec![[0; 3]; rig_devices],
        orientations: vec![[1.0, 0.0, 0.0, 0.0]; rig_devices],
        rig,
        recorders,
        inbox,
        design,
        switches: design::DesignSchedule::new(&scene.compiled.design_flags),
        reference: capture,
        sampled: false,
        timer: StageClock::default(),
        rendered: vec![Vector3::zeros(); n_fingers],
        commanded: vec![Vector3::zeros(); n_fingers],
    };
    let (live_frames, live) = live_exchange(&fast.rig, scene, plan);
    let mut slow = SlowLoop {
        track: track::BodyTrack::of_model(&model),
        track_model: model.clone(),
        poses: Vec::new(),
        contact_points: Vec::new(),
        live: live_frames,
        fresh: false,
        snapshots,
        programs: programs_tx,
        refresh: refresh_tx,
        model: mechanism,
        settings: plan.solver,
        objectives,
        placement: Placement::analyze(&scene.compiled.joints_only, &options)
            .context("analysing the scene's joints for re-projection")?,
        joints_only: scene.compiled.joints_only.clone(),
        threshold_m: limits.threshold_m,
        broken_m: limits.broken_m,
        last_good: q.clone(),
        stats: SlowStats {
            reference_unsupported,
            ..SlowStats::default()
        },
        reference: check,
        contact,
        semantic,
        step_times: haptloop_rt::hist::LatencyHistogram::new(),
    };
    start_track(&mut slow, &model, &q, n_fingers);
    Ok(Built {
        fast,
        slow,
        device_traces,
        trace,
        assembly,
        design: design_columns,
        live,
    })
}

/// The converged reference's capture (fast loop) and check (slow loop),
/// unless `unsupported` says why not or the plan samples no tick.
fn references(
    program: &Program,
    plan: &Plan,
    unsupported: Option<&'static str>,
) -> Result<(Option<ReferenceCapture>, Option<ReferenceCheck>)> {
    Ok(match unsupported {
        Some(_) => (None, None),
        None if plan.reference_every_ticks == 0 => (None, None),
        None => {
            let (c, k) = reference::pair(program, plan.reference_every_ticks)
                .context("building the converged reference")?;
            (Some(c), Some(k))
        }
    })
}

/// The snapshot mailbox, its buffers sized for `model`.
fn snapshot_mailbox(model: &Model) -> (MailboxWriter<Snapshot>, MailboxReader<Snapshot>) {
    let n = model.n_coords();
    let n_fingers = model.fingers().len();
    mailbox(|| Snapshot {
        q: Vec::with_capacity(n),
        solved: true,
        finger_force_n: Vec::with_capacity(n_fingers),
        speeds: Vec::with_capacity(model.bodies().len()),
        ..Snapshot::default()
    })
}

/// A testing aid: stretch the build (off the real-time thread, before any
/// device is driven) so a test can signal the process while it builds.
fn stretch_for_tests() {
    if let Some(ms) = std::env::var(SLOW_BUILD_ENV)
        .ok()
        .and_then(|v| v.parse::<u64>().ok())
    {
        std::thread::sleep(Duration::from_millis(ms.min(60_000)));
    }
}

/// When the loops call the mechanism broken or re-project it.
struct Limits {
    /// A violation above this triggers a re-projection, m.
    threshold_m: f64,
    /// A violation above this means the mechanism came apart, m.
    broken_m: f64,
    /// A penetration above this means the world came apart, m.
    broken_penetration_m: f64,
    /// The witness rows' age, which bounds the motion (contact scenes).
    witness_age: Option<super::witness_age::WitnessAge>,
}

impl Limits {
    /// A violation above the scene's tolerance (else 0.1 mm) triggers a
    /// re-projection; one above a tenth of the mechanism's size means it
    /// came apart. Contact (`contact`): a penetration beyond its bound
    /// means the world came apart; the witness rows' age bounds the motion
    /// (`witness_age`).
    fn of(model: &Model, plan: &Plan, contact: bool) -> Self {
        let threshold_m = plan.violation_tolerance_m.unwrap_or(1e-4);
        let broken_m = (0.1 * model.characteristic_length_m()).max(threshold_m * 10.0);
        let (broken_penetration_m, witness_age) = if contact {
            let per_cycle = (super::SLOW_PERIOD.as_secs_f64() * f64::from(plan.rate_hz)).round();
            (
                super::contact::broken_penetration_m(&plan.contact),
                Some(super::witness_age::WitnessAge::new(
                    per_cycle.max(1.0) as u64
                )),
            )
        } else {
            (f64::INFINITY, None)
        };
        Self {
            threshold_m,
            broken_m,
            broken_penetration_m,
            witness_age,
        }
    }
}

/// The live viewer's exchange: the slow loop and the reporter write, the
/// viewer reads; the fast loop takes no part.
#[allow(clippy::type_complexity)]
fn live_exchange(
    rig: &Rig,
    scene: &Scene,
    plan: &Plan,
) -> (
    Option<MailboxWriter<LiveFrame>>,
    Option<(LiveSources, MailboxWriter<FingerFrame>)>,
) {
    match &plan.live {
        None => (None, None),
        Some(_) => {
            let pointers = fast_pointers(rig, scene);
            let (sinks, sources) = live::exchange(pointers);
            (Some(sinks.frames), Some((sources, sinks.fingers)))
        }
    }
}

/// The track starts at the assembled configuration `q`, at t = 0, the
/// fingers at rest.
fn start_track(slow: &mut SlowLoop, model: &Model, q: &[f64], n_fingers: usize) {
    track::poses_at(model, q, &mut slow.poses);
    if let Some(c) = &slow.contact {
        c.contacts(&mut slow.contact_points);
    }
    let at_rest = vec![[0.0; 3]; n_fingers];
    slow.track
        .offer(0.0, &slow.poses, &slow.contact_points, 0.0, &at_rest);
}

/// Recording streams (`--record`): the fast loop pushes rows into a bounded
/// queue per device, the reporter writes them out as the run goes (no buffer
/// for the whole run; a full queue drops and counts rows). The first row is
/// the reading each device was registered with, so a replay registers
/// identically.
fn recording(
    scene: &Scene,
    plan: &Plan,
    rig: &Rig,
) -> Result<(Vec<TraceRecorder>, Vec<TraceStream>)> {
    let Some(dir) = &plan.record else {
        return Ok((Vec::new(), Vec::new()));
    };
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let mut recorders = Vec::new();
    let mut streams = Vec::new();
    for (k, d) in scene.compiled.devices.iter().enumerate() {
        let header = TraceHeader {
            scene: scene.compiled.name.clone(),
            model: d.model.clone(),
            rate_hz: plan.rate_hz,
        };
        let (mut rec, stream) = TraceRecorder::streaming(header, RECORD_QUEUE);
        if let Some(r) = rig.registered[k] {
            let q = r.orientation_device.quaternion();
            rec.record(TraceRow {
                time: Duration::ZERO,
                counts: r.joint_counts,
                command_n_device: Vector3::zeros(),
                output_n_device: Vector3::zeros(),
                hand_offset_m_device: Vector3::zeros(),
                orientation_wxyz: [q.w, q.i, q.j, q.k],
            });
        }
        let path = dir.join(format!("{}.trace", d.name));
        streams.push(
            stream
                .create(&path)
                .with_context(|| format!("recording device `{}`", d.name))?,
        );
        recorders.push(rec);
    }
    Ok((recorders, streams))
}

/// The pointers of the virtual devices, with the mounts they were
/// registered with.
fn fast_pointers(rig: &Rig, scene: &Scene) -> Vec<LivePointer> {
    rig.pointers
        .iter()
        .zip(&rig.devices)
        .zip(&scene.compiled.devices)
        .filter_map(|((p, d), decl)| {
            p.as_ref().map(|p| LivePointer {
                device: decl.name.clone(),
                pointer: p.clone(),
                mount: d.mount,
            })
        })
        .collect()
}
