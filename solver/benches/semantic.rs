//! Criterion benches of the semantic layer (BENCHMARKS.md, "Issue 13 —
//! semantic constraints"): the paper's claim that an operation costs what
//! its neighbourhood holds, not what the scene holds.
//!
//! The scene is `n` objects in cells of five, one cell per square metre: a
//! fixed floor tile (an offer), a table bound to it (a binding underneath,
//! an offer on top), a cup bound to the table, a chair and a lamp bound to
//! the tile. Every cell looks the same, so the local complexity is the same
//! at 10, 100 and 1000 objects.
//!
//! - `move/{n}`: one interactive move (checkMove, Algorithm 2) of a table by
//!   1 mm along its floor, which carries its cup (the group); tables taken
//!   round robin, the direction alternating so the scene stays put;
//! - `snap_search/{n}`: searchCloseBindings for a cup's binding area (the
//!   close-offer search Algorithm 1 runs per moved object), cups round
//!   robin.
//!
//! Run: `CARGO_TARGET_DIR=target/semantic cargo bench -p haptloop-solver --bench semantic`

use std::hint::black_box;
use std::time::Duration;

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use haptloop_solver::geometry::Shape;
use haptloop_solver::semantic::{
    AreaId, AreaKind, AreaSpec, Move, SemanticScene, SemanticSettings, SemanticSpec,
};
use haptloop_solver::{BodyId, BodySpec, ModelBuilder};
use nalgebra::Vector3;

/// Half extents of the cell's objects, m: tile, table, cup, chair, lamp.
const HALF: [[f64; 3]; 5] = [
    [0.45, 0.45, 0.01],
    [0.1, 0.08, 0.05],
    [0.02, 0.02, 0.03],
    [0.05, 0.05, 0.05],
    [0.03, 0.03, 0.1],
];

/// The top (offer) or bottom (binding) face of a box of half extents `h`.
fn face(body: u32, h: [f64; 3], offer: bool, label: &str) -> AreaSpec {
    let z = if offer { h[2] } else { -h[2] };
    let mut polygon_m = vec![
        [-h[0], -h[1], z],
        [h[0], -h[1], z],
        [h[0], h[1], z],
        [-h[0], h[1], z],
    ];
    if !offer {
        polygon_m.reverse();
    }
    AreaSpec {
        body: BodyId(body),
        kind: if offer {
            AreaKind::Offer
        } else {
            AreaKind::Binding
        },
        label: label.into(),
        polygon_m,
        normal: [0.0, 0.0, if offer { 1.0 } else { -1.0 }],
    }
}

/// `cells` furnished cells (5 objects each), every binding satisfied.
/// Returns the scene and per cell (table, cup binding area).
fn furnished(cells: usize) -> (SemanticScene, Vec<(BodyId, AreaId)>) {
    let side = (cells as f64).sqrt().ceil() as usize;
    let mut b = ModelBuilder::new();
    let mut areas = Vec::new();
    let mut out = Vec::new();
    for c in 0..cells {
        let (x, y) = ((c % side) as f64, (c / side) as f64);
        let base = 5 * c as u32;
        let at = [
            [x, y, -HALF[0][2]],
            [x, y, HALF[1][2]],
            [x, y, 2.0 * HALF[1][2] + HALF[2][2]],
            [x + 0.25, y + 0.2, HALF[3][2]],
            [x - 0.25, y - 0.2, HALF[4][2]],
        ];
        for (k, name) in ["tile", "table", "cup", "chair", "lamp"].iter().enumerate() {
            let spec = if k == 0 {
                BodySpec::fixed(format!("{name}{c}"))
            } else {
                BodySpec::new(format!("{name}{c}"))
            };
            b.body(spec.at(at[k]).shape(Shape::Box {
                half_extents_m: HALF[k],
            }));
        }
        areas.push(face(base, HALF[0], true, "floor"));
        areas.push(face(base + 1, HALF[1], false, "furniture"));
        areas.push(face(base + 1, HALF[1], true, "surface"));
        let cup = areas.len();
        areas.push(face(base + 2, HALF[2], false, "on-surface"));
        areas.push(face(base + 3, HALF[3], false, "furniture"));
        areas.push(face(base + 4, HALF[4], false, "furniture"));
        out.push((BodyId(base + 1), AreaId(cup as u32)));
    }
    let model = b.build().expect("model");
    let spec = SemanticSpec {
        areas,
        order: vec![
            ("furniture".into(), "floor".into()),
            ("on-surface".into(), "surface".into()),
            ("on-surface".into(), "floor".into()),
        ],
        labels: Vec::new(),
        settings: SemanticSettings::default(),
    };
    let mut s = SemanticScene::from_model(&model, model.q0(), &spec).expect("scene");
    let satisfied = s.satisfy_aligned();
    assert_eq!(satisfied, 4 * cells, "every binding satisfied");
    s.consistent().expect("consistent");
    (s, out)
}

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("move");
    for n in [10, 100, 1000] {
        let (mut s, cells) = furnished(n / 5);
        // The move is allowed (not refused by checkMove), both ways.
        for dx in [1e-3, -1e-3] {
            let table = cells[0].0;
            let mv = Move {
                center: s.pose(table).r,
                t: Vector3::new(dx, 0.0, 0.0),
                r: Vector3::zeros(),
            };
            assert!(s.move_object(table, mv).same_as(&mv), "a refused move");
        }
        let mut k = 0usize;
        let mut sign = 1.0;
        g.bench_function(BenchmarkId::from_parameter(n), |b| {
            b.iter(|| {
                let (table, _) = cells[k % cells.len()];
                k += 1;
                if k.is_multiple_of(cells.len()) {
                    sign = -sign;
                }
                let mv = Move {
                    center: s.pose(table).r,
                    t: Vector3::new(1e-3 * sign, 0.0, 0.0),
                    r: Vector3::zeros(),
                };
                black_box(s.move_object(table, mv))
            })
        });
        s.consistent().expect("still consistent");
    }
    g.finish();

    let mut g = c.benchmark_group("snap_search");
    for n in [10, 100, 1000] {
        let (s, cells) = furnished(n / 5);
        assert_eq!(s.search_close(cells[0].1).len(), 1, "the cup's table");
        let mut k = 0usize;
        g.bench_function(BenchmarkId::from_parameter(n), |b| {
            b.iter(|| {
                let (_, cup) = cells[k % cells.len()];
                k += 1;
                black_box(s.search_close(cup))
            })
        });
    }
    g.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(3));
    targets = bench
}
criterion_main!(benches);
