//! `[[objective]]` tables.

use super::Vec3;
use serde::Deserialize;
use toml::Spanned;

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
