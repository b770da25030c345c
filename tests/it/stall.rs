//! Host stalls (`--stall`): after skipped grid slots the world must stay
//! assembled and non-penetrating and no absurd force may reach a motor.
//! Deterministic sessions with stalls injected on the mock clock; each
//! figure is compared with the scene's own tolerance or with the same run
//! without stalls. Before the fix (the gap simulated in one step, the
//! finger targets jumping the gap's hand motion at once) every assertion
//! below failed (BENCHMARKS.md, "Contact: missed ticks").

use crate::mock_session::MockSession;
use haptloop::report::summary::Summary;
use haptloop::scenes::{Scene, resolve};
use haptloop::session::{self, MAX_SIMULATED_PERIODS, Plan, SessionOptions, Stall};
use haptloop_rt::alloc::count;
use haptloop_rt::clock::{MockClock, Nanos};
use haptloop_rt::schedule::{RunLimit, StopFlag, Tick, TickBody, TickStatus};

/// A deterministic session of `scene` for `seconds` with a stall of
/// `periods` after the tick at every half second from 0.5 s on.
fn run(scene: &Scene, seconds: f64, periods: u64) -> Summary {
    let options = SessionOptions {
        seconds,
        deterministic: true,
        ..SessionOptions::default()
    };
    let mut plan = Plan::new(scene, &options).unwrap();
    if periods > 1 {
        let n = (seconds * 2.0) as u32 - 1;
        plan.stalls = (1..=n)
            .map(|k| Stall {
                at_s: 0.5 * f64::from(k),
                periods,
            })
            .collect();
    }
    let o = session::run(scene, plan, &StopFlag::new(), &mut |_| {}).unwrap();
    Summary::of(&o)
}

fn max_force(s: &Summary) -> f64 {
    s.force_n.values().map(|f| f.max).fold(0.0, f64::max)
}

/// The stalls the run reports are the scheduler's: every skipped slot is
/// a period the world did not simulate, and the report says so.
fn assert_accounted(s: &Summary, stalls: u64, periods: u64) {
    assert_eq!(s.misses.skipped, stalls * (periods - 1), "{}", s.scene);
    assert_eq!(s.stalls.ticks_after_gap, stalls);
    assert_eq!(s.stalls.longest_gap_periods, periods);
    assert_eq!(
        s.stalls.periods_dropped,
        stalls * (periods - periods.min(MAX_SIMULATED_PERIODS))
    );
    let behind = s.stalls.periods_dropped as f64 / f64::from(s.rate_hz);
    assert_eq!(s.stalls.world_behind_s, behind);
    assert!(s.stalls.line().unwrap().contains("periods dropped"));
}

/// 50-period stalls (50 ms) while the pyramid tilts onto a side face: one
/// 50 ms inertial step put it 6.6 mm into the floor; one period a tick
/// keeps it within the scene's tolerance with no backup.
#[test]
fn the_pyramid_stays_on_the_floor_after_long_stalls() {
    let scene = resolve("pyramid-tilt").unwrap();
    let s = run(&scene, 4.0, 50);
    let c = s.contact.as_ref().unwrap();
    assert!(
        c.max_penetration_m <= c.tolerance_m,
        "penetrated {} m (tolerance {} m)",
        c.max_penetration_m,
        c.tolerance_m
    );
    assert_eq!(c.backups, 0);
    assert_eq!(s.safety.solver_failures, 0);
    assert_accounted(&s, 7, 50);
}

/// `arm-push` (a jointed arm pushing a block, inertial) with 5-period
/// stalls: the gap in one step broke the arm's joints 5.5× beyond the
/// scene's tolerance and sent the motor its 8.5 N peak, 8.6× the same run
/// without stalls; 20-period stalls pushed the block 0.15 mm into the
/// floor.
#[test]
fn the_arm_keeps_its_joints_and_the_motor_its_force_after_stalls() {
    let scene = resolve("arm-push").unwrap();
    let calm = run(&scene, 4.0, 1);
    let stalled = run(&scene, 4.0, 5);
    let tol = stalled.violation.tolerance.unwrap();
    assert!(
        stalled.violation.max <= tol,
        "joints violated by {} m (tolerance {tol} m)",
        stalled.violation.max
    );
    let (f, f0) = (max_force(&stalled), max_force(&calm));
    assert!(
        f <= 1.5 * f0,
        "after stalls the motor got {f} N, without them at most {f0} N"
    );
    assert_accounted(&stalled, 7, 5);
    let long = run(&scene, 4.0, 20);
    let c = long.contact.as_ref().unwrap();
    assert!(
        c.max_penetration_m <= c.tolerance_m && c.backups == 0,
        "penetrated {} m (tolerance {} m), {} backups",
        c.max_penetration_m,
        c.tolerance_m,
        c.backups
    );
    assert!(long.violation.max <= tol);
}

/// Stalls the fast loop's clock after every `every`th tick, as a host
/// would.
struct Stalling<'a, B> {
    body: &'a mut B,
    clock: MockClock,
    every: u64,
    stall: Nanos,
}

impl<B: TickBody> TickBody for Stalling<'_, B> {
    type Fault = B::Fault;
    fn tick(&mut self, tick: &Tick) -> TickStatus<B::Fault> {
        let status = self.body.tick(tick);
        if tick.index.is_multiple_of(self.every) {
            self.clock.advance(self.stall);
        }
        status
    }
}

/// The tick after a gap (the world's step capped, the targets caught up)
/// allocates nothing either.
#[test]
fn the_tick_after_a_stall_allocates_nothing() {
    let scene = resolve("arm-push").unwrap();
    let options = SessionOptions {
        seconds: 3.0,
        deterministic: true,
        ..SessionOptions::default()
    };
    let mut m = MockSession::new(&scene, &options);
    m.run(200);
    let period = m.plan.period().as_nanos() as u64;
    let mut body = Stalling {
        body: &mut m.built.fast,
        clock: m.clock.clone(),
        every: 97,
        stall: Nanos(12 * period),
    };
    let (_, stats) = count(|| m.periodic.run(&mut body, RunLimit::slots(2000), &m.stop));
    assert_eq!(stats.total(), 0, "the fast loop allocated: {stats:?}");
    let st = m.built.fast.stats().stalls;
    assert!(st.ticks_after_gap >= 10, "{st:?}");
    assert!(st.catch_up_ticks > 0, "the catch-up path never ran: {st:?}");
    while m.built.trace.pop().is_some() {}
}

/// `--slow-stall` holds the lockstep slow loop back: after a 40-period
/// stall at 1 kHz the 8 slow-loop cycles that ended inside it become one
/// step at its end, 7 fewer steps per stall than the same run without.
/// (The tool that reproduces `cluttered`'s real-time blow-up, BENCHMARKS.md,
/// "Contact: missed ticks"; not fixed.)
#[test]
fn a_slow_stall_holds_the_slow_loop_back() {
    let scene = resolve("pyramid-tilt").unwrap();
    let steps = |stalls: Vec<Stall>| {
        let options = SessionOptions {
            seconds: 2.0,
            deterministic: true,
            ..SessionOptions::default()
        };
        let mut plan = Plan::new(&scene, &options).unwrap();
        plan.slow_stalls = stalls;
        let o = session::run(&scene, plan, &StopFlag::new(), &mut |_| {}).unwrap();
        o.slow.steps
    };
    let calm = steps(Vec::new());
    let stalled = steps(vec![
        Stall {
            at_s: 0.5,
            periods: 40,
        },
        Stall {
            at_s: 1.25,
            periods: 40,
        },
    ]);
    assert_eq!(calm - stalled, 2 * 7, "{calm} against {stalled}");
}
