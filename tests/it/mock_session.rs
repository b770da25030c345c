//! A session on the mock clock, built the way the lockstep tests build it:
//! the plan, the session, its periodic scheduler and a stop flag, so a test
//! states only what it runs and checks.

use haptloop::scenes::Scene;
use haptloop::session::{self, Built, Plan, SessionOptions};
use haptloop_rt::clock::{MockClock, Nanos};
use haptloop_rt::schedule::{IntervalReceiver, Periodic, RunLimit, StopFlag};

/// One session on a mock clock starting at 0.
pub struct MockSession {
    /// The session's plan.
    pub plan: Plan,
    /// The clock the scheduler and the session share.
    pub clock: MockClock,
    /// The built session (fast and slow loops, trace queue).
    pub built: Built<MockClock>,
    /// The scheduler that runs the fast loop's ticks.
    pub periodic: Periodic<MockClock>,
    /// Its stop flag (never raised here).
    pub stop: StopFlag,
    /// Kept alive so the scheduler's 1 s intervals have a reader.
    pub _intervals: IntervalReceiver,
}

impl MockSession {
    /// Builds `scene` with `options` (which should be deterministic).
    pub fn new(scene: &Scene, options: &SessionOptions) -> MockSession {
        let plan = Plan::new(scene, options).unwrap();
        let clock = MockClock::new(Nanos(0));
        let built = session::build(scene, &plan, clock.clone()).unwrap();
        let (periodic, intervals) = Periodic::new(&plan.schedule(), clock.clone()).unwrap();
        MockSession {
            plan,
            clock,
            built,
            periodic,
            stop: StopFlag::new(),
            _intervals: intervals,
        }
    }

    /// Runs the fast loop for `slots` grid slots.
    pub fn run(&mut self, slots: u64) {
        self.periodic
            .run(&mut self.built.fast, RunLimit::slots(slots), &self.stop);
    }
}
