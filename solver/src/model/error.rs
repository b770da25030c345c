//! Build errors: each names the offending body, joint, finger or inequality.

use std::fmt;

use super::spec::{DesignParam, JointKind};

/// The item an error is about, printed as ``joint `j3` `` etc.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Owner {
    /// A `[[body]]`.
    Body(String),
    /// A `[[joint]]` (unnamed joints are `#k`, 1-based).
    Joint(String),
    /// A `[[finger]]`.
    Finger(String),
    /// A point–plane inequality passed to
    /// [`Model::with_inequalities`](crate::Model::with_inequalities).
    Inequality(String),
    /// An `[[objective]]` (by its name, or its kind).
    Objective(String),
    /// Scene-level settings (gravity).
    Scene,
}

impl fmt::Display for Owner {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Body(n) => write!(f, "body `{n}`"),
            Self::Joint(n) => write!(f, "joint `{n}`"),
            Self::Finger(n) => write!(f, "finger `{n}`"),
            Self::Inequality(n) => write!(f, "inequality `{n}`"),
            Self::Objective(n) => write!(f, "objective `{n}`"),
            Self::Scene => f.write_str("scene"),
        }
    }
}

/// Why [`ModelBuilder::build`](crate::ModelBuilder::build) (or
/// [`Model::with_inequalities`](crate::Model::with_inequalities)) rejected its input.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum BuildError {
    /// A name is empty.
    #[error("{owner}: the name is empty")]
    EmptyName {
        /// What has no name (its index is in the owner string).
        owner: Owner,
    },
    /// Two bodies, joints or fingers share a name.
    #[error("{owner}: the name is used twice")]
    DuplicateName {
        /// The second item with the name.
        owner: Owner,
    },
    /// A number is NaN or infinite.
    #[error("{owner}: `{field}` is not finite")]
    NonFinite {
        /// Where.
        owner: Owner,
        /// Which field.
        field: &'static str,
    },
    /// A position, anchor, length or point beyond ±[`MAX_COORDINATE_M`](super::compiler::MAX_COORDINATE_M).
    #[error("{owner}: `{field}` holds {value:e} m; scenes are limited to ±10 km (|x| ≤ 1e4 m)")]
    OutOfRange {
        /// Where.
        owner: Owner,
        /// Which field.
        field: &'static str,
        /// The offending entry, m.
        value: f64,
    },
    /// An orientation quaternion is zero or overflows when squared.
    #[error("{owner}: `orientation` cannot be normalised (zero or overflowing)")]
    ZeroOrientation {
        /// The body.
        owner: Owner,
    },
    /// A mass is not positive.
    #[error("{owner}: mass {mass_kg} kg must be positive")]
    NonPositiveMass {
        /// The body.
        owner: Owner,
        /// The mass given.
        mass_kg: f64,
    },
    /// Principal moments not positive (a moving body) or violating the
    /// triangle inequality.
    #[error(
        "{owner}: inertia {inertia_kg_m2:?} kg·m² is not physical (a moving body's moments must be > 0 and each ≤ the sum of the other two)"
    )]
    BadInertia {
        /// The body.
        owner: Owner,
        /// The moments given.
        inertia_kg_m2: [f64; 3],
    },
    /// A reference to a body name (or id) that does not exist.
    #[error("{owner}: names unknown body `{body}`")]
    UnknownBody {
        /// The joint, finger or inequality.
        owner: Owner,
        /// The name (or id) given.
        body: String,
    },
    /// A joint (or inequality) names the same body twice.
    #[error("{owner}: names body `{body}` twice")]
    SameBody {
        /// The joint.
        owner: Owner,
        /// The body.
        body: String,
    },
    /// Both bodies are fixed (or the world): the constraint would have no columns.
    #[error("{owner}: both bodies are fixed, so it constrains nothing")]
    BothFixed {
        /// The joint or inequality.
        owner: Owner,
    },
    /// The kind needs `axes` and none were given.
    #[error("{owner}: a {kind} joint needs `axes`")]
    MissingAxes {
        /// The joint.
        owner: Owner,
        /// Its kind.
        kind: JointKind,
    },
    /// An axis or normal has zero length.
    #[error("{owner}: {field} has zero length")]
    ZeroAxis {
        /// The joint or inequality.
        owner: Owner,
        /// `axes[0]`, `axes[1]` or `normal`.
        field: &'static str,
    },
    /// Axes that must be perpendicular are parallel at the initial configuration
    /// (the perpendicular row would have a zero gradient there).
    #[error(
        "{owner}: axes are parallel at the initial configuration; a {kind} joint needs them perpendicular"
    )]
    ParallelAxes {
        /// The joint.
        owner: Owner,
        /// Its kind.
        kind: JointKind,
    },
    /// A distance joint's anchors coincide at the initial configuration, so the
    /// strut has no direction.
    #[error(
        "{owner}: anchors coincide at the initial configuration, so the distance has no direction"
    )]
    CoincidentAnchors {
        /// The joint.
        owner: Owner,
    },
    /// A distance joint's length is not positive.
    #[error("{owner}: length {length_m} m must be positive")]
    NonPositiveLength {
        /// The joint.
        owner: Owner,
        /// The length given.
        length_m: f64,
    },
    /// `length` given on a kind that has none.
    #[error("{owner}: a {kind} joint has no `length`")]
    UnexpectedLength {
        /// The joint.
        owner: Owner,
        /// Its kind.
        kind: JointKind,
    },
    /// Limits with lo > hi.
    #[error("{owner}: limits [{lo}, {hi}] have lo > hi")]
    LimitsReversed {
        /// The joint.
        owner: Owner,
        /// Lower limit.
        lo: f64,
        /// Upper limit.
        hi: f64,
    },
    /// Limits on a kind without a joint coordinate.
    #[error(
        "{owner}: a {kind} joint has no joint coordinate to limit (only revolute, prismatic and distance do)"
    )]
    LimitsUnsupported {
        /// The joint.
        owner: Owner,
        /// Its kind.
        kind: JointKind,
    },
    /// Revolute limits outside (−π, π).
    #[error("{owner}: revolute limits [{lo}, {hi}] rad must lie inside (-π, π)")]
    AngleLimitsOutOfRange {
        /// The joint.
        owner: Owner,
        /// Lower limit.
        lo: f64,
        /// Upper limit.
        hi: f64,
    },
    /// A fixed (not free) distance length lies outside its limits: infeasible.
    #[error("{owner}: length {length_m} m lies outside limits [{lo}, {hi}] and is not free")]
    LengthOutsideLimits {
        /// The joint.
        owner: Owner,
        /// The length.
        length_m: f64,
        /// Lower limit.
        lo: f64,
        /// Upper limit.
        hi: f64,
    },
    /// A design variable the kind does not have.
    #[error("{owner}: a {kind} joint has no design variable `{param}`")]
    UnsupportedFree {
        /// The joint.
        owner: Owner,
        /// Its kind.
        kind: JointKind,
        /// The parameter.
        param: DesignParam,
    },
    /// A design variable listed twice.
    #[error("{owner}: design variable `{param}` is listed twice")]
    DuplicateFree {
        /// The joint.
        owner: Owner,
        /// The parameter.
        param: DesignParam,
    },
    /// `free` on a body that is not fixed, or with a parameter a body has not.
    #[error(
        "{owner}: `free = [\"{param}\"]` is not available here: a fixed body may free its `position` (a moving body's position is already free)"
    )]
    UnsupportedBodyFree {
        /// The body.
        owner: Owner,
        /// The parameter.
        param: DesignParam,
    },
    /// `bounds` given where nothing is free.
    #[error("{owner}: `bounds` given but nothing is free (add `free = [...]`)")]
    BoundsWithoutFree {
        /// The joint or body.
        owner: Owner,
    },
    /// Per-component (vector) bounds on a one-component variable.
    #[error(
        "{owner}: per-component bounds [[...], [...]] need 3-wide variables, but `{param}` has one component; use `bounds = [lo, hi]`"
    )]
    BoundsShape {
        /// The joint.
        owner: Owner,
        /// The one-component parameter.
        param: DesignParam,
    },
    /// Bounds with lo > hi.
    #[error("{owner}: bounds [{lo}, {hi}] have lo > hi")]
    BoundsReversed {
        /// The joint or body.
        owner: Owner,
        /// Lower bound.
        lo: f64,
        /// Upper bound.
        hi: f64,
    },
    /// A design variable's initial value lies outside its bounds.
    #[error("{owner}: `{var}` starts at {value} m, outside its bounds [{lo}, {hi}]")]
    OutsideBounds {
        /// The joint or body.
        owner: Owner,
        /// The component's name (`"left.length"`, `"foot.position.z"`).
        var: String,
        /// Its initial value.
        value: f64,
        /// Lower bound.
        lo: f64,
        /// Upper bound.
        hi: f64,
    },
    /// An objective's value out of range.
    #[error("{owner}: `{field}` must be {why}")]
    BadObjective {
        /// The objective.
        owner: Owner,
        /// The key.
        field: &'static str,
        /// What it must be.
        why: &'static str,
    },
    /// Two successive bodies of a dexterity chain share no joint.
    #[error(
        "{owner}: no joint between `{a}` and `{b}`; a chain's bodies must be joined in order, base first"
    )]
    ChainNotJoined {
        /// The objective.
        owner: Owner,
        /// The earlier body.
        a: String,
        /// The later body.
        b: String,
    },
    /// A dexterity chain's joint of a kind without a Jacobian column form.
    #[error(
        "{owner}: joint `{joint}` is a {kind} joint; a dexterity chain needs revolute, prismatic, spherical or universal joints"
    )]
    ChainJointKind {
        /// The objective.
        owner: Owner,
        /// The joint.
        joint: String,
        /// Its kind.
        kind: crate::ConstraintKind,
    },
    /// A reference to a joint name that does not exist.
    #[error("{owner}: names unknown joint `{joint}`")]
    UnknownJoint {
        /// The objective.
        owner: Owner,
        /// The name given.
        joint: String,
    },
    /// A joint named for `joint_limit_distance` has no limits.
    #[error("{owner}: joint `{joint}` has no `limits` to keep away from")]
    NoLimits {
        /// The objective.
        owner: Owner,
        /// The joint.
        joint: String,
    },
    /// A finger on a fixed body.
    #[error("{owner}: body `{body}` is fixed; a finger must hold a moving body")]
    FingerOnFixedBody {
        /// The finger.
        owner: Owner,
        /// The body.
        body: String,
    },
    /// A shape that cannot be used (sizes, hull, mass from density).
    #[error("{owner}: `{field}`: {error}")]
    Shape {
        /// The body.
        owner: Owner,
        /// `shape` or `density`.
        field: &'static str,
        /// What is wrong.
        error: crate::geometry::ShapeError,
    },
    /// A contact finger's radius or friction out of range.
    #[error("{owner}: `{field}` = {value} must be {why}")]
    BadFingertip {
        /// The finger.
        owner: Owner,
        /// `radius` or `friction`.
        field: &'static str,
        /// The value given.
        value: f64,
        /// The valid range.
        why: &'static str,
    },
    /// Semantic rows asked of a model that already has derived (contact or
    /// semantic) rows: they are derived from the mechanism alone.
    #[error("{owner}: semantic rows are derived from a model without contact or semantic rows")]
    AlreadyDerived {
        /// The model's owner (the scene).
        owner: Owner,
    },
    /// An `on_surface` or `rolling` joint that cannot be built (see
    /// [`crate::parametric`]).
    #[error("{owner}: {why}")]
    Surface {
        /// The joint.
        owner: Owner,
        /// The key at fault: `surface`, `radius`, `anchors` or `kind`.
        field: &'static str,
        /// What is wrong, with the values.
        why: String,
    },
    /// A flexible body, or a joint or finger on one, that cannot be built
    /// (see [`crate::flexible`]).
    #[error("{owner}: {why}")]
    Flexible {
        /// The body, joint or finger.
        owner: Owner,
        /// What is wrong, with the values.
        why: String,
    },
    /// A body's Coulomb μ is negative, not finite or above
    /// [`MAX_FRICTION`](super::MAX_FRICTION).
    #[error("{owner}: `friction` = {value} must be finite and in [0, 10]")]
    BadFriction {
        /// The body.
        owner: Owner,
        /// The value given.
        value: f64,
    },
}

impl BuildError {
    /// The item the error is about.
    pub fn owner(&self) -> &Owner {
        use BuildError::*;
        match self {
            EmptyName { owner }
            | DuplicateName { owner }
            | NonFinite { owner, .. }
            | OutOfRange { owner, .. }
            | ZeroOrientation { owner }
            | NonPositiveMass { owner, .. }
            | BadInertia { owner, .. }
            | UnknownBody { owner, .. }
            | SameBody { owner, .. }
            | BothFixed { owner }
            | MissingAxes { owner, .. }
            | ZeroAxis { owner, .. }
            | ParallelAxes { owner, .. }
            | CoincidentAnchors { owner }
            | NonPositiveLength { owner, .. }
            | UnexpectedLength { owner, .. }
            | LimitsReversed { owner, .. }
            | LimitsUnsupported { owner, .. }
            | AngleLimitsOutOfRange { owner, .. }
            | LengthOutsideLimits { owner, .. }
            | UnsupportedFree { owner, .. }
            | DuplicateFree { owner, .. }
            | UnsupportedBodyFree { owner, .. }
            | BoundsWithoutFree { owner }
            | BoundsShape { owner, .. }
            | BoundsReversed { owner, .. }
            | OutsideBounds { owner, .. }
            | BadObjective { owner, .. }
            | ChainNotJoined { owner, .. }
            | ChainJointKind { owner, .. }
            | UnknownJoint { owner, .. }
            | NoLimits { owner, .. }
            | FingerOnFixedBody { owner, .. }
            | Shape { owner, .. }
            | BadFingertip { owner, .. }
            | BadFriction { owner, .. }
            | AlreadyDerived { owner }
            | Flexible { owner, .. }
            | Surface { owner, .. } => owner,
        }
    }
}
