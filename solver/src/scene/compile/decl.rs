//! What a compiled scene is: the types `LoadedScene::compile` returns.

use crate::scene::compile_semantic::HoldDecl;
use crate::{FingerId, Model};
use std::ops::Range;
use std::path::PathBuf;

/// The `[solver]` values the file set (unset keys are `None`; the session
/// fills them from command-line flags or the solver's defaults).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct SceneSettings {
    /// Fast-loop rate, Hz.
    pub rate_hz: Option<u32>,
    /// AL iterations per tick.
    pub iterations: Option<u32>,
    /// h.
    pub step: Option<f64>,
    /// K.
    pub gain: Option<f64>,
    /// k₂.
    pub multiplier_gain: Option<f64>,
    /// Newton-KKT stopping tolerance.
    pub placement_tolerance: Option<f64>,
    /// μ.
    pub damping: Option<f64>,
    /// Witness activation distance, m.
    pub contact_distance: Option<f64>,
    /// Witness removal distance, m.
    pub release_distance: Option<f64>,
    /// Violation the scene promises to stay under, m.
    pub violation_tolerance: Option<f64>,
    /// Virtual-coupling stiffness, N/m.
    pub coupling_stiffness: Option<f64>,
    /// Virtual-coupling damping, N·s/m.
    pub coupling_damping: Option<f64>,
    /// Velocity low-pass time constant, s.
    pub velocity_filter: Option<f64>,
    /// Inertial motion (`dynamics`).
    pub dynamics: Option<bool>,
    /// Contact penetration beyond which the slow loop backs up, m.
    pub penetration_tolerance: Option<f64>,
    /// Pre-emptive witness guards (`contact_guards`).
    pub contact_guards: Option<bool>,
    /// The fast loop's coordinates (validated).
    pub coordinates: Option<crate::Coordinates>,
}

/// What the simulated hand does, in the scene frame (offsets from the finger's
/// initial world position).
#[derive(Debug, Clone, PartialEq)]
pub enum HandPath {
    /// Stay where the finger starts.
    Still,
    /// r((cos ωt − 1)u + sin ωt v).
    Circle {
        /// m.
        radius_m: f64,
        /// Revolutions per second.
        hz: f64,
        /// In-plane direction.
        u: [f64; 3],
        /// In-plane direction.
        v: [f64; 3],
    },
    /// Move by `to_m` over `seconds`, then hold.
    Line {
        /// m.
        to_m: [f64; 3],
        /// s.
        seconds: f64,
    },
    /// Offsets at given times, linearly interpolated (an inline trace):
    /// `[t_s, dx_m, dy_m, dz_m]`, times strictly increasing.
    Waypoints {
        /// The points.
        points: Vec<[f64; 4]>,
    },
    /// A CSV trace, path resolved relative to the scene file.
    Trace {
        /// Resolved path.
        path: PathBuf,
        /// Where the path was written, for errors.
        span: Range<usize>,
    },
}

/// A simulated hand: trajectory plus optional grip settings.
#[derive(Debug, Clone, PartialEq)]
pub struct HandDecl {
    /// The trajectory.
    pub path: HandPath,
    /// Grip stiffness, N/m (None: the device crate's default).
    pub stiffness_n_per_m: Option<f64>,
    /// Grip damping, N·s/m (None: default).
    pub damping_n_s_per_m: Option<f64>,
}

/// One `[[device]]`.
#[derive(Debug, Clone, PartialEq)]
pub struct DeviceDecl {
    /// Unique name.
    pub name: String,
    /// Device model name (validated by the session against the device crate).
    pub model: String,
    /// Where `model` was written, for errors.
    pub model_span: Range<usize>,
    /// Scene metres per device metre.
    pub scale: f64,
    /// Device frame in the scene, `[w, x, y, z]`, normalised.
    pub orientation_wxyz: [f64; 4],
    /// The simulated hand (default: still).
    pub hand: HandDecl,
}

/// One `[[finger]]`, wired to its device and its model finger.
#[derive(Debug, Clone, PartialEq)]
pub struct FingerDecl {
    /// Unique name.
    pub name: String,
    /// Index into [`CompiledScene::devices`].
    pub device: usize,
    /// The finger in the model.
    pub finger: FingerId,
}

/// A scene compiled to what it needs.
#[derive(Debug, Clone)]
pub struct CompiledScene {
    /// `[scene] name`.
    pub name: String,
    /// `[scene] description`.
    pub description: String,
    /// The mechanism.
    pub model: Model,
    /// Its design objectives and the built-in weights (`[[objective]]`),
    /// for [`Program::with_objectives`](crate::Program::with_objectives).
    pub objectives: std::sync::Arc<crate::Objectives>,
    /// The mechanism without its fingers: the same q layout, joint and
    /// quaternion-norm rows only.
    pub joints_only: Model,
    /// `[solver]` values the file set.
    pub settings: SceneSettings,
    /// One per `[[device]]`, in file order.
    pub devices: Vec<DeviceDecl>,
    /// One per `[[finger]]`, in file order (the model's finger order).
    pub fingers: Vec<FingerDecl>,
    /// Bodies with a collision shape (contact machinery is compiled only for these).
    pub shaped_bodies: usize,
    /// Semantic offer + binding areas declared.
    pub semantic_areas: usize,
    /// The semantic layer: areas, label order, `[semantic]` settings
    /// (`None` without areas; checked consistent at q0).
    pub semantic: Option<crate::semantic::SemanticSpec>,
    /// The contact fingers' scheduled holds.
    pub holds: Vec<HoldDecl>,
    /// Design variables switched on and off during the run, by time
    /// (`[[design_flag]]`, plus any `--design-on` / `--design-off`).
    pub design_flags: Vec<crate::scene::DesignFlagDecl>,
    /// Objects added and removed, modes switched, by time (`[[schedule]]`).
    pub schedule: Vec<crate::scene::ScheduleDecl>,
    /// Bodies absent at the start (their first schedule entry adds them).
    pub absent: Vec<crate::BodyId>,
}
