//! The cost of design variation in the fast tick (BENCHMARKS.md, "Design
//! variation"): for each built-in design scene, one `Program::tick` (4
//! projected steps, Eq. 7–8, coupling) of the scene as shipped (`with`:
//! its free design variables, bounds and objectives) and of the same scene
//! with all of those removed (`without`: `free`, `bounds` and `[[objective]]`
//! deleted from the text), in the same run. The fingers' targets circle
//! 2 mm around their start at 0.5 Hz so every tick has work.
//!
//! Run: `cargo bench -p haptloop-solver --bench design`

use std::hint::black_box;
use std::path::Path;
use std::sync::Arc;
use std::time::Duration;

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use haptloop_solver::{
    FingerTarget, Model, Objectives, Program, SolverSettings, TickOutcome, scene,
};
use nalgebra::Vector3;

const SCENES: [&str; 5] = [
    "four-bar-design",
    "peaucellier-design",
    "stewart-feet",
    "dexterity-arm",
    "dodge",
];

/// The scene's text without design: no `free`, `bounds` or `[[objective]]`.
fn without_design(text: &str) -> String {
    let mut out = String::new();
    let mut in_objective = false;
    for line in text.lines() {
        if line.starts_with('[') {
            in_objective = line.starts_with("[[objective]]");
        }
        if in_objective || line.starts_with("free = ") || line.starts_with("bounds = ") {
            continue;
        }
        out.push_str(line);
        out.push('\n');
    }
    out
}

fn model(name: &str, text: &str) -> (Model, Arc<Objectives>) {
    let c = scene::parse(name, text, None)
        .and_then(|l| l.compile())
        .unwrap_or_else(|e| panic!("{e}"));
    (c.model, c.objectives)
}

/// 1000 ticks of targets on 2 mm circles at 0.5 Hz (1 kHz).
fn targets(model: &Model) -> Vec<Vec<FingerTarget>> {
    (0..1000)
        .map(|k| {
            let a = std::f64::consts::TAU * 0.5 * k as f64 / 1000.0;
            let mut t = model.initial_targets();
            for f in &mut t {
                f.position_m += Vector3::new(a.cos() - 1.0, a.sin(), 0.0) * 2e-3;
            }
            t
        })
        .collect()
}

fn design_tick(c: &mut Criterion) {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes");
    let mut g = c.benchmark_group("design_tick");
    for name in SCENES {
        let text = std::fs::read_to_string(dir.join(format!("{name}.toml"))).unwrap();
        for (variant, text) in [("with", text.clone()), ("without", without_design(&text))] {
            let (model, objectives) = model(name, &text);
            if variant == "without" {
                assert_eq!(model.layout().design_coords(), 0, "{name}");
                assert!(objectives.is_empty(), "{name}");
            }
            let ts = targets(&model);
            let mut p =
                Program::with_objectives(Arc::new(model), objectives, SolverSettings::default())
                    .unwrap();
            let mut k = 0;
            g.bench_function(BenchmarkId::new(name, variant), |b| {
                b.iter(|| {
                    let r = p.tick(black_box(&ts[k % ts.len()]), Duration::from_millis(1));
                    assert_eq!(r.status, TickOutcome::Ok, "{name} {variant} tick {k}");
                    k += 1;
                })
            });
        }
    }
    g.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(3));
    targets = design_tick
}
criterion_main!(benches);
