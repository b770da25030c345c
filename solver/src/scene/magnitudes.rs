//! Magnitudes a tick can compute with: numbers that are finite in the file
//! but cannot give a finite tick (gravity of −1e300 m/s² asks for a force
//! of 1e300 N, whose length overflows; an objective weight of 1e250 makes
//! the finger's weight infinite) are refused at load, at the field, rather
//! than failing every tick of a run. Each bound is far beyond anything a
//! desk-sized haptic scene uses, and `docs/scene-format.md` states it.

use super::SceneError;
use super::spec::{ObjectiveSection, SceneFile, ShapeSpec};
use super::validate::Checker;
use crate::ObjectiveKind;
use toml::Spanned;

/// The largest gravity, m/s² (about 100 g).
pub const MAX_GRAVITY_M_S2: f64 = 1e3;
/// The largest objective `weight` or `design_weight`.
pub const MAX_WEIGHT: f64 = 1e6;
/// The smallest `least_astonishment` weight (every other weight is divided
/// by it).
pub const MIN_LEAST_ASTONISHMENT_WEIGHT: f64 = 1e-6;
/// The largest size of a shape (half extent, radius, half height, or a
/// convex point's coordinate) and of an obstacle's activation distance, m:
/// the ±10 km of positions.
pub const MAX_SIZE_M: f64 = 1e4;

type Check = Result<(), SceneError>;

impl Checker<'_> {
    /// Every magnitude bound, in file order.
    pub(super) fn magnitudes(&self, s: &SceneFile) -> Check {
        if let Some(g) = &s.scene.gravity {
            // Scaled, so that 1e300 m/s² is not an overflow to infinity.
            let big = g.get_ref().iter().fold(0.0, |a: f64, x| a.max(x.abs()));
            let n = if big > 0.0 {
                big * g
                    .get_ref()
                    .iter()
                    .map(|x| (x / big).powi(2))
                    .sum::<f64>()
                    .sqrt()
            } else {
                0.0
            };
            if n > MAX_GRAVITY_M_S2 {
                return Err(self.err(
                    g.span(),
                    format!(
                        "gravity is {n:.3e} m/s²; at most {MAX_GRAVITY_M_S2} m/s² (about 100 g; \
                         Earth's is 9.81)"
                    ),
                ));
            }
        }
        for b in &s.bodies {
            if let Some(shape) = &b.shape {
                self.shape_size(shape)?;
            }
        }
        for o in &s.objectives {
            self.objective_magnitudes(o)?;
        }
        Ok(())
    }

    fn shape_size(&self, shape: &Spanned<ShapeSpec>) -> Check {
        let largest = match shape.get_ref() {
            ShapeSpec::Box(h) => h.iter().copied().fold(0.0, f64::max),
            ShapeSpec::Sphere(r) => *r,
            ShapeSpec::Capsule {
                half_height,
                radius,
            } => half_height.max(*radius),
            ShapeSpec::Convex(pts) => pts.iter().flatten().map(|x| x.abs()).fold(0.0, f64::max),
        };
        if largest > MAX_SIZE_M {
            return Err(self.err(
                shape.span(),
                format!(
                    "shape has a size of {largest:.3e} m; scenes are limited to ±10 km \
                     ({MAX_SIZE_M} m)"
                ),
            ));
        }
        Ok(())
    }

    fn objective_magnitudes(&self, o: &ObjectiveSection) -> Check {
        let la = *o.kind.get_ref() == ObjectiveKind::LeastAstonishment;
        for (v, what) in [(&o.weight, "weight"), (&o.design_weight, "design_weight")] {
            let Some(v) = v else { continue };
            let x = *v.get_ref();
            if x > MAX_WEIGHT {
                return Err(self.err(
                    v.span(),
                    format!(
                        "{what} is {x:e}; at most {MAX_WEIGHT:e} (1 already halves a distance per \
                         tick)"
                    ),
                ));
            }
            if (la || what == "design_weight") && x < MIN_LEAST_ASTONISHMENT_WEIGHT {
                return Err(self.err(
                    v.span(),
                    format!(
                        "{what} is {x:e}; at least {MIN_LEAST_ASTONISHMENT_WEIGHT:e} (every other \
                         weight is divided by it)"
                    ),
                ));
            }
        }
        if let Some(d) = &o.distance
            && *d.get_ref() > MAX_SIZE_M
        {
            return Err(self.err(
                d.span(),
                format!(
                    "distance is {:e} m; scenes are limited to ±10 km ({MAX_SIZE_M} m)",
                    d.get_ref()
                ),
            ));
        }
        Ok(())
    }
}
