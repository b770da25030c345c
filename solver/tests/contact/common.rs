//! Shared builders: boxes, spheres and capsules as models and colliders.
#![allow(dead_code)] // shared by the test modules; not every module uses every helper

use haptloop_solver::geometry::{PairSpec, Pose3, Shape};
use haptloop_solver::{BodySpec, Model, ModelBuilder};
use nalgebra::{Matrix3, Rotation3, Vector3};

/// A box shape of half extents `h`.
pub fn cuboid(h: [f64; 3]) -> Shape {
    Shape::Box { half_extents_m: h }
}

/// A builder with gravity, a fixed 40 × 40 × 4 cm table whose top is at
/// z = 0, and a fixed 4 × 12 × 4 cm block standing on it centred at x =
/// `block_x`: the ground of the dragged-cube tests.
pub fn table_and_block(block_x: f64) -> ModelBuilder {
    let mut b = ModelBuilder::new();
    b.gravity([0.0, 0.0, -9.81]);
    b.body(
        BodySpec::fixed("table")
            .at([0.0, 0.0, -0.02])
            .shape(cuboid([0.2, 0.2, 0.02])),
    );
    b.body(
        BodySpec::fixed("block")
            .at([block_x, 0.0, 0.02])
            .shape(cuboid([0.02, 0.06, 0.02])),
    );
    b
}

/// Three bodies: moving A, moving B, fixed C, each with a shape, and the
/// contact rows of pairs (A, B) and (A, C) with `slots` rows each, plus
/// friction rows on (A, B) when `friction`.
pub fn three_bodies(shapes: [Shape; 3], slots: u32) -> Model {
    let mut b = ModelBuilder::new();
    b.body(
        BodySpec::new("a")
            .at([0.0, 0.0, 0.3])
            .shape(shapes[0].clone()),
    );
    b.body(
        BodySpec::new("b")
            .at([0.0, 0.0, 0.6])
            .shape(shapes[1].clone()),
    );
    b.body(BodySpec::fixed("c").shape(shapes[2].clone()));
    let base = b.build().expect("model");
    base.with_contacts(&[
        PairSpec {
            bodies: [0, 1],
            slots,
            friction: true,
        },
        PairSpec {
            bodies: [0, 2],
            slots,
            friction: false,
        },
    ])
    .expect("contacts")
}

/// A pose at `r` rotated by `angle` about `axis`.
pub fn pose(r: [f64; 3], axis: [f64; 3], angle: f64) -> Pose3 {
    let rot =
        Rotation3::from_axis_angle(&nalgebra::Unit::new_normalize(Vector3::from(axis)), angle);
    Pose3 {
        r: Vector3::from(r),
        rot: rot.into_inner(),
    }
}

/// The identity pose at `r`.
pub fn at(r: [f64; 3]) -> Pose3 {
    Pose3 {
        r: Vector3::from(r),
        rot: Matrix3::identity(),
    }
}

use haptloop_solver::contact::{ContactManager, ContactUpdate};
use haptloop_solver::geometry::ContactSettings;
use haptloop_solver::{FingerTarget, Program, SolverSettings, TickReport};
use std::sync::Arc;
use std::time::Duration;

/// The fast loop and the slow loop's contact cycle in lockstep, as the
/// session's deterministic mode runs them: a tick every `dt`, a contact
/// cycle every `every` ticks whose update is taken over at once.
pub struct Lockstep {
    pub program: Program,
    pub manager: ContactManager,
    pub every: u64,
    pub dt: Duration,
    pub ticks: u64,
    pub programs: u64,
    pub tables: u64,
    pub backups: u64,
    pub max_penetration_m: f64,
    /// The last contact cycle's report.
    pub last_cycle: haptloop_solver::geometry::Cycle,
    /// The configuration the last cycle saw.
    pub last_snapshot_q: Vec<f64>,
    /// Hand replaced programs back to the manager for reuse, as the
    /// session's slow loop does (on unless a test turns it off).
    pub recycle: bool,
    /// After each witness table, refactor again with a whole force solve
    /// (`Program::refresh_factor`): the refresh `apply_witnesses` made
    /// before it refactored only what the steps use.
    pub full_refresh: bool,
}

impl Lockstep {
    /// Builds the manager and the first program at the model's q0.
    pub fn new(model: Model, settings: SolverSettings, contact: ContactSettings) -> Self {
        // As the session sets it: the contact distance per 5-tick cycle.
        let settings = SolverSettings {
            contact_step_m: contact.contact_distance_m / 5.0,
            ..settings
        };
        Self::with_settings(model, settings, contact)
    }

    /// As [`new`](Self::new), with `settings` exactly as given (no contact
    /// speed limit unless it sets one).
    pub fn with_settings(model: Model, settings: SolverSettings, contact: ContactSettings) -> Self {
        let model = Arc::new(model);
        let mut manager = ContactManager::new(model.clone(), settings, contact).expect("shapes");
        let (_, program) = manager.initial(model.q0()).expect("initial program");
        Self {
            program,
            manager,
            every: 5,
            dt: Duration::from_millis(1),
            ticks: 0,
            programs: 0,
            tables: 0,
            backups: 0,
            max_penetration_m: 0.0,
            last_cycle: Default::default(),
            last_snapshot_q: Vec::new(),
            recycle: true,
            full_refresh: false,
        }
    }

    /// One tick, then a contact cycle when due.
    pub fn tick(&mut self, targets: &[FingerTarget]) -> TickReport {
        let r = self.program.tick(targets, self.dt);
        self.cycle_after(r)
    }

    /// What [`tick`](Self::tick) does after the program's tick `r`: the
    /// contact cycle when due.
    pub fn cycle_after(&mut self, r: TickReport) -> TickReport {
        self.ticks += 1;
        if self.ticks.is_multiple_of(self.every) {
            self.last_snapshot_q = self.program.q().to_vec();
            // As the session does: the bodies' velocities over the next cycle.
            let mut speeds = Vec::new();
            self.program.body_speeds(&mut speeds);
            let horizon = self.dt.as_secs_f64() * self.every as f64;
            self.manager.set_speeds(&speeds, horizon);
            let (cycle, update) = self.manager.step(
                self.program.q(),
                r.status == haptloop_solver::TickOutcome::Ok,
                true,
            );
            self.max_penetration_m = self.max_penetration_m.max(cycle.max_penetration_m);
            self.last_cycle = cycle.clone();
            match update {
                ContactUpdate::None => {}
                ContactUpdate::Table => {
                    assert!(self.program.apply_witnesses(self.manager.published()));
                    if self.full_refresh {
                        assert!(self.program.refresh_factor());
                    }
                    self.tables += 1;
                }
                ContactUpdate::Program { mut program, reset } => {
                    program.adopt_state(&self.program);
                    if let Some(q) = reset {
                        program.set_q(&q).expect("reset");
                        self.backups += 1;
                    }
                    let old = std::mem::replace(&mut self.program, *program);
                    if self.recycle {
                        self.manager.recycle(old);
                    }
                    self.programs += 1;
                }
            }
        }
        r
    }

    /// World position of body `name`.
    pub fn position(&self, name: &str) -> Vector3<f64> {
        let m = self.program.model();
        let id = m.body_id(name).expect("body");
        m.body_position(self.program.q(), id).expect("position")
    }
}
