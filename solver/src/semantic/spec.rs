//! What a scene declares for the semantic layer: areas, the label order and
//! the settings (`[semantic]`), in the solver's vocabulary (body ids, arrays).

use crate::BodyId;
use crate::model::SnapSettings;

/// Offer or binding.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum AreaKind {
    /// Where other objects can connect (a table top, a wall).
    Offer,
    /// Where this object connects to others (a cup's bottom).
    Binding,
}

/// One `[[body.offer]]` or `[[body.binding]]`.
#[derive(Debug, Clone, PartialEq)]
pub struct AreaSpec {
    /// The body it belongs to.
    pub body: BodyId,
    /// Offer or binding.
    pub kind: AreaKind,
    /// Its label.
    pub label: String,
    /// A simple planar polygon (convex for offers), body frame, m.
    pub polygon_m: Vec<[f64; 3]>,
    /// The orientation vector, body frame (normalised by the scene).
    pub normal: [f64; 3],
}

/// The `[semantic]` settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SemanticSettings {
    /// A binding is close to an offer when its plane is at most this far
    /// from the offer's (the maximal distance of §5.1), m.
    pub snap_distance_m: f64,
    /// … and its orientation vector at most this far from anti-parallel to
    /// the offer's, rad.
    pub snap_angle_rad: f64,
    /// Pulling a held object off its offer harder than this breaks the
    /// constraint, N.
    pub break_force_n: f64,
    /// The fast loop's ramp of a snap (speed, force limit).
    pub snap: SnapSettings,
    /// Two shapes collide when they overlap deeper than this, m (contact
    /// keeps touching bodies within its own tolerance).
    pub collision_tolerance_m: f64,
    /// A satisfied constraint is aligned within this (m for distances from
    /// the plane and outside the polygon; rad for the orientation).
    pub align_tolerance: f64,
}

impl Default for SemanticSettings {
    fn default() -> Self {
        Self {
            snap_distance_m: 0.01,
            snap_angle_rad: 0.35,
            break_force_n: 3.0,
            snap: SnapSettings::default(),
            collision_tolerance_m: 1e-4,
            align_tolerance: 1e-4,
        }
    }
}

/// Everything the semantic layer of a scene needs besides its bodies.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SemanticSpec {
    /// Every area, in file order.
    pub areas: Vec<AreaSpec>,
    /// The label order: each `(x, y)` says x ≤ y.
    pub order: Vec<(String, String)>,
    /// Labels declared without relations (`"on-wall" = []`).
    pub labels: Vec<String>,
    /// Settings.
    pub settings: SemanticSettings,
}

impl SemanticSpec {
    /// True for a scene without areas.
    pub fn is_empty(&self) -> bool {
        self.areas.is_empty()
    }
}
