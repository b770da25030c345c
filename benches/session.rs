//! Whole-session benchmarks: the cost of one fast-loop tick per built-in scene
//! (devices + solver + safety layer + statistics + snapshot + trace queue),
//! the cost of timing a tick's stages (`stage_clock/tick`: a start, seven
//! laps on the monotonic clock and the nine histogram records), then the
//! velocity-filter sweep behind the sessions' 10 ms default.
//!
//! `cargo bench --bench session`
//!
//! The tick is timed on the mock clock (deterministic inputs: the same ticks
//! every run), one tick per criterion iteration, continuing the same session
//! so the mechanism keeps moving.

use criterion::{BenchmarkId, Criterion};
use haptloop::scenes::{BUILTIN, resolve};
use haptloop::session::{self, Plan, SessionOptions, Stage, StageClock, StageTimes};
use haptloop_rt::clock::{MockClock, Nanos};
use haptloop_rt::schedule::{Tick, TickBody};
use std::hint::black_box;
use std::time::Duration;

fn options() -> SessionOptions {
    SessionOptions {
        seconds: 3600.0,
        deterministic: true,
        ..SessionOptions::default()
    }
}

fn session_tick(c: &mut Criterion) {
    let mut g = c.benchmark_group("session_tick");
    for b in BUILTIN {
        let scene = resolve(b.name).expect("built-in scenes load");
        let plan = Plan::new(&scene, &options()).expect("plan");
        let mut built = session::build(&scene, &plan, MockClock::new(Nanos(0))).expect("build");
        let mut k = 0u64;
        g.bench_function(BenchmarkId::from_parameter(b.name), |bench| {
            bench.iter(|| {
                let t = Nanos((k + 1) * 1_000_000);
                black_box(built.fast.tick(&Tick {
                    index: k,
                    deadline: t,
                    start: t,
                }));
                while built.trace.pop().is_some() {}
                k += 1;
            })
        });
    }
    g.finish();
}

/// What timing the stages costs a tick: one start, a lap per stage, the
/// records.
fn stage_clock(c: &mut Criterion) {
    let mut clock = StageClock::default();
    let mut times = StageTimes::new();
    c.bench_function("stage_clock/tick", |b| {
        b.iter(|| {
            clock.start();
            for s in Stage::ALL {
                clock.lap(s);
            }
            times.record(black_box(&clock));
        })
    });
}

/// Tick-to-tick change of the Eq. 7 (constraint) part of the finger force on
/// the default scene, 4 s at 1 kHz after a 0.5 s settle, per filter setting.
fn filter_sweep() {
    println!("\nvelocity filter sweep (four-bar, 4 s at 1 kHz; |ΔF| between ticks, N)");
    println!(
        "| τ | Eq. 7 part p50 | p99 | coupling part p99 | solver output p99 (before the safety layer) |"
    );
    println!("|---|---|---|---|---|");
    for tau_ms in [0.0, 2.0, 5.0, 10.0, 20.0] {
        let scene = resolve("four-bar").expect("default scene");
        let mut plan = Plan::new(
            &scene,
            &SessionOptions {
                seconds: 4.5,
                ..options()
            },
        )
        .expect("plan");
        plan.solver.velocity_filter = Duration::from_secs_f64(tau_ms / 1000.0);
        let mut built = session::build(&scene, &plan, MockClock::new(Nanos(0))).expect("build");
        let (mut eq7, mut coupling, mut total) = (Vec::new(), Vec::new(), Vec::new());
        for k in 0..4500u64 {
            let t = Nanos((k + 1) * 1_000_000);
            built.fast.tick(&Tick {
                index: k,
                deadline: t,
                start: t,
            });
            while built.trace.pop().is_some() {}
            let o = built.fast.program().finger_outputs()[0];
            if k >= 500 {
                eq7.push(o.constraint_force_n);
                coupling.push(o.coupling_force_n);
                total.push(o.force_n);
            }
        }
        let changes = |v: &[nalgebra::Vector3<f64>]| {
            let mut d: Vec<f64> = v.windows(2).map(|w| (w[1] - w[0]).norm()).collect();
            d.sort_by(f64::total_cmp);
            (d[d.len() / 2], d[d.len() * 99 / 100])
        };
        let ((e50, e99), (_, c99), (_, t99)) = (changes(&eq7), changes(&coupling), changes(&total));
        println!("| {tau_ms} ms | {e50:.3} | {e99:.3} | {c99:.3} | {t99:.3} |");
    }
}

fn main() {
    let mut c = Criterion::default().configure_from_args();
    session_tick(&mut c);
    stage_clock(&mut c);
    c.final_summary();
    filter_sweep();
}
