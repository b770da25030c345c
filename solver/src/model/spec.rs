//! The builder's vocabulary. It mirrors `docs/scene-format.md` one-to-one so a scene
//! file compiles into builder calls: `[[body]]` → [`BodySpec`], `[[joint]]` →
//! [`JointSpec`], `[[finger]]` → [`FingerSpec`], `scene.gravity` →
//! [`ModelBuilder::gravity`](crate::ModelBuilder::gravity). Units are SI;
//! vectors are `[x, y, z]`; orientations are `[w, x, y, z]`.

use std::fmt;
use std::str::FromStr;

pub use crate::geometry::{DEFAULT_DENSITY_KG_M3, Shape};

/// Default mass when a body gives none, kilograms.
pub const DEFAULT_MASS_KG: f64 = 1.0;

/// Radius of the solid sphere whose inertia a body gets when it gives none,
/// metres: a 10 cm ball is the scale of objects held in a PHANToM workspace, so
/// rotational and translational inertia stay commensurate. The default inertia
/// is `(2/5) m r²` about each principal axis.
pub const DEFAULT_INERTIA_RADIUS_M: f64 = 0.05;

/// A `[[body]]` entry.
#[derive(Debug, Clone, PartialEq)]
pub struct BodySpec {
    /// Required, unique.
    pub name: String,
    /// Fixed bodies have no coordinates.
    pub fixed: bool,
    /// Initial (or, if fixed, permanent) position of the body origin, metres, world frame.
    pub position_m: [f64; 3],
    /// Initial orientation `[w, x, y, z]`, body → world; normalised on build.
    pub orientation_wxyz: [f64; 4],
    /// Mass, kilograms (default [`DEFAULT_MASS_KG`]).
    pub mass_kg: Option<f64>,
    /// Principal moments of inertia in the body frame, kg·m² (default: the
    /// shape's, scaled to the body's mass; without a shape, a solid sphere of
    /// radius [`DEFAULT_INERTIA_RADIUS_M`] and the body's mass).
    pub inertia_kg_m2: Option<[f64; 3]>,
    /// Collision shape (body frame); a body without one takes part in no
    /// contact.
    pub shape: Option<Shape>,
    /// kg/m³: mass and inertia from the shape when `mass_kg` is `None`
    /// (default [`DEFAULT_DENSITY_KG_M3`]).
    pub density_kg_m3: Option<f64>,
    /// Coulomb μ of this body's contacts with other bodies (a pair uses the
    /// geometric mean of its two bodies'; 0: frictionless, the default).
    /// Acts with inertial motion only (`SolverSettings::dynamics`).
    pub friction: f64,
    /// Design variables of a fixed body: [`DesignParam::Position`] makes its
    /// position three coordinates of q (metres, world frame) that objectives
    /// and fingers' pulls may move (Nelson & Cohen Fig. 15's "feet"); it
    /// still has no inertia and no orientation coordinates.
    pub free: Vec<DesignParam>,
    /// Optional bounds on the freed position (see [`Bounds`]).
    pub bounds: Option<Bounds>,
    /// A flexible body's beam (Nelson & Cohen §4; see
    /// [`crate::flexible`]): its points bend with 2 × `modes` deformation
    /// coordinates. `None`: rigid.
    pub flexible: Option<crate::flexible::BeamSpec>,
}

impl BodySpec {
    /// A moving body at the origin with identity orientation and default mass.
    pub fn new(name: impl Into<String>) -> Self {
        Self {
            name: name.into(),
            fixed: false,
            position_m: [0.0; 3],
            orientation_wxyz: [1.0, 0.0, 0.0, 0.0],
            mass_kg: None,
            inertia_kg_m2: None,
            shape: None,
            density_kg_m3: None,
            friction: 0.0,
            free: Vec::new(),
            bounds: None,
            flexible: None,
        }
    }

    /// A fixed body at the origin.
    pub fn fixed(name: impl Into<String>) -> Self {
        Self {
            fixed: true,
            ..Self::new(name)
        }
    }

    /// Sets the position, metres.
    pub fn at(mut self, position_m: [f64; 3]) -> Self {
        self.position_m = position_m;
        self
    }

    /// Sets the orientation `[w, x, y, z]`.
    pub fn oriented(mut self, orientation_wxyz: [f64; 4]) -> Self {
        self.orientation_wxyz = orientation_wxyz;
        self
    }

    /// Sets the mass, kilograms.
    pub fn mass(mut self, mass_kg: f64) -> Self {
        self.mass_kg = Some(mass_kg);
        self
    }

    /// Sets the principal moments of inertia, kg·m².
    pub fn inertia(mut self, inertia_kg_m2: [f64; 3]) -> Self {
        self.inertia_kg_m2 = Some(inertia_kg_m2);
        self
    }

    /// Sets the collision shape.
    pub fn shape(mut self, shape: Shape) -> Self {
        self.shape = Some(shape);
        self
    }

    /// Sets the density, kg/m³.
    pub fn density(mut self, density_kg_m3: f64) -> Self {
        self.density_kg_m3 = Some(density_kg_m3);
        self
    }

    /// Sets the Coulomb μ of the body's contacts.
    pub fn friction(mut self, mu: f64) -> Self {
        self.friction = mu;
        self
    }

    /// Frees a fixed body's position ([`DesignParam::Position`]).
    pub fn free_position(mut self) -> Self {
        self.free.push(DesignParam::Position);
        self
    }

    /// Sets bounds on the freed position.
    pub fn bounds(mut self, bounds: Bounds) -> Self {
        self.bounds = Some(bounds);
        self
    }

    /// Makes the body flexible: it bends as `beam`.
    pub fn flexible(mut self, beam: crate::flexible::BeamSpec) -> Self {
        self.flexible = Some(beam);
        self
    }
}

/// `bounds` of a `[[joint]]` or `[[body]]` entry: limits on the design
/// variables it frees, each component in its own unit and frame (metres; a
/// length, an anchor in its body's frame, a position in the world frame).
/// Every component gets two `≥ 0` rows, x − lo ≥ 0 and hi − x ≥ 0, or, when
/// lo = hi, one equality row x − lo = 0 (the component stays put: a foot
/// that slides on the ground plane keeps its height).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Bounds {
    /// `[lo, hi]`: the same range for every component of every variable the
    /// entry frees.
    Scalar([f64; 2]),
    /// `[[lo_x, lo_y, lo_z], [hi_x, hi_y, hi_z]]`: per component, for
    /// 3-wide variables (anchors, positions) only.
    Vector([[f64; 3]; 2]),
}

impl Bounds {
    /// `[lo, hi]` of component `k` (0, 1, 2).
    pub fn component(&self, k: usize) -> [f64; 2] {
        match *self {
            Self::Scalar(b) => b,
            Self::Vector([lo, hi]) => [lo[k], hi[k]],
        }
    }
}

macro_rules! named_enum {
    ($(#[$doc:meta])* $name:ident { $($(#[$vdoc:meta])* $var:ident = $s:literal),+ $(,)? }) => {
        $(#[$doc])*
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
        pub enum $name { $($(#[$vdoc])* $var),+ }

        impl $name {
            /// Every variant, in declaration order.
            pub const ALL: &'static [Self] = &[$(Self::$var),+];

            /// The scene-file spelling.
            pub fn as_str(self) -> &'static str {
                match self { $(Self::$var => $s),+ }
            }
        }

        impl fmt::Display for $name {
            fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str(self.as_str())
            }
        }

        impl FromStr for $name {
            type Err = UnknownName;
            fn from_str(s: &str) -> Result<Self, UnknownName> {
                Self::ALL.iter().copied().find(|v| v.as_str() == s).ok_or_else(|| UnknownName {
                    what: stringify!($name),
                    name: s.to_owned(),
                    expected: Self::ALL.iter().map(|v| v.as_str()).collect::<Vec<_>>().join(" | "),
                })
            }
        }
    };
}

/// A scene-file word that names no variant.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown {what} `{name}`; expected one of {expected}")]
pub struct UnknownName {
    /// The enum looked up.
    pub what: &'static str,
    /// The word given.
    pub name: String,
    /// The accepted words, `|`-separated.
    pub expected: String,
}

named_enum!(
    /// `joint.kind`.
    JointKind {
        /// Anchors coincide (3 rows).
        Spherical = "spherical",
        /// Spherical + axes stay parallel (5 rows); needs `axes`.
        Revolute = "revolute",
        /// Spherical + axes perpendicular (4 rows); needs `axes`.
        Universal = "universal",
        /// Anchor j slides along axis i, no relative rotation (5 rows); needs `axes`.
        Prismatic = "prismatic",
        /// Weld: anchors coincide and the initial relative orientation is kept (6 rows).
        Fixed = "fixed",
        /// Anchors stay `length` apart (1 row).
        Distance = "distance",
        /// Axes stay perpendicular (1 row); needs `axes`, ignores `anchors`.
        Perpendicular = "perpendicular",
        /// Anchor i stays on the plane through anchor j with normal `axes[1]` of
        /// body j (1 row); `axes[0]` is ignored.
        PointOnPlane = "point_on_plane",
        /// Anchor i (a ball's centre if `radius` is given) stays on body j's
        /// `surface` (3 rows, 2 coordinates (u, v)); frictionless.
        OnSurface = "on_surface",
        /// Body i, a ball of `radius` centred at anchor i, rolls without
        /// slipping on fixed body j's `surface` (3 + 2 rows, (u, v)).
        Rolling = "rolling",
    }
);

named_enum!(
    /// An entry of `joint.free`: a joint parameter that becomes a coordinate.
    DesignParam {
        /// The length of a distance joint (1 coordinate, metres).
        Length = "length",
        /// Anchor k_i in body i's frame (3 coordinates, metres).
        AnchorI = "anchor_i",
        /// Anchor k_j in body j's frame (3 coordinates, metres).
        AnchorJ = "anchor_j",
        /// A fixed body's position (3 coordinates, metres, world frame);
        /// `[[body]]` entries only.
        Position = "position",
    }
);

named_enum!(
    /// `finger.grasp`.
    Grasp {
        /// The finger holds a point (3 rows).
        Point = "point",
        /// The finger holds the body rigidly: point and orientation (6 rows).
        Rigid = "rigid",
        /// A fingertip ball that pushes on shapes and never pulls: a body of
        /// its own, driven by the device through a point grasp (3 rows) at
        /// its centre.
        Contact = "contact",
    }
);

/// A `[[joint]]` entry.
///
/// A joint between a moving body and a fixed body constrains only the moving
/// one: its rows have columns for the moving body (and any free design
/// variables) only, and the fixed body's pose is a constant. A joint between two
/// fixed bodies is an error.
#[derive(Debug, Clone, PartialEq)]
pub struct JointSpec {
    /// Optional, unique if given; unnamed joints are called `#k` (1-based) in errors.
    pub name: Option<String>,
    /// Joint kind.
    pub kind: JointKind,
    /// Body names `[i, j]`.
    pub bodies: [String; 2],
    /// Body-frame anchor points `[k_i, k_j]`, metres (default: both origins).
    pub anchors_m: [[f64; 3]; 2],
    /// Body-frame axes `[h_i, h_j]` where the kind needs them (normalised on build).
    pub axes: Option<[[f64; 3]; 2]>,
    /// Distance joints: length, metres (default: the anchors' initial distance).
    pub length_m: Option<f64>,
    /// Optional `[lo, hi]` on the joint coordinate, two `≥ 0` rows:
    /// - revolute: the angle of body j relative to body i about A_i h_i,
    ///   radians, right-handed, **zero at the bodies' initial poses**, in
    ///   (−π, π] (so limits must lie inside (−π, π));
    /// - prismatic: the displacement (A_i h_i)·(p_j − p_i) of anchor j from
    ///   anchor i along axis i, metres;
    /// - distance: the measured anchor distance |p_i − p_j|, metres (not the
    ///   design variable L).
    ///
    /// Other kinds have no joint coordinate; limits on them are an error.
    pub limits: Option<[f64; 2]>,
    /// Parameters that become design variables.
    pub free: Vec<DesignParam>,
    /// Optional bounds on the design variables `free` lists (see [`Bounds`]).
    pub bounds: Option<Bounds>,
    /// `on_surface` and `rolling`: body j's surface.
    pub surface: Option<ContactSurface>,
    /// `on_surface` (optional) and `rolling` (required): the ball's radius,
    /// metres (anchor i is its centre).
    pub radius_m: Option<f64>,
}

/// A parametric surface fixed to a body (`surface` of an `on_surface` or
/// `rolling` joint; see [`crate::parametric`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactSurface {
    /// Its shape (radius, concave or convex).
    pub kind: crate::parametric::SurfaceKind,
    /// Origin of its local frame, metres, body frame.
    pub origin_m: [f64; 3],
    /// Its local frame, `[w, x, y, z]`, local → body (normalised on build).
    pub orientation_wxyz: [f64; 4],
}

impl ContactSurface {
    /// A surface of `kind` with its local frame at the body's.
    pub fn new(kind: crate::parametric::SurfaceKind) -> Self {
        Self {
            kind,
            origin_m: [0.0; 3],
            orientation_wxyz: [1.0, 0.0, 0.0, 0.0],
        }
    }
}

impl JointSpec {
    /// A joint of `kind` between bodies `i` and `j`, anchored at both origins.
    pub fn new(kind: JointKind, i: impl Into<String>, j: impl Into<String>) -> Self {
        Self {
            name: None,
            kind,
            bodies: [i.into(), j.into()],
            anchors_m: [[0.0; 3]; 2],
            axes: None,
            length_m: None,
            limits: None,
            free: Vec::new(),
            bounds: None,
            surface: None,
            radius_m: None,
        }
    }

    /// Sets the surface of an `on_surface` or `rolling` joint.
    pub fn surface(mut self, surface: ContactSurface) -> Self {
        self.surface = Some(surface);
        self
    }

    /// Sets the ball radius of an `on_surface` or `rolling` joint, metres.
    pub fn radius(mut self, radius_m: f64) -> Self {
        self.radius_m = Some(radius_m);
        self
    }

    /// Sets the name.
    pub fn named(mut self, name: impl Into<String>) -> Self {
        self.name = Some(name.into());
        self
    }

    /// Sets the body-frame anchors `[k_i, k_j]`, metres.
    pub fn anchors(mut self, k_i: [f64; 3], k_j: [f64; 3]) -> Self {
        self.anchors_m = [k_i, k_j];
        self
    }

    /// Sets the body-frame axes `[h_i, h_j]`.
    pub fn axes(mut self, h_i: [f64; 3], h_j: [f64; 3]) -> Self {
        self.axes = Some([h_i, h_j]);
        self
    }

    /// Sets the length, metres.
    pub fn length(mut self, length_m: f64) -> Self {
        self.length_m = Some(length_m);
        self
    }

    /// Sets `[lo, hi]` limits on the joint coordinate.
    pub fn limits(mut self, lo: f64, hi: f64) -> Self {
        self.limits = Some([lo, hi]);
        self
    }

    /// Marks parameters free.
    pub fn free(mut self, params: &[DesignParam]) -> Self {
        self.free.extend_from_slice(params);
        self
    }

    /// Sets bounds on the free parameters.
    pub fn bounds(mut self, bounds: Bounds) -> Self {
        self.bounds = Some(bounds);
        self
    }
}

/// Default fingertip radius of a contact finger, metres: 8 mm, a human
/// fingertip's pad.
pub const DEFAULT_FINGERTIP_RADIUS_M: f64 = 0.008;

/// The largest Coulomb μ a body or fingertip may have: 10 already sticks
/// anything a hand can push (rubber on rubber is about 1–2); larger values
/// only stiffen the friction rows' cone test toward round-off.
pub const MAX_FRICTION: f64 = 10.0;

/// The largest fingertip radius, metres: a fingertip is a finger's pad, and
/// a larger ball is a body of its own (give it a `shape`).
pub const MAX_FINGERTIP_RADIUS_M: f64 = 1.0;

/// Mass of a contact finger's fingertip ball, kilograms: 10 g, light next to
/// the objects it pushes (so their inertia, not its own, is what Eq. 7 feeds
/// back) yet a well-conditioned body. It feels no gravity (the user's hand
/// carries it).
pub const FINGERTIP_MASS_KG: f64 = 0.01;

/// A contact finger's fingertip (see [`Grasp::Contact`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Fingertip {
    /// Where the fingertip starts, metres, world frame (the device is
    /// registered there).
    pub position_m: [f64; 3],
    /// Ball radius, metres.
    pub radius_m: f64,
    /// Coulomb friction coefficient of its contacts (0: frictionless).
    pub friction: f64,
}

/// A `[[finger]]` entry (the device binding lives outside the solver).
#[derive(Debug, Clone, PartialEq)]
pub struct FingerSpec {
    /// Required, unique.
    pub name: String,
    /// The moving body held (a contact finger: its fingertip body,
    /// `"<name>.tip"`, created by the builder).
    pub body: String,
    /// Body-frame attachment point, metres.
    pub point_m: [f64; 3],
    /// Point, rigid or contact grasp.
    pub grasp: Grasp,
    /// The fingertip of a contact finger.
    pub tip: Option<Fingertip>,
}

impl FingerSpec {
    /// A point grasp of `body` at `point_m`.
    pub fn point(name: impl Into<String>, body: impl Into<String>, point_m: [f64; 3]) -> Self {
        Self {
            name: name.into(),
            body: body.into(),
            point_m,
            grasp: Grasp::Point,
            tip: None,
        }
    }

    /// A contact finger: a fingertip ball of `radius_m` starting at
    /// `position_m` (world), with Coulomb `friction` at its contacts.
    pub fn contact(
        name: impl Into<String>,
        position_m: [f64; 3],
        radius_m: f64,
        friction: f64,
    ) -> Self {
        let name = name.into();
        Self {
            body: format!("{name}.tip"),
            name,
            point_m: [0.0; 3],
            grasp: Grasp::Contact,
            tip: Some(Fingertip {
                position_m,
                radius_m,
                friction,
            }),
        }
    }

    /// A rigid grasp of `body` at `point_m`.
    pub fn rigid(name: impl Into<String>, body: impl Into<String>, point_m: [f64; 3]) -> Self {
        Self {
            grasp: Grasp::Rigid,
            ..Self::point(name, body, point_m)
        }
    }
}
