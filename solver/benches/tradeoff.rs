//! The speed/accuracy trade-off of the fast loop: the four-bar's finger target
//! on a horizontal circle (radius 2 cm, 0.5 Hz, centred on the initial finger
//! point) for 10 s at 1 kHz, swept over iterations per tick and other knobs.
//! Prints markdown tables (BENCHMARKS.md, solver section).
//!
//! Columns:
//! - violation: of the mechanism's joints at each tick's final q (metres),
//!   max and RMS over the run;
//! - tracking: |attachment − target|; the coupler point of a 1-DOF linkage
//!   cannot follow a 3-D circle, so this is mostly geometry;
//! - lag: |attachment − attachment of a converged run| (the same settings
//!   with 256 iterations per tick), the solver's own share of the error;
//! - µs/tick: mean wall time of `Program::tick` (median of 5 runs).
//!
//! Run: `CARGO_TARGET_DIR=target/al cargo bench -p haptloop-solver --bench tradeoff`

use std::sync::Arc;
use std::time::{Duration, Instant};

use haptloop_solver::mechanisms::four_bar;
use haptloop_solver::{FingerTarget, Program, SolverSettings, TickOutcome};
use nalgebra::Vector3;

const TICKS: usize = 10_000;
const DT: Duration = Duration::from_millis(1);

/// Target of tick k: the 2 cm, 0.5 Hz circle in the horizontal plane.
fn target(centre: Vector3<f64>, k: usize) -> FingerTarget {
    let w = 2.0 * std::f64::consts::PI * 0.5 * k as f64 * DT.as_secs_f64();
    FingerTarget::at(centre + Vector3::new(w.cos() - 1.0, w.sin(), 0.0) * 0.02)
}

/// Per-run statistics.
#[derive(Default)]
struct Run {
    attach: Vec<Vector3<f64>>,
    max_v: f64,
    sum_v2: f64,
    max_t: f64,
    sum_t2: f64,
    max_f: f64,
    us_per_tick: f64,
}

fn run(settings: SolverSettings) -> Run {
    let model = Arc::new(four_bar());
    let centre = model.initial_targets()[0].position_m;
    let mut times = Vec::new();
    let mut out = Run::default();
    for rep in 0..5 {
        let mut p = Program::new(model.clone(), settings).expect("program");
        let mut r = Run::default();
        let mut targets = vec![target(centre, 0)];
        let start = Instant::now();
        for k in 0..TICKS {
            targets[0] = target(centre, k);
            let rep = p.tick(&targets, DT);
            assert_eq!(rep.status, TickOutcome::Ok, "tick {k}");
            let o = p.finger_outputs()[0];
            r.max_v = r.max_v.max(rep.max_violation_m);
            r.sum_v2 += rep.rms_violation_m.powi(2);
            r.max_t = r.max_t.max(o.tracking_error_m);
            r.sum_t2 += o.tracking_error_m.powi(2);
            r.max_f = r.max_f.max(o.constraint_force_n.norm());
            r.attach.push(o.attachment_m);
        }
        times.push(start.elapsed().as_secs_f64() * 1e6 / TICKS as f64);
        if rep == 0 {
            out = r;
        }
    }
    times.sort_by(f64::total_cmp);
    out.us_per_tick = times[2];
    out
}

fn lag(a: &Run, reference: &Run) -> (f64, f64) {
    let d: Vec<f64> = a
        .attach
        .iter()
        .zip(&reference.attach)
        .map(|(x, y)| (x - y).norm())
        .collect();
    let max = d.iter().copied().fold(0.0, f64::max);
    (
        max,
        (d.iter().map(|v| v * v).sum::<f64>() / d.len() as f64).sqrt(),
    )
}

fn table(title: &str, rows: &[(String, SolverSettings)]) {
    println!("\n{title}\n");
    println!(
        "| setting | max viol. (m) | RMS viol. (m) | max track (mm) | RMS track (mm) | max lag (µm) | RMS lag (µm) | max |F₇| (N) | µs/tick |"
    );
    println!("|---|---|---|---|---|---|---|---|---|");
    for (name, s) in rows {
        let a = run(*s);
        let reference = run(SolverSettings {
            iterations: 256,
            ..*s
        });
        let (ml, rl) = lag(&a, &reference);
        let n = TICKS as f64;
        println!(
            "| {name} | {:.2e} | {:.2e} | {:.2} | {:.2} | {:.1} | {:.1} | {:.2} | {:.1} |",
            a.max_v,
            (a.sum_v2 / n).sqrt(),
            a.max_t * 1e3,
            (a.sum_t2 / n).sqrt() * 1e3,
            ml * 1e6,
            rl * 1e6,
            a.max_f,
            a.us_per_tick
        );
    }
}

fn main() {
    let d = SolverSettings::default();
    let iters: Vec<(String, SolverSettings)> = [1u32, 2, 4, 8, 16]
        .iter()
        .map(|&n| {
            (
                format!("iterations {n}"),
                SolverSettings { iterations: n, ..d },
            )
        })
        .collect();
    table("Iterations per tick (default settings otherwise)", &iters);
    let pull: Vec<(String, SolverSettings)> = [f64::INFINITY, 1e-2, 1e-3]
        .iter()
        .flat_map(|&l| {
            [1u32, 4].map(|n| {
                (
                    format!("pull limit {l} m, iterations {n}"),
                    SolverSettings {
                        iterations: n,
                        finger_pull_limit_m: l,
                        ..d
                    },
                )
            })
        })
        .collect();
    table("Finger pull limit", &pull);
    let scale: Vec<(String, SolverSettings)> = [None, Some(1.0)]
        .iter()
        .map(|&l| {
            (
                format!("length scale {l:?}"),
                SolverSettings {
                    length_scale_m: l,
                    ..d
                },
            )
        })
        .collect();
    table(
        "K rule on / off (length scale L = characteristic length vs 1 m)",
        &scale,
    );
}
