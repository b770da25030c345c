//! Reusing a program whose set of contact pairs comes back
//! (`ContactManager::recycle`) changes nothing but the cost: a held cube
//! lifted off a table and set back down, next to a block, three times,
//! runs tick for tick the same with reuse as with a fresh program at every
//! change of structure.

use haptloop_solver::geometry::ContactSettings;
use haptloop_solver::{BodySpec, FingerSpec, FingerTarget, SolverSettings};
use nalgebra::Vector3;

use crate::common::{Lockstep, cuboid, table_and_block};

fn scene() -> haptloop_solver::Model {
    let mut b = table_and_block(0.05);
    b.body(
        BodySpec::new("cube")
            .at([0.0, 0.0, 0.0105])
            .shape(cuboid([0.01; 3])),
    );
    b.finger(FingerSpec::rigid("hand", "cube", [0.0, 0.0, 0.01]));
    b.build().unwrap()
}

/// The hand's path: down on the table, up 5 cm, over next to the block,
/// down, back; three times. Piecewise linear, 0.1 m/s at most.
fn path(t: f64) -> Vector3<f64> {
    let legs = [
        [0.0, 0.0, 0.0205],
        [0.0, 0.0, 0.07],
        [0.0185, 0.0, 0.07],
        [0.0185, 0.0, 0.0205],
        [0.0185, 0.0, 0.07],
        [0.0, 0.0, 0.07],
        [0.0, 0.0, 0.0205],
    ];
    let leg_s = 0.6;
    let u = (t / leg_s) % (legs.len() - 1) as f64;
    let (k, f) = (u.floor() as usize, u.fract());
    let (a, b) = (Vector3::from(legs[k]), Vector3::from(legs[k + 1]));
    a + (b - a) * f
}

fn run(recycle: bool) -> (Vec<Vec<f64>>, Vec<Vector3<f64>>, Lockstep) {
    let settings = SolverSettings {
        dynamics: true,
        ..SolverSettings::default()
    };
    let mut l = Lockstep::new(scene(), settings, ContactSettings::default());
    l.recycle = recycle;
    let (mut qs, mut forces) = (Vec::new(), Vec::new());
    for k in 0..3 * 6 * 600 {
        let t = k as f64 * 1e-3;
        let r = l.tick(&[FingerTarget::at(path(t))]);
        assert_eq!(r.status, haptloop_solver::TickOutcome::Ok, "tick {k}");
        qs.push(l.program.q().to_vec());
        forces.push(l.program.finger_outputs()[0].force_n);
    }
    (qs, forces, l)
}

#[test]
fn a_reused_program_runs_exactly_as_a_fresh_one() {
    let (q_fresh, f_fresh, fresh) = run(false);
    let (q_reuse, f_reuse, reuse) = run(true);
    let built = reuse.manager.builds();
    assert_eq!(fresh.manager.builds().reused, 0);
    assert_eq!(
        fresh.programs, reuse.programs,
        "the same changes of structure"
    );
    assert!(
        reuse.programs >= 6,
        "only {} programs: nothing to reuse",
        reuse.programs
    );
    assert!(
        2 * built.reused >= reuse.programs,
        "{} of {} programs reused",
        built.reused,
        reuse.programs
    );
    assert_eq!(reuse.backups + fresh.backups, 0);
    let mut worst_q = 0.0f64;
    let mut worst_f = 0.0f64;
    for k in 0..q_fresh.len() {
        for (a, b) in q_fresh[k].iter().zip(&q_reuse[k]) {
            worst_q = worst_q.max((a - b).abs());
        }
        worst_f = worst_f.max((f_fresh[k] - f_reuse[k]).norm());
    }
    assert!(worst_q < 1e-9, "positions differ by {worst_q:e}");
    assert!(worst_f < 1e-6, "forces differ by {worst_f:e} N");
}
