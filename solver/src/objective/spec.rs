//! The builder's vocabulary for objectives ([`ObjectiveSpec`], mirroring the
//! scene's `[[objective]]`); `compile.rs` compiles it against a built model.

use std::fmt;
use std::str::FromStr;

use crate::model::UnknownName;

/// `[[objective]] kind`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ObjectiveKind {
    /// The finger rows' penalty (its weight only).
    Finger,
    /// ½‖q − q₀‖ in the update's metric (its weight only).
    LeastAstonishment,
    /// Manipulability of a chain at a body point, Eq. 12–14.
    Dexterity,
    /// Body points kept away from an obstacle point, Eq. 15.
    Obstacle,
    /// A body point kept on a line, Fig. 10.
    StraightLine,
    /// Limited joints kept near the middle of their limits.
    JointLimitDistance,
    /// Body points kept away from an obstacle point by Eq. 15 as written.
    InverseDistance,
    /// A chain's reachable volume, App. D.
    WorkspaceVolume,
}

impl ObjectiveKind {
    /// Every kind, in declaration order.
    pub const ALL: &'static [Self] = &[
        Self::Finger,
        Self::LeastAstonishment,
        Self::Dexterity,
        Self::Obstacle,
        Self::StraightLine,
        Self::JointLimitDistance,
        Self::InverseDistance,
        Self::WorkspaceVolume,
    ];

    /// The scene-file spelling.
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Finger => "finger",
            Self::LeastAstonishment => "least_astonishment",
            Self::Dexterity => "dexterity",
            Self::Obstacle => "obstacle",
            Self::StraightLine => "straight_line",
            Self::JointLimitDistance => "joint_limit_distance",
            Self::InverseDistance => "inverse_distance",
            Self::WorkspaceVolume => "workspace_volume",
        }
    }
}

impl fmt::Display for ObjectiveKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

impl FromStr for ObjectiveKind {
    type Err = UnknownName;
    fn from_str(s: &str) -> Result<Self, UnknownName> {
        Self::ALL
            .iter()
            .copied()
            .find(|k| k.as_str() == s)
            .ok_or_else(|| UnknownName {
                what: "ObjectiveKind",
                name: s.to_owned(),
                expected: Self::ALL
                    .iter()
                    .map(|k| k.as_str())
                    .collect::<Vec<_>>()
                    .join(" | "),
            })
    }
}

/// The obstacle of an `obstacle` objective.
#[derive(Debug, Clone, PartialEq)]
pub enum ObstacleSpec {
    /// A fixed world point, metres.
    World([f64; 3]),
    /// A point of a body (body frame, metres): it moves with the body.
    Body {
        /// The body.
        body: String,
        /// The point, body frame.
        point_m: [f64; 3],
    },
}

/// One `[[objective]]`: its kind's parameters, by name.
#[derive(Debug, Clone, PartialEq)]
pub enum ObjectiveSpec {
    /// The finger rows' weight.
    Finger {
        /// Weight, ≥ 0.
        weight: f64,
    },
    /// Least astonishment's weight and the design variables' metric.
    LeastAstonishment {
        /// Weight, > 0.
        weight: f64,
        /// Design variables' metric relative to a body of mean mass, > 0.
        design_weight: f64,
    },
    /// Maximise the manipulability of `chain` at `point_m` of its last body.
    Dexterity {
        /// Optional name.
        name: Option<String>,
        /// Weight, ≥ 0.
        weight: f64,
        /// Bodies joined in order, base first (at least 2).
        chain: Vec<String>,
        /// The point x on the last body, body frame, metres.
        point_m: [f64; 3],
        /// Task directions (world, 1–3, independent); empty: x, y, z.
        directions: Vec<[f64; 3]>,
        /// Angular task directions (world, 0–3, independent): Eq. 13's
        /// angular rows; empty: none.
        angular_directions: Vec<[f64; 3]>,
        /// Bodies closing the chain into a loop, from after its last body
        /// back to its base (the last one is the chain's first); empty: an
        /// open chain.
        closure: Vec<String>,
    },
    /// Keep body points at least `distance_m` from an obstacle.
    Obstacle {
        /// Optional name.
        name: Option<String>,
        /// Weight, ≥ 0.
        weight: f64,
        /// (body, point in its frame), at least one.
        points: Vec<(String, [f64; 3])>,
        /// The obstacle.
        obstacle: ObstacleSpec,
        /// Activation distance D, metres, > 0.
        distance_m: f64,
    },
    /// Keep a body point on a world line.
    StraightLine {
        /// Optional name.
        name: Option<String>,
        /// Weight, ≥ 0.
        weight: f64,
        /// The body.
        body: String,
        /// The point, body frame, metres.
        point_m: [f64; 3],
        /// A point of the line, world frame, metres.
        line_point_m: [f64; 3],
        /// The line's direction, world frame (non-zero).
        direction: [f64; 3],
    },
    /// Keep joints near the middle of their limits.
    JointLimitDistance {
        /// Optional name.
        name: Option<String>,
        /// Weight, ≥ 0.
        weight: f64,
        /// Joint names (each with `limits`); empty: every joint with limits.
        joints: Vec<String>,
    },
    /// Eq. 15 as written: minimise 1 / (the nearest point's distance).
    InverseDistance {
        /// Optional name.
        name: Option<String>,
        /// Weight, ≥ 0.
        weight: f64,
        /// (body, point in its frame), at least one.
        points: Vec<(String, [f64; 3])>,
        /// The obstacle.
        obstacle: ObstacleSpec,
    },
    /// Maximise the volume a chain's point can reach (App. D).
    WorkspaceVolume {
        /// Optional name.
        name: Option<String>,
        /// Weight, ≥ 0.
        weight: f64,
        /// Bodies joined in order, base first (at least 2).
        chain: Vec<String>,
        /// The point on the last body, body frame, metres.
        point_m: [f64; 3],
    },
}

impl ObjectiveSpec {
    /// Its kind.
    pub fn kind(&self) -> ObjectiveKind {
        match self {
            Self::Finger { .. } => ObjectiveKind::Finger,
            Self::LeastAstonishment { .. } => ObjectiveKind::LeastAstonishment,
            Self::Dexterity { .. } => ObjectiveKind::Dexterity,
            Self::Obstacle { .. } => ObjectiveKind::Obstacle,
            Self::StraightLine { .. } => ObjectiveKind::StraightLine,
            Self::JointLimitDistance { .. } => ObjectiveKind::JointLimitDistance,
            Self::InverseDistance { .. } => ObjectiveKind::InverseDistance,
            Self::WorkspaceVolume { .. } => ObjectiveKind::WorkspaceVolume,
        }
    }

    /// Its weight.
    pub fn weight(&self) -> f64 {
        match *self {
            Self::Finger { weight }
            | Self::LeastAstonishment { weight, .. }
            | Self::Dexterity { weight, .. }
            | Self::Obstacle { weight, .. }
            | Self::StraightLine { weight, .. }
            | Self::JointLimitDistance { weight, .. }
            | Self::InverseDistance { weight, .. }
            | Self::WorkspaceVolume { weight, .. } => weight,
        }
    }

    /// Its name, if given.
    pub fn name(&self) -> Option<&str> {
        match self {
            Self::Finger { .. } | Self::LeastAstonishment { .. } => None,
            Self::Dexterity { name, .. }
            | Self::Obstacle { name, .. }
            | Self::StraightLine { name, .. }
            | Self::JointLimitDistance { name, .. }
            | Self::InverseDistance { name, .. }
            | Self::WorkspaceVolume { name, .. } => name.as_deref(),
        }
    }
}
