//! A witness table's refresh (`Program::apply_witnesses`) refactors only
//! what the next steps use; a whole force solve after it
//! (`Program::refresh_factor`, the refresh it replaced) must change
//! nothing: the same motion and forces, tick for tick.

use haptloop_rt::alloc::count;
use haptloop_solver::geometry::ContactSettings;
use haptloop_solver::{BodySpec, FingerSpec, FingerTarget, SolverSettings, TickOutcome};
use nalgebra::{UnitQuaternion, Vector3};

use crate::common::{Lockstep, cuboid, table_and_block};

/// A held 2 cm cube pressed onto a table, dragged and turned into a block
/// (its faces, edges and corners change witnesses on the way), and two
/// free boxes on the table in its path.
fn scene() -> haptloop_solver::Model {
    let mut b = table_and_block(0.06);
    for (k, y) in [-0.03, 0.03].into_iter().enumerate() {
        b.body(
            BodySpec::new(format!("box{k}"))
                .at([0.0, y, 0.0101])
                .shape(cuboid([0.01; 3]))
                .mass(0.05),
        );
    }
    b.body(
        BodySpec::new("cube")
            .at([-0.05, 0.0, 0.0105])
            .shape(cuboid([0.01; 3])),
    );
    b.finger(FingerSpec::rigid("hand", "cube", [0.0, 0.0, 0.01]));
    b.build().unwrap()
}

/// The hand's target at tick `k` of 700: down 0.3 mm into the table,
/// across to the block and into it, turning.
fn target(start: Vector3<f64>, k: usize) -> FingerTarget {
    let s = (k as f64 / 600.0).min(1.0);
    FingerTarget {
        position_m: start + Vector3::new(0.11 * s, 0.004 * s, -0.0003),
        orientation: UnitQuaternion::from_axis_angle(&Vector3::z_axis(), 0.4 * s),
    }
}

#[test]
fn a_witness_tables_chord_refresh_equals_a_whole_force_solve() {
    let run = |full_refresh: bool| {
        let mut l = Lockstep::new(
            scene(),
            SolverSettings::default(),
            ContactSettings::default(),
        );
        l.full_refresh = full_refresh;
        let start = l.program.model().initial_targets()[0].position_m;
        let mut out = Vec::new();
        for k in 0..700 {
            let r = l.tick(&[target(start, k)]);
            assert_eq!(r.status, TickOutcome::Ok, "tick {k}");
            let f = l.program.finger_outputs()[0];
            out.push((l.program.q().to_vec(), f.force_n, r.max_penetration_m));
        }
        (out, l.tables, l.programs, l.program.chord_refreshes())
    };
    let (chord, tables, programs, chords) = run(false);
    let (full, tables_full, programs_full, _) = run(true);
    println!("chord refresh: {tables} tables, {programs} programs, {chords} chord refreshes");
    assert!(
        tables > 5,
        "{tables} witness tables: the drag must change features"
    );
    assert!(chords > 0, "no table took the chord refresh");
    assert_eq!((tables, programs), (tables_full, programs_full));
    for (k, (a, b)) in chord.iter().zip(&full).enumerate() {
        let dq =
            a.0.iter()
                .zip(&b.0)
                .map(|(x, y)| (x - y).abs())
                .fold(0.0, f64::max);
        assert!(dq <= 1e-12, "tick {k}: q differs by {dq:e}");
        assert!(
            (a.1 - b.1).norm() <= 1e-9,
            "tick {k}: force {} against {}",
            a.1,
            b.1
        );
        assert!((a.2 - b.2).abs() <= 1e-12, "tick {k}: penetration");
    }
}

/// The chord refresh is on the fast path: taking a witness table allocates
/// nothing (each table the drag publishes, taken again under the counter).
#[test]
fn a_witness_tables_chord_refresh_allocates_nothing() {
    let mut l = Lockstep::new(
        scene(),
        SolverSettings::default(),
        ContactSettings::default(),
    );
    let start = l.program.model().initial_targets()[0].position_m;
    let mut table = Vec::new();
    let (mut taken, mut allocations) = (0, 0);
    for k in 0..700 {
        let seen = l.tables;
        let r = l.tick(&[target(start, k)]);
        assert_eq!(r.status, TickOutcome::Ok, "tick {k}");
        if l.tables > seen {
            table.clear();
            table.extend_from_slice(l.manager.published());
            let before = l.program.chord_refreshes();
            let (ok, stats) = count(|| l.program.apply_witnesses(&table));
            assert!(ok);
            taken += l.program.chord_refreshes() - before;
            allocations += stats.total();
        }
    }
    assert!(taken > 0, "no table took the chord refresh");
    assert_eq!(allocations, 0, "taking {taken} tables allocated");
}
