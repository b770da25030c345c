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

/// `[[body]]`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BodySection {
    /// Required, unique.
    pub name: Spanned<String>,
    /// Fixed bodies have no coordinates.
    #[serde(default)]
    pub fixed: bool,
    /// m, scene frame; default origin.
    #[serde(default)]
    pub position: Option<Spanned<Vec3>>,
    /// `[w, x, y, z]`; default identity.
    #[serde(default)]
    pub orientation: Option<Spanned<Quat>>,
    /// kg.
    #[serde(default)]
    pub mass: Option<Spanned<f64>>,
    /// Principal moments, kg·m², body frame.
    #[serde(default)]
    pub inertia: Option<Spanned<Vec3>>,
    /// Collision shape; a body without one takes part in no contact.
    #[serde(default)]
    pub shape: Option<Spanned<ShapeSpec>>,
    /// kg/m³: mass and inertia from the shape when `mass` is absent.
    #[serde(default)]
    pub density: Option<Spanned<f64>>,
    /// Coulomb μ of the body's contacts with other bodies.
    #[serde(default)]
    pub friction: Option<Spanned<f64>>,
    /// Restitution of the body's contacts, in [0, 1].
    #[serde(default)]
    pub restitution: Option<Spanned<f64>>,
    /// Velocity damping, 1/s.
    #[serde(default)]
    pub damping: Option<Spanned<f64>>,
    /// Initial velocity, m/s, scene frame.
    #[serde(default)]
    pub velocity: Option<Spanned<Vec3>>,
    /// Initial angular velocity, rad/s, scene frame.
    #[serde(default)]
    pub angular_velocity: Option<Spanned<Vec3>>,
    /// `[[body.offer]]` semantic areas.
    #[serde(default)]
    pub offer: Vec<AreaSection>,
    /// `[[body.binding]]` semantic areas.
    #[serde(default)]
    pub binding: Vec<AreaSection>,
    /// Design variables of a fixed body: `["position"]`.
    #[serde(default)]
    pub free: Vec<Spanned<FreeSpec>>,
    /// Bounds on the freed position.
    #[serde(default)]
    pub bounds: Option<Spanned<BoundsSpec>>,
    /// A flexible body's beam (Nelson & Cohen §4).
    #[serde(default)]
    pub flexible: Option<Spanned<FlexibleSpec>>,
}

/// `flexible = { span, clamp, stiffness, stiffness_z, modes }`.
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FlexibleSpec {
    /// `[x0, x1]` along the body's x axis, m, body frame.
    pub span: Arr<f64, 2>,
    /// Where on the span the body frame is the beam's tangent frame, m
    /// (default 0).
    #[serde(default)]
    pub clamp: Option<f64>,
    /// EI for deflection along the body's y axis (and z unless
    /// `stiffness_z`), N·m².
    pub stiffness: f64,
    /// EI for deflection along z, N·m² (default: `stiffness`).
    #[serde(default)]
    pub stiffness_z: Option<f64>,
    /// Shape functions per direction (default 3).
    #[serde(default)]
    pub modes: Option<u32>,
}

/// `shape = { … }`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields, rename_all = "snake_case")]
pub enum ShapeSpec {
    /// Half extents, m.
    Box(Vec3),
    /// Radius, m.
    Sphere(f64),
    /// Along the body's z axis.
    Capsule {
        /// Half the length of the cylinder part, m.
        half_height: f64,
        /// m.
        radius: f64,
    },
    /// Convex hull of the points, body frame.
    Convex(Vec<Vec3>),
}

/// A semantic offer or binding area.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AreaSection {
    /// Label in the `[labels]` partial order.
    pub label: Spanned<String>,
    /// Planar polygon, body frame.
    pub polygon: Spanned<Vec<Vec3>>,
    /// Orientation vector, body frame.
    pub normal: Spanned<Vec3>,
}

/// `kind = "…"` of a joint.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum JointKindSpec {
    /// 3 rows.
    Spherical,
    /// 5 rows.
    Revolute,
    /// 4 rows.
    Universal,
    /// 5 rows.
    Prismatic,
    /// 6 rows.
    Fixed,
    /// 1 row.
    Distance,
    /// 1 row.
    Perpendicular,
    /// 1 row.
    PointOnPlane,
    /// 3 rows + (u, v).
    OnSurface,
    /// 3 + 2 rows + (u, v).
    Rolling,
}

/// A name in `free = [...]`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FreeSpec {
    /// The distance joint's length.
    Length,
    /// The anchor on body i.
    AnchorI,
    /// The anchor on body j.
    AnchorJ,
    /// A fixed body's position (`[[body]]` only).
    Position,
}

/// `bounds = [lo, hi]` or `bounds = [[lo_x, lo_y, lo_z], [hi_x, hi_y, hi_z]]`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum BoundsSpec {
    /// The same range for every component.
    Scalar([f64; 2]),
    /// A range per component.
    Vector([[f64; 3]; 2]),
}

impl<'de> Deserialize<'de> for BoundsSpec {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        #[derive(Deserialize)]
        #[serde(untagged)]
        enum Raw {
            Scalar(Vec<f64>),
            Vector(Vec<Vec<f64>>),
        }
        let shape = || {
            serde::de::Error::custom(
                "expected `bounds = [lo, hi]` or `bounds = [[lo_x, lo_y, lo_z], [hi_x, hi_y, hi_z]]`",
            )
        };
        match Raw::deserialize(d).map_err(|_| shape())? {
            Raw::Scalar(v) => <[f64; 2]>::try_from(v)
                .map(BoundsSpec::Scalar)
                .map_err(|_| shape()),
            Raw::Vector(v) => {
                let rows: Vec<[f64; 3]> = v
                    .into_iter()
                    .map(|r| <[f64; 3]>::try_from(r).map_err(|_| shape()))
                    .collect::<Result<_, _>>()?;
                <[[f64; 3]; 2]>::try_from(rows)
                    .map(BoundsSpec::Vector)
                    .map_err(|_| shape())
            }
        }
    }
}

/// `[[joint]]`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct JointSection {
    /// Optional, unique if given.
    #[serde(default)]
    pub name: Option<Spanned<String>>,
    /// The joint kind.
    pub kind: Spanned<JointKindSpec>,
    /// Body i, body j.
    pub bodies: Spanned<Arr<Spanned<String>, 2>>,
    /// Body-local anchor points k_i, k_j, m.
    #[serde(default)]
    pub anchors: Option<Spanned<Arr<Vec3, 2>>>,
    /// Body-local axes h_i, h_j.
    #[serde(default)]
    pub axes: Option<Spanned<Arr<Vec3, 2>>>,
    /// Distance joints: strut length, m.
    #[serde(default)]
    pub length: Option<Spanned<f64>>,
    /// Inequality on the joint coordinate.
    #[serde(default)]
    pub limits: Option<Spanned<Arr<f64, 2>>>,
    /// Design variables.
    #[serde(default)]
    pub free: Vec<Spanned<FreeSpec>>,
    /// Bounds on the design variables.
    #[serde(default)]
    pub bounds: Option<Spanned<BoundsSpec>>,
    /// The two bodies' shapes collide with each other (default false).
    #[serde(default)]
    pub collide: Option<Spanned<bool>>,
    /// Report the torque a motor on this joint's axis would need (§5.2).
    #[serde(default)]
    pub report_torque: Option<Spanned<bool>>,
    /// `on_surface` and `rolling`: body j's surface.
    #[serde(default)]
    pub surface: Option<Spanned<SurfaceSection>>,
    /// `on_surface` and `rolling`: the ball's radius, m.
    #[serde(default)]
    pub radius: Option<Spanned<f64>>,
}

/// `surface = { type, radius, origin, orientation }` of a joint.
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SurfaceSection {
    /// The surface's shape.
    #[serde(rename = "type")]
    pub kind: SurfaceTypeSpec,
    /// Sphere or cylinder radius, m.
    #[serde(default)]
    pub radius: Option<f64>,
    /// Origin of its local frame, m, body j's frame.
    #[serde(default)]
    pub origin: Option<Vec3>,
    /// Its local frame, `[w, x, y, z]`, local → body.
    #[serde(default)]
    pub orientation: Option<Quat>,
}

/// `type = "…"` of a surface.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SurfaceTypeSpec {
    /// The local xy plane.
    Plane,
    /// A sphere seen from inside.
    Bowl,
    /// A sphere seen from outside.
    Dome,
    /// A cylinder along local x seen from inside.
    Trough,
    /// A cylinder along local x seen from outside.
    Ridge,
}

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

/// `kind = "…"` of an objective.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ObjectiveKindSpec {
    /// The finger rows' weight.
    Finger,
    /// Least astonishment's weight (and the design variables' metric).
    LeastAstonishment,
    /// Manipulability of a chain, Eq. 12–14.
    Dexterity,
    /// Body points kept away from an obstacle, Eq. 15.
    Obstacle,
    /// A body point kept on a line.
    StraightLine,
    /// Joints kept away from their limits.
    JointLimitDistance,
    /// Eq. 15 as written: 1 / the nearest point's distance.
    InverseDistance,
    /// A chain's reachable volume.
    WorkspaceVolume,
}

/// `{ body = "…", point = [x, y, z] }` in an objective's `points`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PointRef {
    /// The body.
    pub body: Spanned<String>,
    /// Body frame, m; default its origin.
    #[serde(default)]
    pub point: Option<Vec3>,
}

/// `[[objective]]`: one table for every kind; `validate` checks which keys
/// the kind takes.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ObjectiveSection {
    /// The kind.
    pub kind: Spanned<ObjectiveKindSpec>,
    /// Optional, unique among objectives.
    #[serde(default)]
    pub name: Option<Spanned<String>>,
    /// Relative to least astonishment; default 1.
    #[serde(default)]
    pub weight: Option<Spanned<f64>>,
    /// least_astonishment: the design variables' metric; default 1.
    #[serde(default)]
    pub design_weight: Option<Spanned<f64>>,
    /// dexterity: bodies joined in order, base first.
    #[serde(default)]
    pub chain: Option<Spanned<Vec<Spanned<String>>>>,
    /// dexterity, straight_line: the point on the (last) body, body frame.
    #[serde(default)]
    pub point: Option<Spanned<Vec3>>,
    /// dexterity: task directions, world frame.
    #[serde(default)]
    pub directions: Option<Spanned<Vec<Vec3>>>,
    /// dexterity: angular task directions (Eq. 13's angular rows), world frame.
    #[serde(default)]
    pub angular_directions: Option<Spanned<Vec<Vec3>>>,
    /// dexterity: bodies closing the chain into a loop, back to its base.
    #[serde(default)]
    pub closure: Option<Spanned<Vec<Spanned<String>>>>,
    /// obstacle: the body points kept away.
    #[serde(default)]
    pub points: Option<Spanned<Vec<Spanned<PointRef>>>>,
    /// obstacle: a world point.
    #[serde(default)]
    pub obstacle: Option<Spanned<Vec3>>,
    /// obstacle: or a body carrying the obstacle.
    #[serde(default)]
    pub obstacle_body: Option<Spanned<String>>,
    /// obstacle: the point on `obstacle_body`, body frame.
    #[serde(default)]
    pub obstacle_point: Option<Spanned<Vec3>>,
    /// obstacle: activation distance, m.
    #[serde(default)]
    pub distance: Option<Spanned<f64>>,
    /// straight_line: the body.
    #[serde(default)]
    pub body: Option<Spanned<String>>,
    /// straight_line: a point of the line, world frame.
    #[serde(default)]
    pub line_point: Option<Spanned<Vec3>>,
    /// straight_line: the line's direction, world frame.
    #[serde(default)]
    pub direction: Option<Spanned<Vec3>>,
    /// joint_limit_distance: joint names; default every limited joint.
    #[serde(default)]
    pub joints: Option<Spanned<Vec<Spanned<String>>>>,
}

impl ObjectiveSection {
    /// Every optional key that is set, with its span (for `validate`).
    pub fn keys(&self) -> Vec<(&'static str, std::ops::Range<usize>)> {
        let mut out = Vec::new();
        macro_rules! key {
            ($($f:ident),*) => {$(
                if let Some(v) = &self.$f {
                    out.push((stringify!($f), v.span()));
                }
            )*};
        }
        key!(
            name,
            weight,
            design_weight,
            chain,
            point,
            directions,
            angular_directions,
            closure,
            points,
            obstacle,
            obstacle_body,
            obstacle_point,
            distance,
            body,
            line_point,
            direction,
            joints
        );
        out
    }
}
