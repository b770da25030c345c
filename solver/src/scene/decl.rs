//! What a compiled scene declares besides the model: the devices, their
//! hands and the finger wiring.

use crate::FingerId;
use std::ops::Range;
use std::path::PathBuf;

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
