//! `[[device]]`, its hand, `[[finger]]` and `[[hold]]` tables.

use super::{Arr, Quat, Vec3};
use serde::Deserialize;
use toml::Spanned;

/// `[[device]]`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DeviceSection {
    /// Required, unique.
    pub name: Spanned<String>,
    /// A built-in simulated device model.
    pub model: Spanned<String>,
    /// Scene metres per device metre.
    #[serde(default)]
    pub scale: Option<Spanned<f64>>,
    /// Device frame in the scene, `[w, x, y, z]`.
    #[serde(default)]
    pub orientation: Option<Spanned<Quat>>,
    /// The simulated hand.
    #[serde(default)]
    pub hand: Option<Spanned<HandSection>>,
}

/// `hand = { … }`: one trajectory kind plus optional grip settings.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HandSection {
    /// Stay where the finger starts.
    #[serde(default)]
    pub still: Option<Spanned<bool>>,
    /// r((cos ωt − 1)u + sin ωt v).
    #[serde(default)]
    pub circle: Option<Spanned<CircleSpec>>,
    /// Move by `to` over `seconds`, then hold.
    #[serde(default)]
    pub line: Option<Spanned<LineSpec>>,
    /// CSV `t,dx,dy,dz`, relative to the scene file.
    #[serde(default)]
    pub trace: Option<Spanned<String>>,
    /// Extra: an inline trace, `[t, dx, dy, dz]` per point.
    #[serde(default)]
    pub waypoints: Option<Spanned<Vec<Arr<f64, 4>>>>,
    /// Grip stiffness, N/m.
    #[serde(default)]
    pub stiffness: Option<Spanned<f64>>,
    /// Grip damping, N·s/m.
    #[serde(default)]
    pub damping: Option<Spanned<f64>>,
}

/// `circle = { radius, hz, u, v }`.
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CircleSpec {
    /// m.
    pub radius: f64,
    /// Revolutions per second.
    pub hz: f64,
    /// First in-plane direction (scene frame).
    pub u: Vec3,
    /// Second in-plane direction (scene frame).
    pub v: Vec3,
}

/// `line = { to, seconds }`.
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LineSpec {
    /// Offset reached at the end, m, scene frame.
    pub to: Vec3,
    /// Duration of the move.
    pub seconds: f64,
}

/// `grasp = "…"`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum GraspSpec {
    /// 3 rows: the point follows the finger.
    #[default]
    Point,
    /// 6 rows: position and orientation follow the finger.
    Rigid,
    /// A fingertip ball that pushes on shapes and never pulls.
    Contact,
}

/// `[[finger]]`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FingerSection {
    /// Required, unique.
    pub name: Spanned<String>,
    /// The `[[device]]` that drives it.
    pub device: Spanned<String>,
    /// The body it holds (point and rigid grasps; required there).
    #[serde(default)]
    pub body: Option<Spanned<String>>,
    /// Body-local attachment point, m; default the body origin.
    #[serde(default)]
    pub point: Option<Spanned<Vec3>>,
    /// Point, rigid or contact grasp; default point.
    #[serde(default)]
    pub grasp: Option<Spanned<GraspSpec>>,
    /// Contact fingers: where the fingertip starts, m, world frame (required).
    #[serde(default)]
    pub position: Option<Spanned<Vec3>>,
    /// Contact fingers: fingertip radius, m (default 0.008).
    #[serde(default)]
    pub radius: Option<Spanned<f64>>,
    /// Contact fingers: Coulomb friction coefficient (default 0).
    #[serde(default)]
    pub friction: Option<Spanned<f64>>,
    /// Contact fingers: when the fingertip holds which body.
    #[serde(default)]
    pub holds: Vec<Spanned<HoldSection>>,
}

/// One `holds = [{ body, from, until }]` entry of a contact finger: from
/// `from` to `until` (s) the fingertip holds `body` where it touches it.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HoldSection {
    /// The body held (a moving one).
    pub body: Spanned<String>,
    /// When the hold starts, s.
    pub from: Spanned<f64>,
    /// When it ends, s.
    pub until: Spanned<f64>,
}
