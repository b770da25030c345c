//! Checks of a scene's semantic parts (Gösele & Stuerzlinger): the
//! `[semantic]` settings, that every area's label is declared in `[labels]`,
//! that offer polygons are convex and every area's orientation vector is
//! perpendicular to its polygon, and the contact fingers' `holds`. (The
//! polygons' planarity and simplicity and the order's cycles are checked in
//! `validate.rs`; the loaded scene's consistency when it compiles.)

use std::collections::BTreeSet;

use nalgebra::Vector3;

use super::SceneError;
use super::spec::{AreaSection, FingerSection, GraspSpec, SceneFile};
use super::validate::{Checker, list};

type Check = Result<(), SceneError>;

/// An orientation vector this far from its polygon's normal is refused, rad
/// (1°: a typo, not a rounding).
const NORMAL_TOLERANCE_RAD: f64 = 0.017_453_292_519_943_295;

impl Checker<'_> {
    /// Every semantic check, in file order.
    pub(super) fn semantic(&self, s: &SceneFile) -> Check {
        if let Some(sec) = &s.semantic {
            for (v, what) in [
                (&sec.snap_distance, "snap_distance"),
                (&sec.snap_speed, "snap_speed"),
                (&sec.snap_force, "snap_force"),
                (&sec.break_force, "break_force"),
            ] {
                if let Some(v) = v {
                    self.positive(v, what)?;
                }
            }
            if let Some(a) = &sec.snap_angle {
                let x = *a.get_ref();
                if !(x.is_finite() && x > 0.0 && x < std::f64::consts::FRAC_PI_2) {
                    return Err(self.err(
                        a.span(),
                        format!("snap_angle is {x}; expected radians in (0, π/2)"),
                    ));
                }
            }
        }
        let mut declared: BTreeSet<&str> = BTreeSet::new();
        for (k, vs) in &s.labels {
            declared.insert(k.get_ref());
            declared.extend(vs.get_ref().iter().map(|v| v.get_ref().as_str()));
        }
        for b in &s.bodies {
            for (area, offer) in b
                .offer
                .iter()
                .map(|a| (a, true))
                .chain(b.binding.iter().map(|a| (a, false)))
            {
                let label = area.label.get_ref();
                if !declared.contains(label.as_str()) {
                    let known: Vec<&str> = declared.iter().copied().collect();
                    return Err(self.err(
                        area.label.span(),
                        format!(
                            "unknown label `{label}`; [labels] declares: {} (a label without \
                             relations is declared as `\"{label}\" = []`)",
                            list(&known)
                        ),
                    ));
                }
                self.area_shape(area, offer)?;
            }
        }
        for f in &s.fingers {
            self.holds(s, f)?;
        }
        Ok(())
    }

    /// Orientation vector ⊥ polygon; offers convex.
    fn area_shape(&self, a: &AreaSection, offer: bool) -> Check {
        let pts: Vec<Vector3<f64>> = a
            .polygon
            .get_ref()
            .iter()
            .map(|p| Vector3::from(p.get()))
            .collect();
        let k = pts.len();
        // Newell's normal (planarity and area were checked before).
        let mut n = Vector3::zeros();
        for i in 0..k {
            let (p, q) = (pts[i], pts[(i + 1) % k]);
            n += Vector3::new(
                (p.y - q.y) * (p.z + q.z),
                (p.z - q.z) * (p.x + q.x),
                (p.x - q.x) * (p.y + q.y),
            );
        }
        let n = n.normalize();
        let v = Vector3::from(a.normal.get_ref().get()).normalize();
        let off = n.dot(&v).abs().clamp(0.0, 1.0).acos();
        if off > NORMAL_TOLERANCE_RAD {
            return Err(self.err(
                a.normal.span(),
                format!(
                    "area normal is {:.1}° off its polygon's normal; the orientation vector is \
                     perpendicular to the area",
                    off.to_degrees()
                ),
            ));
        }
        if offer {
            let scale = pts.iter().map(|p| p.norm()).fold(1e-9, f64::max);
            for i in 0..k {
                let (p, q, r) = (pts[i], pts[(i + 1) % k], pts[(i + 2) % k]);
                if (q - p).cross(&(r - q)).dot(&n) < -1e-9 * scale * scale {
                    return Err(self.err(
                        a.polygon.span(),
                        format!(
                            "offer polygon is not convex (it turns the other way at vertex {}); \
                             split it into convex offer areas",
                            (i + 1) % k
                        ),
                    ));
                }
            }
        }
        Ok(())
    }

    /// A contact finger's `holds`: known moving bodies, 0 ≤ from < until,
    /// in order, not overlapping.
    fn holds(&self, s: &SceneFile, f: &FingerSection) -> Check {
        let contact = f
            .grasp
            .as_ref()
            .is_some_and(|g| *g.get_ref() == GraspSpec::Contact);
        let name = f.name.get_ref();
        let mut last_until = f64::NEG_INFINITY;
        for (k, h) in f.holds.iter().enumerate() {
            let h_ref = h.get_ref();
            if !contact {
                return Err(self.err(
                    h.span(),
                    format!(
                        "finger `{name}`: `holds` belongs to contact fingers (grasp = \"contact\"); \
                         a point or rigid finger holds its `body` all the time"
                    ),
                ));
            }
            let body = h_ref.body.get_ref();
            let Some(b) = s.bodies.iter().find(|b| b.name.get_ref() == body) else {
                let names: Vec<&str> = s.bodies.iter().map(|b| b.name.get_ref().as_str()).collect();
                return Err(self.err(
                    h_ref.body.span(),
                    format!(
                        "finger `{name}`: hold {k} names unknown body `{body}` (bodies: {})",
                        list(&names)
                    ),
                ));
            };
            if b.fixed {
                return Err(self.err(
                    h_ref.body.span(),
                    format!(
                        "finger `{name}`: hold {k} names fixed body `{body}`, which cannot be moved"
                    ),
                ));
            }
            let (from, until) = (*h_ref.from.get_ref(), *h_ref.until.get_ref());
            if !(from.is_finite() && from >= 0.0) {
                return Err(self.err(
                    h_ref.from.span(),
                    format!(
                        "finger `{name}`: hold {k} starts at {from} s; expected a finite time ≥ 0"
                    ),
                ));
            }
            if !(until.is_finite() && until > from) {
                return Err(self.err(
                    h_ref.until.span(),
                    format!("finger `{name}`: hold {k} ends at {until} s; expected a finite time after its start ({from} s)"),
                ));
            }
            if from < last_until {
                return Err(self.err(
                    h_ref.from.span(),
                    format!(
                        "finger `{name}`: hold {k} starts at {from} s, before hold {} ends ({last_until} s); holds come in order, one at a time",
                        k - 1
                    ),
                ));
            }
            last_until = until;
        }
        Ok(())
    }
}
