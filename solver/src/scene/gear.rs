//! `[[gear]]` tables: couplings between two joints (Nelson & Cohen Fig. 12's
//! gears; `constraint::gear`, `constraint::rack_pinion`). Parsed here,
//! checked by the model builder ([`crate::GearSpec`]), errors mapped back to
//! the offending value.

use serde::Deserialize;
use std::ops::Range;
use toml::Spanned;

use super::spec::Arr;
use crate::model::{BuildError, GearKind, GearSpec};

/// `[[gear]]`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GearSection {
    /// Required, unique among joints and gears.
    pub name: Spanned<String>,
    /// Gear pair or rack and pinion.
    pub kind: Spanned<GearKindSpec>,
    /// `[driver, driven]` or `[pinion, rack]`.
    pub joints: Spanned<Arr<Spanned<String>, 2>>,
    /// Joint j's coordinate per unit of joint i's.
    pub ratio: Spanned<f64>,
}

/// `kind = "…"` of a gear.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum GearKindSpec {
    /// Two revolutes.
    Gear,
    /// A revolute and a prismatic.
    RackPinion,
}

/// The builder's spec of a `[[gear]]`.
pub(super) fn gear_spec(g: &GearSection) -> GearSpec {
    let [a, b] = &g.joints.get_ref().0;
    GearSpec {
        name: g.name.get_ref().clone(),
        kind: match g.kind.get_ref() {
            GearKindSpec::Gear => GearKind::Gear,
            GearKindSpec::RackPinion => GearKind::RackPinion,
        },
        joints: [a.get_ref().clone(), b.get_ref().clone()],
        ratio: *g.ratio.get_ref(),
    }
}

/// The span of the value of gear `g` that error `e` is about.
pub(super) fn gear_field(g: &GearSection, e: &BuildError) -> Range<usize> {
    let joint = |name: &str| {
        g.joints
            .get_ref()
            .0
            .iter()
            .rev()
            .find(|j| j.get_ref() == name)
            .map_or(g.joints.span(), Spanned::span)
    };
    match e {
        BuildError::UnknownJoint { joint: j, .. }
        | BuildError::GearJoint { joint: j, .. }
        | BuildError::GearRackDesign { joint: j, .. } => joint(j),
        BuildError::GearBodies { .. } => g.joints.span(),
        BuildError::GearRatio { .. } => g.ratio.span(),
        _ => g.name.span(),
    }
}
