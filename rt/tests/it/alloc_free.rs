//! The real-time rules, proved: after warm-up, a running loop (tick body,
//! histogram recording, interval snapshots), mailbox publishing and program
//! hand-over allocate and free nothing on the fast thread.

use haptloop_rt::alloc::{count, is_installed};
use haptloop_rt::clock::{MockClock, Nanos};
use haptloop_rt::exchange::{mailbox, program_channel};
use haptloop_rt::hist::LatencyHistogram;
use haptloop_rt::schedule::{
    Periodic, RunLimit, ScheduleConfig, StopFlag, Tick, TickBody, TickStatus,
};

/// A snapshot the size of a small mechanism's state.
#[derive(Clone)]
struct Snapshot {
    tick: u64,
    q: Vec<f64>,
}

struct Body {
    clock: MockClock,
    work: Vec<f64>,
    out: haptloop_rt::exchange::MailboxWriter<Snapshot>,
}

impl TickBody for Body {
    type Fault = ();
    fn tick(&mut self, tick: &Tick) -> TickStatus<()> {
        for (i, w) in self.work.iter_mut().enumerate() {
            *w = (*w * 0.5 + i as f64).sin();
        }
        let work = &self.work;
        self.out.publish_with(|s| {
            s.tick = tick.index;
            s.q.copy_from_slice(work);
        });
        self.clock.advance(Nanos(150_000));
        TickStatus::Ok
    }
}

#[test]
fn a_running_loop_with_mailbox_and_intervals_allocates_nothing() {
    assert!(
        is_installed(),
        "the counting allocator must be this binary's allocator"
    );
    let clock = MockClock::new(Nanos(1));
    let (mut sched, intervals) = Periodic::new(&ScheduleConfig::default(), clock.clone()).unwrap();
    let (out, mut reader) = mailbox(|| Snapshot {
        tick: 0,
        q: vec![0.0; 64],
    });
    let mut body = Body {
        clock,
        work: vec![1.0; 64],
        out,
    };
    let stop = StopFlag::new();
    sched.run(&mut body, RunLimit::slots(1500), &stop); // warm-up, crosses an interval
    let (_, stats) = count(|| sched.run(&mut body, RunLimit::slots(20_000), &stop));
    assert_eq!(stats.total(), 0, "loop allocated: {stats:?}");
    assert_eq!(sched.report().ticks, 21_500);
    // The reader (another thread in real use) sees the newest snapshot…
    assert_eq!(reader.latest().tick, 21_499);
    // The reporter never read during the run, so after the warm-up's two
    // intervals (1000 + 500 ticks) the counted run handed over five more before
    // the pool ran dry; the rest stays in the open interval. Publishing them
    // (and running dry) allocated nothing.
    let got: Vec<u64> = std::iter::from_fn(|| intervals.try_recv().map(|s| s.ticks)).collect();
    assert_eq!(got, vec![1000, 500, 1000, 1000, 1000, 1000, 1000]);
}

#[test]
fn histogram_recording_allocates_nothing() {
    let mut h = LatencyHistogram::new();
    let (_, stats) = count(|| {
        for v in 0..200_000u64 {
            h.record(v.wrapping_mul(2_654_435_761) % 20_000_000_000);
        }
    });
    assert_eq!(stats.total(), 0);
    assert_eq!(h.count(), 200_000);
}

#[test]
fn program_handover_neither_allocates_nor_frees_on_the_fast_side() {
    let (mut tx, mut rx) = program_channel::<Vec<f64>>(4);
    let mut current = Box::new(vec![0.0; 1024]);
    for round in 0..50 {
        for k in 0..4 {
            tx.try_send(Box::new(vec![(round * 4 + k) as f64; 1024]))
                .unwrap();
        }
        let (n, stats) = count(|| rx.try_swap(&mut current, |old, new| new[1] = old[0]));
        assert_eq!(n, 4);
        assert_eq!(
            stats.total(),
            0,
            "fast side touched the allocator: {stats:?}"
        );
        assert_eq!(tx.collect_all(), 4); // freed here, on the "slow" side
    }
    assert_eq!(current[0], 199.0);
    assert_eq!(
        current[1], 198.0,
        "carry moved state from the replaced program"
    );
    assert_eq!(rx.leaked(), 0);
}
