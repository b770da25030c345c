//! Exchange benchmarks: mailbox publish and read, program hand-over, and the
//! alternatives the mailbox was chosen over, in one run.
//!
//! `cargo bench -p haptloop-rt --bench exchange`
//!
//! Criterion reports medians. Criterion does not report tail percentiles of
//! single operations, so after it, a distribution pass times batches of 32
//! operations with the monotonic clock (≈ 20 ns per read, amortised over the
//! batch) and prints p50/p99/p99.9 of the per-operation time.

use criterion::{BenchmarkId, Criterion};
use crossbeam::queue::ArrayQueue;
use haptloop_rt::clock::{Clock, MonotonicClock};
use haptloop_rt::exchange::{mailbox, program_channel};
use haptloop_rt::hist::LatencyHistogram;
use std::hint::black_box;
use std::sync::Arc;
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, Ordering};

/// A 1 KiB snapshot: the order of a session snapshot of a mid-size mechanism
/// (~130 coordinates).
#[derive(Clone)]
struct Snapshot {
    tick: u64,
    q: [f64; 127],
}

fn snapshot() -> Snapshot {
    Snapshot {
        tick: 0,
        q: [0.0; 127],
    }
}

/// Runs `f` on this thread while another thread runs `poll` in a loop, so a
/// publish is measured with the cache-line traffic of real use (the slow loop
/// polling the newest snapshot from the other core).
fn with_poller<T: Send + 'static, R>(
    mut poller_state: T,
    poll: fn(&mut T) -> u64,
    f: impl FnOnce() -> R,
) -> R {
    let done = Arc::new(AtomicBool::new(false));
    let d = done.clone();
    let reader = std::thread::spawn(move || {
        let mut sum = 0u64;
        while !d.load(Ordering::Relaxed) {
            sum = sum.wrapping_add(poll(&mut poller_state));
            std::hint::spin_loop();
        }
        sum
    });
    let out = f();
    done.store(true, Ordering::Relaxed);
    black_box(reader.join().unwrap());
    out
}

type Reader = haptloop_rt::exchange::MailboxReader<Snapshot>;

fn exchange(c: &mut Criterion) {
    let mut g = c.benchmark_group("exchange");
    let src = snapshot();

    // The three latest-value designs, each publishing the same 1 KiB snapshot
    // while a reader on the other core polls it.
    let (mut w, r) = mailbox(snapshot);
    with_poller(
        r,
        |r: &mut Reader| r.read(|s| s.tick),
        || {
            let mut k = 0u64;
            g.bench_function("mailbox_publish", |b| {
                b.iter(|| {
                    k += 1;
                    w.publish_with(|s| {
                        s.tick = k;
                        s.q.copy_from_slice(&src.q);
                    })
                })
            });
        },
    );
    let q = Arc::new(ArrayQueue::<Snapshot>::new(1));
    with_poller(
        q.clone(),
        |q: &mut Arc<ArrayQueue<Snapshot>>| q.pop().map_or(0, |s| s.tick),
        || {
            g.bench_function(
                BenchmarkId::new("alternative_publish", "arrayqueue_force_push"),
                |b| b.iter(|| black_box(q.force_push(src.clone()))),
            );
        },
    );
    let m = Arc::new(Mutex::new(snapshot()));
    with_poller(
        m.clone(),
        |m: &mut Arc<Mutex<Snapshot>>| m.lock().unwrap().tick,
        || {
            g.bench_function(BenchmarkId::new("alternative_publish", "mutex_copy"), |b| {
                b.iter(|| m.lock().unwrap().q.copy_from_slice(&src.q))
            });
        },
    );

    let (mut w, mut r) = mailbox(snapshot);
    let mut k = 0u64;
    g.bench_function("mailbox_publish_then_read_one_thread", |b| {
        b.iter(|| {
            k += 1;
            w.publish_with(|s| s.tick = k); // a fresh value every time: the swap path
            r.read(|s| black_box(s.q[0] + s.tick as f64))
        })
    });

    // Hand-over round: send a program, swap it in on the "fast" side (carrying
    // one value), collect the replaced one back. Boxes are recycled, so the
    // round itself allocates nothing.
    let (mut tx, mut rx) = program_channel::<Snapshot>(2);
    let mut current = Box::new(snapshot());
    let mut spare = Some(Box::new(snapshot()));
    g.bench_function("program_handover", |b| {
        b.iter(|| {
            let p = spare.take().expect("recycled");
            assert!(tx.try_send(p).is_ok());
            rx.try_swap(&mut current, |old, new| new.tick = old.tick + 1);
            spare = tx.collect();
        })
    });
    g.finish();
}

/// p50/p99/p99.9 of per-operation time, from batches of 32.
fn distribution() {
    const BATCH: u64 = 32;
    let clock = MonotonicClock::new();
    let measure = |name: &str, op: &mut dyn FnMut()| {
        let mut h = LatencyHistogram::new();
        for _ in 0..20_000 {
            let t0 = clock.now();
            for _ in 0..BATCH {
                op();
            }
            h.record((clock.now() - t0).0 / BATCH);
        }
        let s = h.summary();
        println!(
            "distribution {name:<36} p50 {:>5} ns  p99 {:>5} ns  p99.9 {:>6} ns",
            s.p50, s.p99, s.p999
        );
    };
    let src = snapshot();
    let (mut w, r) = mailbox(snapshot);
    with_poller(
        r,
        |r: &mut Reader| r.read(|s| s.tick),
        || {
            let mut k = 0u64;
            measure("exchange/mailbox_publish (polled)", &mut || {
                k += 1;
                w.publish_with(|s| {
                    s.tick = k;
                    s.q.copy_from_slice(&src.q);
                });
            });
        },
    );
    let m = Arc::new(Mutex::new(snapshot()));
    with_poller(
        m.clone(),
        |m: &mut Arc<Mutex<Snapshot>>| m.lock().unwrap().tick,
        || {
            measure("alternative mutex_copy (polled)", &mut || {
                m.lock().unwrap().q.copy_from_slice(&src.q);
            });
        },
    );
    let (mut w, mut r) = mailbox(snapshot);
    let mut k = 0u64;
    measure("exchange/mailbox_publish_then_read_one_thread", &mut || {
        k += 1;
        w.publish_with(|s| s.tick = k);
        black_box(r.read(|s| s.tick));
    });
    let (mut tx, mut rx) = program_channel::<Snapshot>(2);
    let mut current = Box::new(snapshot());
    let mut spare = Some(Box::new(snapshot()));
    measure("exchange/program_handover", &mut || {
        let p = spare.take().expect("recycled");
        assert!(tx.try_send(p).is_ok());
        rx.try_swap(&mut current, |old, new| new.tick = old.tick + 1);
        spare = tx.collect();
    });
}

fn main() {
    let mut c = Criterion::default().configure_from_args();
    exchange(&mut c);
    c.final_summary();
    distribution();
}
