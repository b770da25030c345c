//! Criterion bench of `Program::new` on n identical revolutes between the
//! ground and one link (the issue's "1000 joints between the same two
//! bodies"): `program_build/auto/{100,400,1000}`. The per-body-pair pass keeps
//! the dependent rows out of A, so the cost should grow linearly with n.
//! (With the check off, `Program::new` refuses this model: A is singular.)
//!
//! `program_build/ladder/{20,40,80}`: a planar ladder of pinned rods with that
//! many closed loops (3 redundant rows each), where the ordered check runs:
//! a sparse factorisation in model order, linear in the ladder's length.
//!
//! Run: `cargo bench -p haptloop-solver --bench program_build`

use std::hint::black_box;
use std::sync::Arc;
use std::time::Duration;

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use haptloop_solver::{Program, RedundancyCheck, SolverSettings};

#[allow(dead_code)]
#[path = "../tests/al/planar.rs"]
mod ladder;

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("program_build");
    g.sample_size(10).measurement_time(Duration::from_secs(4));
    for (mode, name, sizes) in [(RedundancyCheck::Auto, "auto", &[100, 400, 1000][..])] {
        for &n in sizes {
            let model = Arc::new(ladder::many_revolutes(n));
            let settings = SolverSettings {
                redundancy: mode,
                ..SolverSettings::default()
            };
            g.bench_with_input(BenchmarkId::new(name, n), &model, |b, m| {
                b.iter(|| black_box(Program::new(m.clone(), settings).unwrap()))
            });
        }
    }
    for cells in [20, 40, 80] {
        let model = Arc::new(ladder::ladder(cells));
        g.bench_with_input(BenchmarkId::new("ladder", cells), &model, |b, m| {
            b.iter(|| black_box(Program::new(m.clone(), SolverSettings::default()).unwrap()))
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
