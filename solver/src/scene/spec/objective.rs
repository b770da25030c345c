//! `[[objective]]` tables.

use super::Vec3;
use crate::ObjectiveKind;
use serde::de::{self, EnumAccess, VariantAccess, Visitor};
use serde::{Deserialize, Deserializer};
use std::fmt;
use std::sync::LazyLock;
use toml::Spanned;

/// `kind = "…"` of an objective is the model's [`ObjectiveKind`], spelled
/// as [`ObjectiveKind::as_str`] spells it. Its `Deserialize` lives here, in
/// the scene layer, so the model keeps no serde: it reads the kind as
/// `#[derive(Deserialize)]` with `rename_all = "snake_case"` would (a unit
/// variant; an unknown name is an error at the name, listing every kind).
impl<'de> Deserialize<'de> for ObjectiveKind {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct Kind;
        impl<'de> Visitor<'de> for Kind {
            type Value = ObjectiveKind;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("enum ObjectiveKind")
            }
            fn visit_enum<A: EnumAccess<'de>>(self, data: A) -> Result<ObjectiveKind, A::Error> {
                let (KindName(kind), variant) = data.variant()?;
                variant.unit_variant()?;
                Ok(kind)
            }
        }
        d.deserialize_enum("ObjectiveKind", kind_names(), Kind)
    }
}

/// Every kind's spelling, in declaration order.
fn kind_names() -> &'static [&'static str] {
    static NAMES: LazyLock<Vec<&'static str>> =
        LazyLock::new(|| ObjectiveKind::ALL.iter().map(|k| k.as_str()).collect());
    &NAMES
}

/// An objective kind's name (the enum's variant identifier).
struct KindName(ObjectiveKind);

impl<'de> Deserialize<'de> for KindName {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct Name;
        impl Visitor<'_> for Name {
            type Value = KindName;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("variant identifier")
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<KindName, E> {
                (v.parse().map(KindName)).map_err(|_| E::unknown_variant(v, kind_names()))
            }
        }
        d.deserialize_identifier(Name)
    }
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
    pub kind: Spanned<ObjectiveKind>,
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

#[cfg(test)]
mod tests {
    use super::*;

    /// What `kind` read as before this file's hand-written impl: the
    /// derived `Deserialize` of a snake_case unit enum (the reference).
    #[derive(Debug, Deserialize)]
    #[serde(rename_all = "snake_case")]
    enum Derived {
        Finger,
        LeastAstonishment,
        Dexterity,
        Obstacle,
        StraightLine,
        JointLimitDistance,
        InverseDistance,
        WorkspaceVolume,
    }

    #[derive(Debug, Deserialize)]
    struct Ours {
        kind: Spanned<ObjectiveKind>,
    }

    #[derive(Debug, Deserialize)]
    struct Theirs {
        kind: Spanned<Derived>,
    }

    /// Every kind's spelling as a string and as an inline table, unknown
    /// names in both forms, other types and a non-unit variant: the same
    /// kind (by variant name) and span, or the same message and span.
    #[test]
    fn kinds_read_as_the_derived_deserialize_read_them() {
        let mut inputs: Vec<String> = ObjectiveKind::ALL
            .iter()
            .flat_map(|k| {
                let k = k.as_str();
                [
                    format!("kind = \"{k}\""),
                    format!("kind = {{ {k} = {{}} }}"),
                ]
            })
            .collect();
        for bad in [
            "kind = \"bogus\"",
            "kind = { bogus = {} }",
            "kind = \"Finger\"",
            "kind = 3",
            "kind = [\"finger\"]",
            "kind = { finger = 1 }",
            "kind = { finger = {}, obstacle = {} }",
            "kind = {}",
        ] {
            inputs.push(bad.into());
        }
        let mut refused = 0;
        for text in &inputs {
            let ours = toml::from_str::<Ours>(text);
            let theirs = toml::from_str::<Theirs>(text);
            match (ours, theirs) {
                (Ok(o), Ok(t)) => {
                    assert_eq!(
                        format!("{:?}", o.kind.get_ref()),
                        format!("{:?}", t.kind.get_ref())
                    );
                    assert_eq!(o.kind.span(), t.kind.span(), "{text}");
                }
                (Err(o), Err(t)) => {
                    assert_eq!(o.message(), t.message(), "{text}");
                    assert_eq!(o.span(), t.span(), "{text}");
                    refused += 1;
                }
                (o, t) => panic!("{text}: ours {o:?}, derived {t:?}"),
            }
        }
        assert_eq!(refused, 8);
    }
}
