//! Choi & Cremer §3.2, path by path, on hand-made configurations (no
//! solver in between, so each path is reached on purpose):
//!
//! - the depth-triggered backup: a box pushed through a table by less than
//!   its size (no tunnelling) but deeper than `penetration_tolerance` is
//!   answered by a reset to the last clean configuration, bit for bit, with
//!   the cycle counting no tunnel; a penetration within the tolerance is not
//!   backed up and becomes the new clean configuration; a configuration
//!   whose tick failed never does;
//! - optional removal: a tracked pair stays tracked between
//!   `contact_distance` and `release_distance` (hysteresis), is dropped
//!   beyond `release_distance`, and is not taken up again until it is back
//!   within `contact_distance` (plus what it moved).
//!
//! Each depth and distance is computed here from the poses (box half height
//! and table top) and compared with what the active set reports.

use std::sync::Arc;

use haptloop_solver::contact::{ContactManager, ContactUpdate};
use haptloop_solver::geometry::{ActiveSet, ContactBody, ContactSettings, Pose3};
use haptloop_solver::{BodySpec, Model, ModelBuilder, SolverSettings};

use crate::common::{at, cuboid};

/// Half height of the box and the table top's height.
const BOX_H: f64 = 0.01;
const TABLE_TOP: f64 = 0.0;

/// A 2 cm box over a fixed table whose top is at z = 0.
fn model(z: f64) -> Model {
    let mut b = ModelBuilder::new();
    b.body(
        BodySpec::fixed("table")
            .at([0.0, 0.0, TABLE_TOP - 0.02])
            .shape(cuboid([0.15, 0.15, 0.02])),
    );
    b.body(
        BodySpec::new("box")
            .at([0.0, 0.0, z])
            .shape(cuboid([BOX_H; 3])),
    );
    b.build().expect("model")
}

/// `q0` with the box's centre at height `z`.
fn with_box_at(m: &Model, z: f64) -> Vec<f64> {
    let mut q = m.q0().to_vec();
    let id = m.body_id("box").expect("box");
    let r = m.layout().position_range(id).expect("moving");
    q[r.start + 2] = z;
    q
}

/// The box's gap to the table (negative: penetration) with its centre at `z`.
fn gap(z: f64) -> f64 {
    z - BOX_H - TABLE_TOP
}

fn manager(m: &Arc<Model>) -> ContactManager {
    ContactManager::new(
        m.clone(),
        SolverSettings::default(),
        ContactSettings::default(),
    )
    .expect("two shaped bodies")
}

#[test]
fn a_penetration_deeper_than_the_tolerance_backs_up_to_the_last_clean_configuration() {
    let tol = ContactSettings::default().penetration_tolerance_m;
    let z0 = BOX_H + 0.001;
    let m = Arc::new(model(z0));
    let mut mgr = manager(&m);
    let (c, _) = mgr.initial(m.q0()).expect("initial");
    assert_eq!((c.tracked, c.backups.len()), (1, 0), "{c:?}");

    // Within the tolerance: counted, not backed up; it becomes the clean q.
    let shallow_z = BOX_H - 0.5 * tol;
    let shallow = with_box_at(&m, shallow_z);
    let (c, up) = mgr.step(&shallow, true, true);
    assert!(
        (c.max_penetration_m + gap(shallow_z)).abs() < 1e-12,
        "{c:?}"
    );
    assert!(c.backups.is_empty() && c.tunnels == 0, "{c:?}");
    assert!(!matches!(up, ContactUpdate::Program { reset: Some(_), .. }));

    // A failed tick's configuration is not clean, even without penetration.
    let failed = with_box_at(&m, BOX_H + 0.0005);
    let (c, _) = mgr.step(&failed, false, true);
    assert!(c.backups.is_empty(), "{c:?}");

    // Five tolerances deep, moved 0.5 mm (far less than the box: no
    // tunnel): a backup to `shallow`, not to `failed` or q0.
    let deep_z = BOX_H - 5.0 * tol;
    let deep = with_box_at(&m, deep_z);
    let (c, up) = mgr.step(&deep, true, true);
    assert!((c.max_penetration_m + gap(deep_z)).abs() < 1e-12, "{c:?}");
    assert_eq!(c.backups, vec![[0, 1]], "{c:?}");
    assert_eq!(c.tunnels, 0, "the depth path, not the tunnelling one");
    let ContactUpdate::Program { program, reset } = up else {
        panic!("a backup sends a program with its reset, got {up:?}");
    };
    assert_eq!(reset.as_deref(), Some(shallow.as_slice()));
    // The retry ran at the clean configuration: its poses are the manager's.
    let box_id = m.body_id("box").expect("box");
    let z_seen = mgr.poses()[box_id.index()].r.z;
    assert_eq!(z_seen, shallow_z);
    assert_eq!(program.q().len(), m.n_coords());

    // Without a program slot free, the backup waits: no reset is sent.
    let (c, up) = mgr.step(&deep, true, false);
    assert_eq!(c.backups.len(), 1);
    assert!(!matches!(up, ContactUpdate::Program { .. }));
}

fn active_set() -> (ActiveSet, ContactSettings) {
    let s = ContactSettings::default();
    let body = |fixed: bool, h: [f64; 3]| {
        Some(ContactBody {
            collider: cuboid(h).collider().unwrap(),
            fixed,
            fingertip: false,
            friction: 0.0,
        })
    };
    let set = ActiveSet::new(
        vec![body(true, [0.15, 0.15, 0.02]), body(false, [BOX_H; 3])],
        Vec::new(),
        s,
    );
    (set, s)
}

/// Poses with the box's gap to the table `g`.
fn poses(g: f64) -> [Pose3; 2] {
    [
        at([0.0, 0.0, TABLE_TOP - 0.02]),
        at([0.0, 0.0, TABLE_TOP + BOX_H + g]),
    ]
}

/// Steps the box to gap `to` in moves of at most 1 mm, then one cycle at
/// rest there (so the motion term of the window is zero), returning that
/// cycle's tracked count.
fn walk(set: &mut ActiveSet, from: f64, to: f64) -> u32 {
    let n = ((to - from).abs() / 0.001).ceil().max(1.0) as usize;
    for k in 1..=n {
        set.update(&poses(from + (to - from) * k as f64 / n as f64));
    }
    set.update(&poses(to)).tracked
}

/// The thresholds at rest: a new pair is taken up below `contact_distance`
/// plus the guard reach (itself `contact_distance` plus the motion, so
/// 2 × `contact_distance` at rest), a tracked one is dropped beyond
/// `release_distance`. Between the two it keeps its state.
#[test]
fn a_pair_is_kept_until_release_distance_and_taken_up_again_near_contact() {
    let (mut set, s) = active_set();
    let (cd, rd) = (s.contact_distance_m, s.release_distance_m);
    assert!(rd > 3.0 * cd, "the test needs room between the thresholds");
    // Far away: not tracked; approaching: not until near contact.
    assert_eq!(set.update(&poses(2.0 * rd)).tracked, 0);
    assert_eq!(walk(&mut set, 2.0 * rd, 3.0 * cd), 0);
    assert_eq!(walk(&mut set, 3.0 * cd, 0.5 * cd), 1);
    assert_eq!(set.witnesses([0, 1]).len(), 4, "the box's bottom face");
    // Leaving: kept up to release_distance (hysteresis) ...
    assert_eq!(walk(&mut set, 0.5 * cd, 0.9 * rd), 1);
    // ... dropped past it (the optional removal) ...
    assert_eq!(walk(&mut set, 0.9 * rd, 1.2 * rd), 0);
    assert!(set.witnesses([0, 1]).is_empty());
    // ... and, coming back, not taken up again at the same distance.
    assert_eq!(walk(&mut set, 1.2 * rd, 0.9 * rd), 0);
    assert_eq!(walk(&mut set, 0.9 * rd, 0.5 * cd), 1);
}
