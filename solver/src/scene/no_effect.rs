//! Values that would load and then do nothing, or something other than
//! what they say: refused at their place instead of silently ignored.
//!
//! - `density` beside `mass`: the mass wins (the density then only shapes
//!   an inertia that is scaled to the mass anyway), so the density is dead;
//! - `directions = []` on a dexterity objective: no direction is no task,
//!   yet it meant "x, y, z" (the default when the key is left out);
//! - an area whose orientation vector points into its own body: it can
//!   never meet a fitting area (aligned areas face each other), so it never
//!   snaps.
//!
//! (A dexterity chain written tip first is refused by the objective's
//! compiler, an obstacle's activation distance works at any size, a box
//! beyond ±10 km is a magnitude: `magnitudes.rs`; `--free` given twice is
//! refused in `flags.rs`.)

use nalgebra::Vector3;

use super::SceneError;
use super::spec::{AreaSection, BodySection, ObjectiveSection, SceneFile};
use super::validate::Checker;
use crate::geometry::convert::to_glam;

type Check = Result<(), SceneError>;

impl Checker<'_> {
    /// Every check of this file, in file order.
    pub(super) fn no_effect(&self, s: &SceneFile) -> Check {
        for b in &s.bodies {
            if let (Some(d), Some(_)) = (&b.density, &b.mass) {
                return Err(self.err(
                    d.span(),
                    format!(
                        "body `{}` gives both `mass` and `density`: the mass wins and the \
                         density would do nothing; keep one",
                        b.name.get_ref()
                    ),
                ));
            }
            for (area, kind) in b
                .offer
                .iter()
                .map(|a| (a, "offer"))
                .chain(b.binding.iter().map(|a| (a, "binding")))
            {
                self.area_side(b, area, kind)?;
            }
        }
        for o in &s.objectives {
            self.no_directions(o)?;
        }
        Ok(())
    }

    fn no_directions(&self, o: &ObjectiveSection) -> Check {
        match &o.directions {
            Some(d) if d.get_ref().is_empty() => Err(self.err(
                d.span(),
                "`directions = []` lists no direction; give one to three, or leave the key out \
                 for x, y and z",
            )),
            _ => Ok(()),
        }
    }

    /// The area's orientation vector points away from its body's shape: a
    /// step along it from the polygon's centroid ends farther from the
    /// shape than a step against it (bodies without a shape: unchecked).
    fn area_side(&self, b: &BodySection, a: &AreaSection, kind: &str) -> Check {
        let Some(shape) = &b.shape else {
            return Ok(());
        };
        let Ok((full, radius_m)) = super::compile::shape(shape.get_ref()).parry_shape() else {
            return Ok(()); // the shape's own error is reported where it is
        };
        let pts: Vec<Vector3<f64>> = a
            .polygon
            .get_ref()
            .iter()
            .map(|p| Vector3::from(p.get()))
            .collect();
        let n = Vector3::from(a.normal.get_ref().get());
        let (Some(n), false) = (n.try_normalize(1e-300), pts.is_empty()) else {
            return Ok(());
        };
        let c = pts.iter().sum::<Vector3<f64>>() / pts.len() as f64;
        let step = 1e-3 * radius_m.max(1e-9);
        let dist = |p: Vector3<f64>| full.distance_to_local_point(to_glam(&p), true);
        let (ahead, behind) = (dist(c + n * step), dist(c - n * step));
        if ahead < behind {
            return Err(self.err(
                a.normal.span(),
                format!(
                    "this {kind} area's orientation vector points into body `{}`; it points away \
                     from its body (a table top's up, a cup bottom's down), or the area never \
                     meets a fitting one",
                    b.name.get_ref()
                ),
            ));
        }
        Ok(())
    }
}
