//! The session: a scene, its devices, the pinned fast loop, the slow loop and
//! a reporter, wired together. This is where device → fast loop → force lives.
//!
//! ```text
//!  main thread: build Program + Rig, assemble, then report (status line, trace.csv)
//!  fast thread (rt::schedule, pinned): FastLoop::tick  ──snapshot──►  slow thread: SlowLoop::step
//!                                                       ◄──programs──
//! ```
//!
//! Deterministic mode runs the same fast loop on a mock clock, as fast as
//! possible, with the slow loop stepped in lockstep every few ticks on the same
//! thread, so two runs produce bit-identical results.

mod build;
mod catch_up;
mod contact;
mod design;
mod device_limits;
pub mod energy;
mod fast;
mod live;
mod messages;
mod plan;
mod recorder;
mod reference;
mod refresh;
mod rig;
mod semantic;
mod slow;
mod stall;
mod stats;
pub mod timing;
pub mod track;
mod witness_age;

pub use build::build;
pub use contact::{
    At, ContactLoop, ContactSlowStats, Interpenetration, Received, WitnessFrame, WitnessInbox,
    broken_penetration_m, held_penetration_cap_m,
};
pub use design::{DesignColumns, DesignStats, DesignTracker, Range4};
pub use device_limits::DeviceLimitTicks;
pub use fast::{FastLoop, MAX_SIMULATED_PERIODS, SessionFault, TraceSample};
pub use live::{FingerFrame, LiveFrame, LiveHook, LivePointer, LiveSources};
pub use messages::{Correction, Handover, RowsStamp, Snapshot};
pub use plan::{DEFAULT_REFERENCE_EVERY, Plan, SessionOptions};
pub use recorder::{Recorder, Series};
pub use reference::{
    REFERENCE_GAIN, REFERENCE_MAX_ITERATIONS, REFERENCE_TOLERANCE_M, ReferenceCapture,
    ReferenceCheck, ReferenceSample, ReferenceStats,
};
pub use rig::{Rig, SessionDevice, VirtualOutcome, device_trajectory};
pub use semantic::{Event, EventKind, SemanticLoop, SemanticPlan, SemanticReport};
pub use slow::{SlowLoop, SlowStats};
pub use stall::Stall;
pub use stats::{FailureKind, FingerStats, RunStats, StallStats};
pub use timing::{Stage, StageClock, StageTimes};
pub use track::{BodyTrack, FingerTrack, TrackSample};
pub use witness_age::{WINDOW_CYCLES, WitnessAge};

use crate::scenes::Scene;
use anyhow::{Context, Result};
use crossbeam::queue::ArrayQueue;
use haptloop_devices::TraceStream;
use haptloop_rt::clock::{Clock, MockClock, MonotonicClock, Nanos};
use haptloop_rt::exchange::MailboxWriter;
use haptloop_rt::schedule::{
    IntervalReceiver, LoopHistograms, LoopReport, Periodic, RunLimit, StopFlag, Tick, TickBody,
    TickStatus, spawn_loop,
};
use haptloop_rt::thread::Granted;
use haptloop_solver::SolveInfo;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

/// Slots in the trace queue: 32 s of one finger at 1 kHz, so a stalled
/// reporter loses nothing for a long while (drops are counted, never hidden).
const TRACE_QUEUE: usize = 1 << 15;
/// Programs in flight between the slow and fast loops.
const PROGRAM_QUEUE: usize = 4;
/// Environment variable that delays `build` by that many milliseconds (at
/// most 60 s): lets tests interrupt a session while it is being built.
pub const SLOW_BUILD_ENV: &str = "HAPTLOOP_TEST_SLOW_BUILD_MS";
/// Rows per device a recording may queue between two drains by the reporter
/// (every 100 ms, or every slow step when deterministic): 1.6 s at 20 kHz.
const RECORD_QUEUE: usize = 1 << 15;
/// The slow loop's period in real time, and in ticks in deterministic mode at
/// 1 kHz (scaled with the rate).
const SLOW_PERIOD: Duration = Duration::from_millis(5);

/// Everything a finished session measured.
pub struct SessionOutcome {
    /// The resolved plan (settings, rate, duration).
    pub plan: Plan,
    /// The scheduler's counts and percentiles.
    pub report: LoopReport,
    /// The scheduler's histograms.
    pub histograms: LoopHistograms,
    /// What the OS granted (None in deterministic mode).
    pub granted: Option<Granted>,
    /// The fast loop's statistics.
    pub stats: RunStats,
    /// The slow loop's statistics.
    pub slow: SlowStats,
    /// Initial assembly before the clock started.
    pub assembly: Option<SolveInfo>,
    /// Trace series for plots, and the newest sample per finger.
    pub recorder: Recorder,
    /// Model finger names, in model order.
    pub fingers: Vec<String>,
    /// Device model per model finger.
    pub finger_devices: Vec<String>,
    /// Trace samples dropped because the queue was full.
    pub trace_dropped: u64,
    /// Safety events per device: (device name, event text, count).
    pub device_events: Vec<(String, String, u64)>,
    /// Per device, the joint torques its motors applied after the loop
    /// stopped (N·m; `None` if the device cannot report them): zero on every
    /// exit, read at the motor.
    pub torque_at_exit_nm: Vec<(String, Option<[f64; 3]>)>,
    /// True if the run was stopped early (Ctrl-C, SIGTERM, SIGHUP).
    pub stopped_early: bool,
    /// Wall-clock seconds the run took (the only field that differs between
    /// two deterministic runs).
    pub wall_clock_s: f64,
    /// Every body's pose, the contacts and the violation over the run.
    pub track: BodyTrack,
    /// Which coordinates the fast loop's tick ran in, and why
    /// (`Program::coordinates`).
    pub coordinates: String,
    /// Joint ticks of the final program that failed and ran as augmented
    /// ticks (`Program::joint_fallbacks`).
    pub joint_fallbacks: u64,
    /// Translational joint rows of the model (0: a scene of free bodies,
    /// whose joint violation cannot be measured).
    pub joint_rows: usize,
    /// How the design variables and objectives moved (empty without any).
    pub design: DesignStats,
    /// Semantic events and the grouping graph (scenes with areas or holds).
    pub semantic: Option<SemanticReport>,
    /// What each virtual device did (scenes with any).
    pub virtual_devices: Vec<VirtualOutcome>,
    /// Per device: its workspace stops, clamps, saturations and thermal cuts
    /// (and a replay's comparison with its recording).
    pub device_limits: Vec<DeviceLimitTicks>,
}

/// Everything the loops need, built before the clock starts.
pub struct Built<C: Clock> {
    /// The fast loop's tick body.
    pub fast: FastLoop<C>,
    /// The slow loop.
    pub slow: SlowLoop,
    /// The queue of trace samples the reporter drains.
    pub trace: Arc<ArrayQueue<TraceSample>>,
    /// One stream per device when recording (`--record`), drained by the
    /// reporter into `<device>.trace`.
    pub device_traces: Vec<TraceStream>,
    /// The initial assembly.
    pub assembly: Option<SolveInfo>,
    /// The reporter's end of the design-variable trace (scenes with design
    /// variables or objectives).
    pub design: Option<DesignColumns>,
    /// The live viewer's ends (`--live`) and the reporter's finger end.
    live: Option<(LiveSources, MailboxWriter<FingerFrame>)>,
}

/// Hands the viewer its ends of the exchange and the reporter its finger
/// end (live sessions).
fn start_live(
    plan: &Plan,
    live: Option<(LiveSources, MailboxWriter<FingerFrame>)>,
    recorder: &mut Recorder,
) {
    if let (Some(hook), Some((sources, fingers))) = (&plan.live, live) {
        recorder.attach_live(fingers);
        (hook.0)(sources);
    }
}

impl<C: Clock> Built<C> {
    /// Starts the live exchange of a built session (`plan.live`): hands the
    /// hook the viewer's ends and `recorder` the reporter's (what `run`
    /// does when the loops start; public for tests that drive the loops
    /// themselves).
    pub fn start_live(&mut self, plan: &Plan, recorder: &mut Recorder) {
        start_live(plan, self.live.take(), recorder);
    }
}

/// Sessions whose loops are running, process-wide. While none is (a session
/// is still being built: program, factorisations, assembly), there is nothing
/// to stop at a tick boundary, so the command line's signal handler exits at
/// once instead of waiting for the build ([`loops_running`]).
static LOOPS_RUNNING: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);

/// True while some session's loops are running in this process.
pub fn loops_running() -> bool {
    LOOPS_RUNNING.load(Ordering::Acquire) > 0
}

/// Set when a session's loops start, and never cleared: from then on a
/// signal has ticks whose figures are worth writing.
static STARTED: AtomicBool = AtomicBool::new(false);

/// True once some session's loops have started in this process (a signal
/// before that has nothing to stop at a tick boundary and nothing to report).
pub fn started() -> bool {
    STARTED.load(Ordering::Acquire)
}

/// Counts a session's loops as running while alive.
struct LoopsRunning;

impl LoopsRunning {
    fn start() -> Self {
        LOOPS_RUNNING.fetch_add(1, Ordering::AcqRel);
        STARTED.store(true, Ordering::Release);
        LoopsRunning
    }
}

impl Drop for LoopsRunning {
    fn drop(&mut self) {
        LOOPS_RUNNING.fetch_sub(1, Ordering::AcqRel);
    }
}

/// Runs `scene` as planned. `stop` ends it early (at a tick boundary) and the
/// outcome is still complete. `on_status` receives a one-line status about
/// once a second (real time) in real-time mode.
pub fn run(
    scene: &Scene,
    plan: Plan,
    stop: &StopFlag,
    on_status: &mut dyn FnMut(&str),
) -> Result<SessionOutcome> {
    let names: Vec<String> = scene
        .compiled
        .model
        .fingers()
        .iter()
        .map(|f| f.name.clone())
        .collect();
    let injected = !plan.stalls.is_empty() || !plan.slow_stalls.is_empty();
    if injected && !plan.deterministic {
        anyhow::bail!(
            "injected stalls (--stall, --slow-stall) need a deterministic run (--deterministic)"
        );
    }
    let wall_start = MonotonicClock::new().now();
    let ticks = plan.ticks();
    let mut recorder = Recorder::new(&names, ticks, plan.out_dir.as_deref())?;
    if plan.deterministic {
        let f = run_deterministic(scene, &plan, stop, &mut recorder, &names)?;
        finish(scene, plan, stop, recorder, names, f, wall_start)
    } else {
        let f = run_real_time(scene, &plan, stop, &mut recorder, &names, on_status)?;
        finish(scene, plan, stop, recorder, names, f, wall_start)
    }
}

/// Saves recorded device traces and gathers everything into the outcome.
fn finish<C: Clock>(
    scene: &Scene,
    plan: Plan,
    stop: &StopFlag,
    mut recorder: Recorder,
    names: Vec<String>,
    finished: Finished<C>,
    wall_start: Nanos,
) -> Result<SessionOutcome> {
    recorder.finish()?;
    let (report, histograms, granted, fast, slow, assembly, trace, track, semantic) = finished;
    let device_events = fast
        .rig()
        .devices
        .iter()
        .flat_map(|d| {
            d.device
                .counters()
                .events()
                .map(|(e, n)| (d.name.clone(), e.to_string(), n))
                .collect::<Vec<_>>()
        })
        .collect();
    let torque_at_exit_nm = fast
        .rig()
        .devices
        .iter()
        .map(|d| {
            let t = haptloop_devices::Device::applied_torque_nm(d.device.device())
                .map(|t| [t.x, t.y, t.z]);
            (d.name.clone(), t)
        })
        .collect();
    let force_max: Vec<f64> = recorder
        .force
        .iter()
        .map(|f| f.points.iter().map(|p| p.1).fold(0.0, f64::max))
        .collect();
    let virtual_devices = fast.rig().virtual_outcomes(&recorder.latest, &force_max);
    Ok(SessionOutcome {
        torque_at_exit_nm,
        stopped_early: stop.is_requested(),
        trace_dropped: trace,
        plan,
        report,
        histograms,
        granted,
        stats: fast.stats().clone(),
        slow,
        assembly,
        recorder,
        finger_devices: scene
            .compiled
            .fingers
            .iter()
            .map(|f| scene.compiled.devices[f.device].model.clone())
            .collect(),
        fingers: names,
        device_events,
        wall_clock_s: (MonotonicClock::new().now() - wall_start).0 as f64 / 1e9,
        track,
        joint_rows: joint_length_rows(&scene.compiled.model),
        coordinates: fast.program().coordinates().to_string(),
        joint_fallbacks: fast.program().joint_fallbacks(),
        design: fast.design_stats(),
        semantic,
        virtual_devices,
        device_limits: DeviceLimitTicks::of(fast.rig()),
    })
}

/// Length rows of joints (not fingers, contacts or quaternion norms): what
/// the violation figures measure.
fn joint_length_rows(model: &haptloop_solver::Model) -> usize {
    use haptloop_solver::{ConstraintKind, RowUnit};
    model
        .rows()
        .iter()
        .filter(|r| {
            let c = &model.constraints()[r.constraint.index()];
            r.unit == RowUnit::Length
                && c.finger.is_none()
                && !matches!(
                    c.kind,
                    ConstraintKind::Contact | ConstraintKind::ContactFriction
                )
        })
        .count()
}

type Finished<C> = (
    LoopReport,
    LoopHistograms,
    Option<Granted>,
    FastLoop<C>,
    SlowStats,
    Option<SolveInfo>,
    u64,
    BodyTrack,
    Option<SemanticReport>,
);

/// The fast loop and the slow loop on one thread, in lockstep: deterministic.
struct Lockstep<'a> {
    fast: FastLoop<MockClock>,
    slow: SlowLoop,
    every: u64,
    recorder: &'a mut Recorder,
    trace: &'a ArrayQueue<TraceSample>,
    names: &'a [String],
    error: Option<anyhow::Error>,
    stalls: stall::StallPlayer,
    /// The slow-loop cycle of the last slow step.
    slow_cycle: u64,
}

impl TickBody for Lockstep<'_> {
    type Fault = SessionFault;
    fn tick(&mut self, tick: &Tick) -> TickStatus<SessionFault> {
        let status = self.fast.tick(tick);
        // Every sampled tick is compared, in order: nothing is overwritten.
        if self.fast.sampled() {
            self.slow.check_reference();
        }
        self.stalls.after_tick(tick.index);
        // One slow step per slow period of session time that ended by this
        // tick (a tick after skipped slots may close one whose last slot it
        // skipped).
        let cycle = (tick.index + 1) / self.every;
        if cycle > self.slow_cycle && !self.stalls.slow_stalled(tick.index) {
            self.slow_cycle = cycle;
            self.slow.step();
            if let Err(e) = self.recorder.drain(self.trace, self.names) {
                self.error.get_or_insert(e);
            }
        }
        status
    }
    fn on_safety(&mut self, event: haptloop_rt::schedule::SafetyEvent<SessionFault>) {
        self.fast.on_safety(event);
    }
    fn on_stop(&mut self) {
        self.fast.on_stop();
    }
}

fn run_deterministic(
    scene: &Scene,
    plan: &Plan,
    stop: &StopFlag,
    recorder: &mut Recorder,
    names: &[String],
) -> Result<Finished<MockClock>> {
    let clock = MockClock::new(Nanos(0));
    let mut built = build(scene, plan, clock.clone())?;
    recorder.attach_device_traces(std::mem::take(&mut built.device_traces));
    recorder.attach_design(built.design.take())?;
    start_live(plan, built.live.take(), recorder);
    let stalls = stall::StallPlayer::new(
        &plan.stalls,
        &plan.slow_stalls,
        plan.rate_hz,
        plan.period(),
        clock.clone(),
    );
    let (mut periodic, _intervals) = Periodic::new(&plan.schedule(), clock)?;
    let _running = LoopsRunning::start();
    let every = ((SLOW_PERIOD.as_secs_f64() * f64::from(plan.rate_hz)).round() as u64).max(1);
    let mut body = Lockstep {
        fast: built.fast,
        slow: built.slow,
        every,
        recorder,
        trace: &built.trace,
        names,
        error: None,
        stalls,
        slow_cycle: 0,
    };
    periodic.run(&mut body, RunLimit::slots(plan.ticks()), stop);
    body.on_stop();
    body.slow.step();
    body.recorder.drain(&built.trace, names)?;
    if let Some(e) = body.error {
        return Err(e);
    }
    let dropped =
        (body.fast.stats().ticks * names.len() as u64).saturating_sub(body.recorder.samples);
    Ok((
        periodic.report(),
        periodic.histograms().clone(),
        None,
        body.fast,
        body.slow.stats(),
        built.assembly,
        dropped,
        body.slow.track(),
        body.slow.semantic_report(),
    ))
}

fn run_real_time(
    scene: &Scene,
    plan: &Plan,
    stop: &StopFlag,
    recorder: &mut Recorder,
    names: &[String],
    on_status: &mut dyn FnMut(&str),
) -> Result<Finished<MonotonicClock>> {
    let built = build(scene, plan, MonotonicClock::new())?;
    let Built {
        fast,
        mut slow,
        trace,
        device_traces,
        assembly,
        design,
        live,
    } = built;
    recorder.attach_device_traces(device_traces);
    recorder.attach_design(design)?;
    start_live(plan, live, recorder);
    let _running = LoopsRunning::start();
    let handle = spawn_loop(
        &plan.schedule(),
        MonotonicClock::new(),
        fast,
        stop.clone(),
        RunLimit::duration(plan.duration()),
    )?;
    let done = Arc::new(AtomicBool::new(false));
    let slow_done = done.clone();
    let slow_thread = std::thread::Builder::new()
        .name("haptloop-slow".into())
        .spawn(move || {
            while !slow_done.load(Ordering::Acquire) {
                slow.step();
                std::thread::sleep(SLOW_PERIOD);
            }
            slow.step();
            slow
        })
        .context("spawning the slow loop")?;
    report_live(
        &handle.intervals,
        &trace,
        recorder,
        names,
        plan,
        &|| handle.is_finished(),
        on_status,
    )?;
    let out = handle.join()?;
    done.store(true, Ordering::Release);
    let slow = slow_thread
        .join()
        .map_err(|_| anyhow::anyhow!("the slow loop panicked"))?;
    recorder.drain(&trace, names)?;
    let dropped = (out.body.stats().ticks * names.len() as u64).saturating_sub(recorder.samples);
    Ok((
        out.report,
        out.histograms,
        Some(out.granted),
        out.body,
        slow.stats(),
        assembly,
        dropped,
        slow.track(),
        slow.semantic_report(),
    ))
}

/// The reporter: drains trace samples and interval snapshots every 100 ms and
/// emits a status line about once a second, until the loop has finished.
fn report_live(
    intervals: &IntervalReceiver,
    trace: &ArrayQueue<TraceSample>,
    recorder: &mut Recorder,
    names: &[String],
    plan: &Plan,
    finished: &dyn Fn() -> bool,
    on_status: &mut dyn FnMut(&str),
) -> Result<()> {
    let mut misses = 0u64;
    // A live viewer shows the fingers as the reporter drains them: at
    // display rate then, else ten times a second.
    let every = if plan.live.is_some() {
        Duration::from_millis(10)
    } else {
        Duration::from_millis(100)
    };
    while !finished() {
        std::thread::sleep(every);
        recorder.drain(trace, names)?;
        while let Some(iv) = intervals.try_recv() {
            misses += iv.misses.total();
            let secs = (iv.ended - iv.started).0 as f64 / 1e9;
            let rate = if secs > 0.0 {
                iv.ticks.saturating_sub(1) as f64 / secs
            } else {
                0.0
            };
            let force: Vec<String> = recorder
                .latest
                .iter()
                .zip(names)
                .map(|(s, n)| {
                    let f = s.force_n;
                    format!(
                        "{n} {:.2} N",
                        (f[0] * f[0] + f[1] * f[1] + f[2] * f[2]).sqrt()
                    )
                })
                .collect();
            let t = recorder.latest.first().map_or(0.0, |s| s.t_s);
            // No joint rows: nothing to violate, and no 0 that says otherwise.
            let violation = if plan.joint_rows > 0 {
                let v = recorder.latest.first().map_or(f64::NAN, |s| s.violation_m);
                format!("{v:8.2e} m")
            } else {
                "    none".to_string()
            };
            on_status(&format!(
                "t {t:5.1}/{:.0} s | {rate:6.0} Hz | misses {misses} | lateness p99 {:6.1} µs | violation {violation} | {}",
                plan.seconds,
                iv.lateness.quantile(0.99) as f64 / 1e3,
                force.join(", ")
            ));
        }
    }
    Ok(())
}
