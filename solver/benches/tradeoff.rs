//! The speed/accuracy trade-off of the fast loop: the four-bar's finger target
//! on a circle of 2 cm diameter at 0.5 Hz for 10 s at 1 kHz, swept over the
//! update rule, iterations per tick and other knobs. Prints markdown tables
//! (BENCHMARKS.md, solver section).
//!
//! The circle starts at the initial finger point and lies in the plane of the
//! coupler curve's tangent t and binormal b there (both measured by converged
//! nudges): the 2 cm travel along t is reachable, the ±1 cm along b is not
//! (a 1-DOF linkage), but the closest reachable point moves continuously. A
//! circle in an arbitrary plane can cross the curve's medial axis, where even
//! the converged solution jumps millimetres in a tick (a horizontal circle did:
//! 2.9 mm in one tick, 377 N of Eq. 7 inertia in the converged run).
//!
//! Columns:
//! - violation: of the mechanism's joints at each tick's final q (metres),
//!   max and RMS over the run;
//! - tracking: |attachment − target| (mostly the unreachable b part);
//! - lag: |attachment − attachment of a converged run| (the projected rule
//!   with 64 iterations per tick, converged to round-off), the solver's own
//!   share of the error;
//! - norm F₇: largest Eq. 7 force on the finger, newtons;
//! - µs/tick: mean wall time of `Program::tick` (median of 5 runs).
//!
//! The first table also has the projected rule with full steps (`step` 1.0,
//! the built-in scenes' setting) at 1–4 iterations.
//!
//! A last table compares the two solvers of Eq. 7's joint block (sparse
//! Cholesky vs warm-started CG at several caps) on all three mechanisms, each
//! finger on a 5 mm, 1 Hz circle for 1 s with the gradient rule: µs per tick,
//! mean CG iterations per tick, largest force difference from the Cholesky.
//!
//! Run: `CARGO_TARGET_DIR=target/al cargo bench -p haptloop-solver --bench tradeoff`

use std::sync::Arc;
use std::time::{Duration, Instant};

use haptloop_solver::mechanisms::{four_bar, sphere_toy, stewart};
use haptloop_solver::{
    FingerId, FingerTarget, ForceSolver, Model, Program, SolverSettings, TickOutcome, UpdateRule,
};
use nalgebra::Vector3;

const TICKS: usize = 10_000;
const DT: Duration = Duration::from_millis(1);

/// The circle: start point and the unit tangent and binormal of the coupler
/// curve there.
struct Circle {
    p0: Vector3<f64>,
    t: Vector3<f64>,
    b: Vector3<f64>,
}

impl Circle {
    fn new() -> Self {
        let reach = |offset: Vector3<f64>| {
            let m = Arc::new(four_bar());
            let p0 = m.initial_targets()[0].position_m;
            let mut p = Program::new(m, SolverSettings::default()).unwrap();
            let r = p.assemble(&[FingerTarget::at(p0 + offset)], 100, 1e-12);
            assert!(r.converged, "{r:?}");
            (p0, p.model().finger_point(p.q(), FingerId(0)).unwrap())
        };
        let (p0, a) = reach(Vector3::x() * 1e-3);
        let t = (a - p0).normalize();
        let s = 3e-3;
        let (_, plus) = reach(t * s);
        let (_, minus) = reach(-t * s);
        let normal = (plus + minus - p0 * 2.0).normalize();
        Circle {
            p0,
            t,
            b: t.cross(&normal).normalize(),
        }
    }

    /// Target of tick k: radius 1 cm, 0.5 Hz, from p0 towards −t.
    fn target(&self, k: usize) -> FingerTarget {
        let w = 2.0 * std::f64::consts::PI * 0.5 * k as f64 * DT.as_secs_f64();
        FingerTarget::at(self.p0 + (self.t * (w.cos() - 1.0) + self.b * w.sin()) * 0.01)
    }
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

fn run(circle: &Circle, settings: SolverSettings) -> Run {
    let model = Arc::new(four_bar());
    let mut times = Vec::new();
    let mut out = Run::default();
    for rep in 0..5 {
        let mut p = Program::new(model.clone(), settings).expect("program");
        let mut r = Run::default();
        let mut targets = vec![circle.target(0)];
        let start = Instant::now();
        for k in 0..TICKS {
            targets[0] = circle.target(k);
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

fn table(circle: &Circle, title: &str, rows: &[(String, SolverSettings)], reference: &Run) {
    println!("\n{title}\n");
    println!(
        "| setting | max viol. (m) | RMS viol. (m) | max track (mm) | RMS track (mm) | max lag (m) | RMS lag (m) | max norm F₇ (N) | µs/tick |"
    );
    println!("|---|---|---|---|---|---|---|---|---|");
    for (name, s) in rows {
        let a = run(circle, *s);
        let (ml, rl) = lag(&a, reference);
        let n = TICKS as f64;
        println!(
            "| {name} | {:.2e} | {:.2e} | {:.2} | {:.2} | {:.1e} | {:.1e} | {:.2} | {:.1} |",
            a.max_v,
            (a.sum_v2 / n).sqrt(),
            a.max_t * 1e3,
            (a.sum_t2 / n).sqrt() * 1e3,
            ml,
            rl,
            a.max_f,
            a.us_per_tick
        );
    }
}

fn main() {
    let d = SolverSettings::default();
    let circle = Circle::new();
    let reference = run(
        &circle,
        SolverSettings {
            iterations: 64,
            ..d
        },
    );
    let rule = |u: UpdateRule, n: u32| SolverSettings {
        update: u,
        iterations: n,
        ..d
    };
    let mut rows = Vec::new();
    for (name, u) in [
        ("gradient (Eq. 3)", UpdateRule::Gradient),
        ("projected", UpdateRule::Projected),
    ] {
        for n in [1u32, 2, 4, 8, 16] {
            rows.push((format!("{name}, {n} it."), rule(u, n)));
        }
    }
    // Full Gauss–Newton steps (the built-in scenes' setting since issue 10).
    for n in [1u32, 2, 3, 4] {
        rows.push((
            format!("projected, step 1.0, {n} it."),
            SolverSettings {
                step: 1.0,
                ..rule(UpdateRule::Projected, n)
            },
        ));
    }
    table(
        &circle,
        "Update rule × iterations per tick (defaults otherwise)",
        &rows,
        &reference,
    );
    let pull: Vec<(String, SolverSettings)> = [f64::INFINITY, 1e-2, 1e-3]
        .iter()
        .flat_map(|&l| {
            [UpdateRule::Gradient, UpdateRule::Projected].map(|u| {
                (
                    format!("{u:?}, 4 it., pull limit {l} m"),
                    SolverSettings {
                        finger_pull_limit_m: l,
                        ..rule(u, 4)
                    },
                )
            })
        })
        .collect();
    table(&circle, "Finger pull limit", &pull, &reference);
    let scale: Vec<(String, SolverSettings)> = [None, Some(1.0)]
        .iter()
        .map(|&l| {
            (
                format!("gradient, 4 it., length scale {l:?}"),
                SolverSettings {
                    length_scale_m: l,
                    ..rule(UpdateRule::Gradient, 4)
                },
            )
        })
        .collect();
    table(
        &circle,
        "K rule on / off (L = characteristic length vs 1 m)",
        &scale,
        &reference,
    );
    force_solvers();
}

/// Per-tick forces, mean µs per tick (median of 3 runs) and mean CG
/// iterations of one solver on one mechanism.
fn force_run(model: &Arc<Model>, solver: ForceSolver) -> (Vec<Vector3<f64>>, f64, f64) {
    let settings = SolverSettings {
        update: UpdateRule::Gradient,
        force_solver: solver,
        ..SolverSettings::default()
    };
    let ticks = 1000;
    let targets: Vec<Vec<FingerTarget>> = (0..ticks)
        .map(|k| {
            let w = 2.0 * std::f64::consts::PI * k as f64 * DT.as_secs_f64();
            let mut t = model.initial_targets();
            for f in &mut t {
                f.position_m += Vector3::new(w.cos() - 1.0, w.sin(), 0.0) * 5e-3;
            }
            t
        })
        .collect();
    let mut times = Vec::new();
    let (mut forces, mut cg) = (Vec::new(), 0.0);
    for rep in 0..3 {
        let mut p = Program::new(model.clone(), settings).expect("program");
        let start = Instant::now();
        let mut iters = 0u64;
        for t in &targets {
            assert_eq!(p.tick(t, DT).status, TickOutcome::Ok);
            iters += p.force_cg_iterations() as u64;
            if rep == 0 {
                forces.push(p.finger_outputs()[0].constraint_force_n);
            }
        }
        times.push(start.elapsed().as_secs_f64() * 1e6 / ticks as f64);
        cg = iters as f64 / ticks as f64;
    }
    times.sort_by(f64::total_cmp);
    (forces, times[1], cg)
}

fn force_solvers() {
    println!("\nEq. 7 joint-block solver (gradient rule, 4 it.; µs/tick includes the AL part)\n");
    println!("| mechanism | solver | µs/tick | CG it./tick | max norm ΔF₇ / max norm F₇ |");
    println!("|---|---|---|---|---|");
    for (name, model) in [
        ("four-bar", four_bar()),
        ("stewart", stewart()),
        ("sphere-toy", sphere_toy()),
    ] {
        let model = Arc::new(model);
        let (exact, t_chol, _) = force_run(&model, ForceSolver::Cholesky);
        let scale = exact.iter().map(|f| f.norm()).fold(0.0, f64::max);
        println!("| {name} | Cholesky | {t_chol:.1} | – | 0 |");
        for cap in [5u32, 20, 100] {
            let (f, t, it) = force_run(
                &model,
                ForceSolver::ConjugateGradient {
                    max_iterations: cap,
                },
            );
            let err = f
                .iter()
                .zip(&exact)
                .map(|(a, b)| (a - b).norm())
                .fold(0.0, f64::max);
            println!(
                "| {name} | CG, cap {cap} | {t:.1} | {it:.1} | {:.1e} |",
                err / scale
            );
        }
    }
}
