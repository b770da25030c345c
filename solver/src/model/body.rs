//! A body spec compiled into a [`Body`]: its hull, mass and inertia (given
//! or from the shape), and every check of its values (finite, in range).

use nalgebra::{Quaternion, UnitQuaternion, Vector3};

use super::Body;
use super::compiler::check_bounds;
use super::error::{BuildError, Owner};
use super::spec::{
    BodySpec, DEFAULT_DENSITY_KG_M3, DEFAULT_INERTIA_RADIUS_M, DEFAULT_MASS_KG, DesignParam,
    FINGERTIP_MASS_KG, FingerSpec, Fingertip, MAX_FINGERTIP_RADIUS_M, MAX_FRICTION, Shape,
};
use crate::geometry::HullSimplification;
use crate::geometry::simplify::{MAX_HULL_VERTICES, simplify_hull};

/// The fingertip body of a contact finger: a ball of the finger's radius and
/// [`FINGERTIP_MASS_KG`] at its start position.
pub(super) fn tip_body(f: &FingerSpec, t: &Fingertip) -> Result<BodySpec, BuildError> {
    let owner = || Owner::Finger(f.name.clone());
    if !(t.radius_m.is_finite() && t.radius_m > 0.0 && t.radius_m <= MAX_FINGERTIP_RADIUS_M) {
        return Err(BuildError::BadFingertip {
            owner: owner(),
            field: "radius",
            value: t.radius_m,
            why: "finite, > 0 and at most 1 m (a larger ball is a body with a `shape`)",
        });
    }
    if !(t.friction.is_finite() && (0.0..=MAX_FRICTION).contains(&t.friction)) {
        return Err(BuildError::BadFingertip {
            owner: owner(),
            field: "friction",
            value: t.friction,
            why: "finite and in [0, 10]",
        });
    }
    if !t.position_m.iter().all(|x| x.is_finite()) {
        return Err(BuildError::NonFinite {
            owner: owner(),
            field: "position",
        });
    }
    super::compiler::in_range(&owner(), "position", &t.position_m)?;
    let i = 0.4 * FINGERTIP_MASS_KG * t.radius_m * t.radius_m;
    Ok(BodySpec::new(f.body.clone())
        .at(t.position_m)
        .mass(FINGERTIP_MASS_KG)
        .inertia([i; 3])
        .shape(Shape::Sphere {
            radius_m: t.radius_m,
        }))
}

/// Mass and inertia of a body: as given; else from its shape at its density
/// (inertia scaled to a given mass); else the defaults.
fn mass_and_inertia(
    s: &BodySpec,
    shape: Option<&Shape>,
    com_slack_m: f64,
    owner: &dyn Fn() -> Owner,
) -> Result<(f64, [f64; 3]), BuildError> {
    let from_shape = match shape {
        Some(shape) => {
            let density = s.density_kg_m3.unwrap_or(DEFAULT_DENSITY_KG_M3);
            if !(density.is_finite() && density > 0.0) {
                return Err(BuildError::Shape {
                    owner: owner(),
                    field: "density",
                    error: crate::geometry::ShapeError::Size {
                        field: "density",
                        value: density,
                    },
                });
            }
            if s.mass_kg.is_some() && s.inertia_kg_m2.is_some() {
                // Checked for sizes only: mass and inertia are given.
                shape.collider().map_err(|error| BuildError::Shape {
                    owner: owner(),
                    field: "shape",
                    error,
                })?;
                None
            } else {
                // Of the kept hull (its centre of mass may lie up to the
                // distance it was cut by from the given shape's).
                Some(
                    shape
                        .mass_properties_within(density, com_slack_m)
                        .map_err(|error| BuildError::Shape {
                            owner: owner(),
                            field: "shape",
                            error,
                        })?,
                )
            }
        }
        None => None,
    };
    let mass_kg = s
        .mass_kg
        .or(from_shape.map(|m| m.mass_kg))
        .unwrap_or(DEFAULT_MASS_KG);
    let inertia = match (s.inertia_kg_m2, from_shape) {
        (Some(i), _) => i,
        (None, Some(m)) => m.inertia_kg_m2.map(|x| x * mass_kg / m.mass_kg),
        (None, None) => [0.4 * mass_kg * DEFAULT_INERTIA_RADIUS_M * DEFAULT_INERTIA_RADIUS_M; 3],
    };
    Ok((mass_kg, inertia))
}

/// The body of spec `s` (the `i`-th), every key checked.
pub(super) fn body(i: usize, s: &BodySpec) -> Result<Body, BuildError> {
    if s.name.is_empty() {
        return Err(BuildError::EmptyName {
            owner: Owner::Body(format!("#{}", i + 1)),
        });
    }
    let owner = || Owner::Body(s.name.clone());
    let finite = |field, v: &[f64]| finite(&owner, field, v);
    finite("position", &s.position_m)?;
    super::compiler::in_range(&owner(), "position", &s.position_m)?;
    finite("orientation", &s.orientation_wxyz)?;
    if let Some(m) = s.mass_kg {
        finite("mass", &[m])?;
    }
    let (shape, hull) = kept_hull(s, &owner)?;
    let slack = hull.map_or(0.0, |h| h.error_m);
    let (mass_kg, inertia) = mass_and_inertia(s, shape.as_ref(), slack, &owner)?;
    check_mass(s, mass_kg, inertia, &owner)?;
    if !(s.friction.is_finite() && (0.0..=MAX_FRICTION).contains(&s.friction)) {
        return Err(BuildError::BadFriction {
            owner: owner(),
            value: s.friction,
        });
    }
    motion(s, &owner)?;
    check_free(s, &owner)?;
    check_flexible(s, &owner)?;
    let freed: Vec<(DesignParam, &[f64])> =
        s.free.iter().map(|&p| (p, &s.position_m[..])).collect();
    check_bounds(&owner(), &s.name, s.bounds.as_ref(), &freed)?;
    let [w, x, y, z] = s.orientation_wxyz;
    let q = Quaternion::new(w, x, y, z);
    let n2 = q.norm_squared();
    if n2 <= 0.0 || !n2.is_finite() {
        return Err(BuildError::ZeroOrientation { owner: owner() });
    }
    Ok(Body {
        name: s.name.clone(),
        fixed: s.fixed,
        position_m: Vector3::from(s.position_m),
        orientation: UnitQuaternion::from_quaternion(q),
        mass_kg,
        inertia_kg_m2: Vector3::from(inertia),
        shape,
        fingertip: false,
        friction: s.friction,
        hull,
        restitution: s.restitution,
        damping_per_s: s.damping_per_s,
        velocity_m_s: Vector3::from(s.velocity_m_s),
        angular_velocity_rad_s: Vector3::from(s.angular_velocity_rad_s),
    })
}

/// Fails with `NonFinite` naming `field` unless every value of `v` is
/// finite.
pub(crate) fn finite(
    owner: &dyn Fn() -> Owner,
    field: &'static str,
    v: &[f64],
) -> Result<(), BuildError> {
    if v.iter().all(|x| x.is_finite()) {
        Ok(())
    } else {
        Err(BuildError::NonFinite {
            owner: owner(),
            field,
        })
    }
}

/// The body's shape with a hull past the vertex budget cut, and what the
/// cut cost (when it cost anything). The cut comes before anything uses
/// the hull (mass properties included): every later collider is built
/// from the kept vertices.
fn kept_hull(
    s: &BodySpec,
    owner: &dyn Fn() -> Owner,
) -> Result<(Option<Shape>, Option<HullSimplification>), BuildError> {
    Ok(match &s.shape {
        Some(Shape::Convex { points_m }) => {
            match simplify_hull(points_m, MAX_HULL_VERTICES).map_err(|e| BuildError::Shape {
                owner: owner(),
                field: "shape",
                error: e.into(),
            })? {
                Some(cut) => (
                    Some(Shape::Convex {
                        points_m: cut.points_m.clone(),
                    }),
                    (cut.error_m > 0.0).then(|| cut.summary()),
                ),
                None => (s.shape.clone(), None),
            }
        }
        other => (other.clone(), None),
    })
}

/// A positive finite mass, and principal moments that are finite, at
/// least 0, above 0 on a moving body (a zero one leaves a rotation without
/// inertia and M singular: the force solve's factorisation then fails),
/// and satisfy the triangle inequalities.
fn check_mass(
    s: &BodySpec,
    mass_kg: f64,
    inertia: [f64; 3],
    owner: &dyn Fn() -> Owner,
) -> Result<(), BuildError> {
    finite(owner, "mass", &[mass_kg])?;
    if mass_kg <= 0.0 {
        return Err(BuildError::NonPositiveMass {
            owner: owner(),
            mass_kg,
        });
    }
    finite(owner, "inertia", &inertia)?;
    let [a, b, c] = inertia;
    let slack = 1e-9 * (a + b + c);
    if inertia.iter().any(|&x| x < 0.0)
        || (!s.fixed && inertia.iter().any(|&x| x <= 0.0))
        || a > b + c + slack
        || b > a + c + slack
        || c > a + b + slack
    {
        return Err(BuildError::BadInertia {
            owner: owner(),
            inertia_kg_m2: inertia,
        });
    }
    Ok(())
}

/// A body's design parameters: its position only, on a fixed body, each
/// once.
fn check_free(s: &BodySpec, owner: &dyn Fn() -> Owner) -> Result<(), BuildError> {
    for (k, &param) in s.free.iter().enumerate() {
        if param != DesignParam::Position || !s.fixed {
            return Err(BuildError::UnsupportedBodyFree {
                owner: owner(),
                param,
            });
        }
        if s.free[..k].contains(&param) {
            return Err(BuildError::DuplicateFree {
                owner: owner(),
                param,
            });
        }
    }
    Ok(())
}

/// A flexible body moves, has no shape, and its beam's keys are valid.
fn check_flexible(s: &BodySpec, owner: &dyn Fn() -> Owner) -> Result<(), BuildError> {
    if let Some(beam) = &s.flexible {
        let why = if s.fixed {
            Some("a flexible body must move (weld it to a fixed body at its clamp)".into())
        } else if s.shape.is_some() {
            Some("a flexible body takes part in no contact: its shape would not bend".into())
        } else {
            beam.check()
                .err()
                .map(|(field, why)| format!("flexible `{field}` {why}"))
        };
        if let Some(why) = why {
            return Err(BuildError::Flexible {
                owner: owner(),
                why,
            });
        }
    }
    Ok(())
}

/// Largest initial speed a body may be given, m/s (a bullet is 1 km/s).
pub const MAX_SPEED_M_S: f64 = 1e3;

/// Largest initial angular speed a body may be given, rad/s.
pub const MAX_SPIN_RAD_S: f64 = 1e4;

/// Largest velocity damping, 1/s (a body then stops within a microsecond).
pub const MAX_DAMPING_PER_S: f64 = 1e6;

/// The inertial-motion keys of a body: restitution, damping, initial
/// velocities.
fn motion(s: &BodySpec, owner: &dyn Fn() -> Owner) -> Result<(), BuildError> {
    let bad = |field, value, why| {
        Err(BuildError::BadMotion {
            owner: owner(),
            field,
            value,
            why,
        })
    };
    if !(s.restitution.is_finite() && (0.0..=1.0).contains(&s.restitution)) {
        return bad("restitution", s.restitution, "in [0, 1]");
    }
    if !(s.damping_per_s.is_finite() && (0.0..=MAX_DAMPING_PER_S).contains(&s.damping_per_s)) {
        return bad("damping", s.damping_per_s, "finite, ≥ 0 and at most 1e6 /s");
    }
    for (field, v, max, why) in [
        (
            "velocity",
            s.velocity_m_s,
            MAX_SPEED_M_S,
            "a speed of at most 1000 m/s",
        ),
        (
            "angular_velocity",
            s.angular_velocity_rad_s,
            MAX_SPIN_RAD_S,
            "an angular speed of at most 1e4 rad/s",
        ),
    ] {
        let norm = v.iter().map(|x| x * x).sum::<f64>().sqrt();
        if !(norm.is_finite() && norm <= max) {
            return bad(field, norm, why);
        }
        if s.fixed && norm > 0.0 {
            return bad(field, norm, "zero on a fixed body");
        }
    }
    Ok(())
}
