//! The scene file as typed values, exactly as `docs/scene-format.md` spells it.
//!
//! Every value a later check may complain about keeps its byte span
//! ([`Spanned`]) so the complaint can name the line and column. Unknown keys,
//! wrong types, wrong array lengths, missing required keys and duplicate keys
//! are rejected by the TOML deserializer itself (`deny_unknown_fields`); the
//! semantic checks live in `validate`.

use serde::Deserialize;
use std::collections::BTreeMap;
use toml::Spanned;

pub use super::gear::{GearKindSpec, GearSection};

mod body;
mod device;
mod joint;
mod objective;

pub use body::{AreaSection, BodySection, FlexibleSpec, ShapeSpec};
pub use device::{
    CircleSpec, DeviceSection, FingerSection, GraspSpec, HandSection, HoldSection, LineSpec,
};
pub use joint::{
    BoundsSpec, FreeSpec, JointKindSpec, JointSection, SurfaceSection, SurfaceTypeSpec,
};
pub use objective::{ObjectiveSection, PointRef};
/// A 3-vector in the file: `[x, y, z]`.
pub type Vec3 = Arr<f64, 3>;
/// A quaternion in the file: `[w, x, y, z]` (normalised on load).
pub type Quat = Arr<f64, 4>;

/// A TOML array of exactly `N` elements. Serde's own `[T; N]` reads the
/// first `N` elements and silently drops the rest (`position` with four
/// numbers passed as three); this one refuses any other length.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Arr<T, const N: usize>(pub [T; N]);

impl<T, const N: usize> std::ops::Deref for Arr<T, N> {
    type Target = [T; N];
    fn deref(&self) -> &[T; N] {
        &self.0
    }
}

impl<T: Copy, const N: usize> Arr<T, N> {
    /// The elements as a plain array.
    pub fn get(&self) -> [T; N] {
        self.0
    }
}

impl<const M: usize, const N: usize> Arr<Arr<f64, M>, N> {
    /// An array of arrays as plain nested arrays.
    pub fn nested(&self) -> [[f64; M]; N] {
        self.0.map(|a| a.0)
    }
}

impl<'a, T, const N: usize> IntoIterator for &'a Arr<T, N> {
    type Item = &'a T;
    type IntoIter = std::slice::Iter<'a, T>;
    fn into_iter(self) -> Self::IntoIter {
        self.0.iter()
    }
}

impl<'de, T: Deserialize<'de>, const N: usize> Deserialize<'de> for Arr<T, N> {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let v = Vec::<T>::deserialize(d)?;
        let len = v.len();
        <[T; N]>::try_from(v).map(Arr).map_err(|_| {
            serde::de::Error::custom(format!(
                "invalid length {len}, expected an array of length {N}"
            ))
        })
    }
}

/// The whole file.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneFile {
    /// `[scene]`: name, description, gravity.
    pub scene: SceneSection,
    /// `[solver]`: rates, iterations, gains, tolerances.
    #[serde(default)]
    pub solver: SolverSection,
    /// `[[body]]` tables, in file order.
    #[serde(default, rename = "body")]
    pub bodies: Vec<BodySection>,
    /// `[[joint]]` tables, in file order.
    #[serde(default, rename = "joint")]
    pub joints: Vec<JointSection>,
    /// `[[gear]]` tables, in file order.
    #[serde(default, rename = "gear")]
    pub gears: Vec<GearSection>,
    /// `[[device]]` tables, in file order.
    #[serde(default, rename = "device")]
    pub devices: Vec<DeviceSection>,
    /// `[[finger]]` tables, in file order.
    #[serde(default, rename = "finger")]
    pub fingers: Vec<FingerSection>,
    /// `[[objective]]` tables, in file order.
    #[serde(default, rename = "objective")]
    pub objectives: Vec<ObjectiveSection>,
    /// `[[design_flag]]` tables: design variables switched on and off.
    #[serde(default, rename = "design_flag")]
    pub design_flags: Vec<super::design_flags::DesignFlagSection>,
    /// `[labels]`: each key is ≤ every label in its list (a partial order).
    #[serde(default)]
    pub labels: BTreeMap<Spanned<String>, Spanned<Vec<Spanned<String>>>>,
    /// `[semantic]`: snapping and breaking of semantic constraints.
    #[serde(default)]
    pub semantic: Option<SemanticSection>,
    /// `[[schedule]]` tables: objects added and removed, modes switched.
    #[serde(default, rename = "schedule")]
    pub schedule: Vec<super::schedule::ScheduleSection>,
}

/// `[semantic]`: every key optional (defaults in
/// [`SemanticSettings`](crate::semantic::SemanticSettings)).
#[derive(Debug, Clone, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SemanticSection {
    /// A binding this close to a fitting offer's plane snaps, m.
    pub snap_distance: Option<Spanned<f64>>,
    /// … if its orientation is this close to the offer's, rad.
    pub snap_angle: Option<Spanned<f64>>,
    /// Speed at which a snap pulls the binding onto the offer, m/s.
    pub snap_speed: Option<Spanned<f64>>,
    /// The largest change of a finger's force a snap's pull may cause, N.
    pub snap_force: Option<Spanned<f64>>,
    /// Pulling a held object off its offer harder than this breaks the
    /// constraint, N.
    pub break_force: Option<Spanned<f64>>,
}

/// `[scene]`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneSection {
    /// Required.
    pub name: Spanned<String>,
    /// One line for `haptloop scenes`.
    #[serde(default)]
    pub description: Option<String>,
    /// m/s², scene frame; default none (zero).
    #[serde(default)]
    pub gravity: Option<Spanned<Vec3>>,
}

/// `[solver]`: every key optional; defaults live in the solver's settings.
#[derive(Debug, Clone, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SolverSection {
    /// Fast-loop rate, Hz.
    pub rate_hz: Option<Spanned<u32>>,
    /// Augmented-Lagrangian iterations per tick.
    pub iterations: Option<Spanned<u32>>,
    /// h in q += h·Δq.
    pub step: Option<Spanned<f64>>,
    /// K, the constraint-violation gain.
    pub gain: Option<Spanned<f64>>,
    /// k₂, the multiplier gain.
    pub multiplier_gain: Option<Spanned<f64>>,
    /// Newton-KKT stopping tolerance (constraint norm).
    pub placement_tolerance: Option<Spanned<f64>>,
    /// μ in (J Jᵀ + μI).
    pub damping: Option<Spanned<f64>>,
    /// Witness activation distance, m.
    pub contact_distance: Option<Spanned<f64>>,
    /// Witness removal distance, m.
    pub release_distance: Option<Spanned<f64>>,
    /// Extra: the constraint violation this scene promises to stay under while
    /// running (m for translational rows); checked by the scene tests.
    pub violation_tolerance: Option<Spanned<f64>>,
    /// Extra: virtual-coupling stiffness between device point and finger, N/m.
    pub coupling_stiffness: Option<Spanned<f64>>,
    /// Extra: virtual-coupling damping, N·s/m.
    pub coupling_damping: Option<Spanned<f64>>,
    /// Extra: time constant of the low-pass filter on body velocities
    /// estimated from q, seconds (0 turns it off).
    pub velocity_filter: Option<Spanned<f64>>,
    /// Extra: inertial motion (bodies keep their velocity and fall under
    /// gravity) instead of least astonishment alone.
    pub dynamics: Option<Spanned<bool>>,
    /// Extra: contact penetration beyond which the slow loop backs up, m.
    pub penetration_tolerance: Option<Spanned<f64>>,
    /// Extra: pre-emptive witness guards on nearby vertices and edges
    /// (default on; off leaves penetrations to the backup and §3.2.1).
    pub contact_guards: Option<Spanned<bool>>,
    /// Extra: the fast loop's coordinates, `"augmented"` (default),
    /// `"joint"` or `"auto"` (`SolverSettings::coordinates`).
    pub coordinates: Option<Spanned<String>>,
}
