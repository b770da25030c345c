//! The initial configuration checked against the joints' own limits.

use crate::scene::LoadedScene;
use crate::scene::SceneError;
use crate::{Model, RowUnit, Sense};
use toml::Spanned;

impl LoadedScene {
    /// An initial configuration outside a joint's own limits is an error at
    /// that joint's `limits` (the fast loop would start with a violated
    /// inequality and ask for an enormous force to fix it in one tick).
    pub(super) fn check_limits_at_q0(&self, model: &Model) -> Result<(), SceneError> {
        /// Slack for a configuration written with finite digits: 1 µm or µrad.
        const SLACK: f64 = 1e-6;
        let mut ev = model.evaluation();
        if ev
            .evaluate(model, model.q0(), &model.initial_targets())
            .is_err()
        {
            return Ok(()); // non-finite q0: the builder's checks report it
        }
        for (r, row) in model.rows().iter().enumerate() {
            let v = ev.values()[r];
            if row.sense != Sense::Inequality || v >= -SLACK {
                continue;
            }
            let c = &model.constraints()[row.constraint.index()];
            let Some(joint) = c.name.strip_suffix(".limits") else {
                continue;
            };
            let j = match joint
                .strip_prefix('#')
                .and_then(|k| k.parse::<usize>().ok())
            {
                Some(k) => self.spec.joints.get(k.saturating_sub(1)),
                None => self
                    .spec
                    .joints
                    .iter()
                    .find(|j| j.name.as_ref().is_some_and(|n| n.get_ref() == joint)),
            };
            let span = j
                .and_then(|j| j.limits.as_ref().map(Spanned::span))
                .unwrap_or(0..0);
            let unit = match row.unit {
                RowUnit::Angle => "rad",
                _ => "m",
            };
            return Err(self.error_at(
                span,
                format!(
                    "joint `{joint}`: the initial configuration (bodies' positions and orientations as written) is outside these limits by {:.3e} {unit}; move the bodies inside the limits or widen them",
                    -v
                ),
            ));
        }
        Ok(())
    }
}
