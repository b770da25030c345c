//! Parametric surfaces S(u, v) in a body's frame: graphs over a local
//! frame (origin o, rotation A, body frame),
//!
//! ```text
//! S(u, v) = o + A (u, v, h(u, v))ᵀ,    n = A m / |m|,   m = (−h_u, −h_v, 1)
//! ```
//!
//! with h per kind: a plane (h = 0), a sphere of radius R (h = s (R − w),
//! w = √(R² − u² − v²): s = +1 a bowl whose lowest point is o, s = −1 a
//! dome whose top is o), a cylinder along local x (h = s (R − √(R² − v²))).
//! (u, v) are metres on the local x, y axes, so the parameters are regular
//! everywhere on the patch (|(u, v)| < R for the sphere, |v| < R for the
//! cylinder): no pole. A body touches a surface from the side its normal n
//! points to (local +z).
//!
//! [`Surface::offset`] gives the surface a ball's centre moves on:
//! P = S + ρ n, P_u = S_u + ρ n_u, with n_u from the second derivatives
//! (Weingarten): n_u = (m_u − n (n·m_u)) / |m|, m_u = (−h_uu, −h_uv, 0).

use nalgebra::{Matrix3, Vector3};

/// The shape of a [`Surface`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SurfaceKind {
    /// The local xy plane.
    Plane,
    /// A sphere of radius R through o, tangent to the local xy plane there:
    /// a bowl (`concave`: the centre is at o + R z) or a dome.
    Sphere {
        /// R, metres.
        radius_m: f64,
        /// Bowl (true) or dome.
        concave: bool,
    },
    /// A cylinder of radius R along the local x axis, tangent to the local
    /// xy plane along it: a trough (`concave`) or a ridge.
    Cylinder {
        /// R, metres.
        radius_m: f64,
        /// Trough (true) or ridge.
        concave: bool,
    },
}

/// A surface fixed to a body.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Surface {
    /// Its shape.
    pub kind: SurfaceKind,
    /// o, metres, body frame.
    pub origin_m: Vector3<f64>,
    /// A: local → body frame.
    pub rotation: Matrix3<f64>,
}

/// A point of a (possibly offset) surface and its tangents, body frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfacePoint {
    /// The point, metres.
    pub p: Vector3<f64>,
    /// ∂p/∂u.
    pub pu: Vector3<f64>,
    /// ∂p/∂v.
    pub pv: Vector3<f64>,
    /// Unit normal (the side bodies touch from).
    pub n: Vector3<f64>,
}

/// h and its first and second derivatives at (u, v): (h, h_u, h_v, h_uu,
/// h_uv, h_vv).
type Height = (f64, f64, f64, f64, f64, f64);

fn sphere_height(r: f64, s: f64, u: f64, v: f64) -> Height {
    let w = (r * r - u * u - v * v).sqrt();
    let w3 = w * w * w;
    (
        s * (r - w),
        s * u / w,
        s * v / w,
        s * (1.0 / w + u * u / w3),
        s * u * v / w3,
        s * (1.0 / w + v * v / w3),
    )
}

impl Surface {
    /// A surface of `kind` with its local frame at `origin_m` turned by
    /// `rotation` (local → body).
    pub fn new(kind: SurfaceKind, origin_m: Vector3<f64>, rotation: Matrix3<f64>) -> Self {
        Self {
            kind,
            origin_m,
            rotation,
        }
    }

    fn height(&self, u: f64, v: f64) -> Height {
        match self.kind {
            SurfaceKind::Plane => (0.0, 0.0, 0.0, 0.0, 0.0, 0.0),
            SurfaceKind::Sphere { radius_m, concave } => {
                sphere_height(radius_m, if concave { 1.0 } else { -1.0 }, u, v)
            }
            SurfaceKind::Cylinder { radius_m, concave } => {
                let (h, _, hv, _, _, hvv) =
                    sphere_height(radius_m, if concave { 1.0 } else { -1.0 }, 0.0, v);
                (h, 0.0, hv, 0.0, 0.0, hvv)
            }
        }
    }

    /// Whether (u, v) lies on the surface's patch (where it is a graph).
    pub fn covers(&self, u: f64, v: f64) -> bool {
        match self.kind {
            SurfaceKind::Plane => u.is_finite() && v.is_finite(),
            SurfaceKind::Sphere { radius_m, .. } => u * u + v * v < radius_m * radius_m,
            SurfaceKind::Cylinder { radius_m, .. } => u.is_finite() && v.abs() < radius_m,
        }
    }

    /// The surface offset by `rho` along its normal at (u, v): the point
    /// P = S + ρ n and its tangents, body frame (ρ = 0: the surface
    /// itself). Not finite off the patch.
    #[inline]
    pub fn offset(&self, u: f64, v: f64, rho: f64) -> SurfacePoint {
        let (h, hu, hv, huu, huv, hvv) = self.height(u, v);
        let m = Vector3::new(-hu, -hv, 1.0);
        let len = m.norm();
        let n = m / len;
        let dn = |mu: Vector3<f64>| (mu - n * n.dot(&mu)) / len;
        let nu = dn(Vector3::new(-huu, -huv, 0.0));
        let nv = dn(Vector3::new(-huv, -hvv, 0.0));
        let a = &self.rotation;
        SurfacePoint {
            p: self.origin_m + a * (Vector3::new(u, v, h) + n * rho),
            pu: a * (Vector3::new(1.0, 0.0, hu) + nu * rho),
            pv: a * (Vector3::new(0.0, 1.0, hv) + nv * rho),
            n: a * n,
        }
    }

    /// The parameters of the point of the offset surface nearest `p` (body
    /// frame), by Gauss–Newton from the local xy of `p` (20 steps at most);
    /// with the distance left, metres.
    pub fn project(&self, p: &Vector3<f64>, rho: f64) -> ([f64; 2], f64) {
        let local = self.rotation.tr_mul(&(p - self.origin_m));
        let (mut u, mut v) = (local.x, local.y);
        for _ in 0..20 {
            let s = self.offset(u, v, rho);
            let d = p - s.p;
            let (a, b, c) = (s.pu.dot(&s.pu), s.pu.dot(&s.pv), s.pv.dot(&s.pv));
            let (gu, gv) = (s.pu.dot(&d), s.pv.dot(&d));
            let det = a * c - b * b;
            if !(det.is_finite() && det > 0.0) {
                break;
            }
            let (du, dv) = ((c * gu - b * gv) / det, (a * gv - b * gu) / det);
            if !self.covers(u + du, v + dv) {
                break;
            }
            u += du;
            v += dv;
            if du.abs().max(dv.abs()) < 1e-15 {
                break;
            }
        }
        let s = self.offset(u, v, rho);
        ([u, v], (p - s.p).norm())
    }
}

/// The surface of a [`ContactSurface`](crate::ContactSurface), checked:
/// a finite origin within ±10 km, a normalisable orientation, a radius
/// finite and > 0. The error says what is wrong.
pub(crate) fn check(spec: &crate::ContactSurface) -> Result<Surface, String> {
    let radius_ok = |r: f64| {
        if r.is_finite() && r > 0.0 && r <= 1e4 {
            Ok(())
        } else {
            Err(format!("surface `radius` = {r} must be finite and > 0 m"))
        }
    };
    match spec.kind {
        SurfaceKind::Plane => {}
        SurfaceKind::Sphere { radius_m, .. } | SurfaceKind::Cylinder { radius_m, .. } => {
            radius_ok(radius_m)?
        }
    }
    if !spec
        .origin_m
        .iter()
        .all(|x| x.is_finite() && x.abs() <= 1e4)
    {
        return Err(format!(
            "surface `origin` {:?} must be finite, within ±10 km",
            spec.origin_m
        ));
    }
    let [w, x, y, z] = spec.orientation_wxyz;
    let q = nalgebra::Quaternion::new(w, x, y, z);
    let n2 = q.norm_squared();
    if !(n2.is_finite() && n2 > 0.0) {
        return Err("surface `orientation` cannot be normalised".into());
    }
    let rot = nalgebra::UnitQuaternion::from_quaternion(q).to_rotation_matrix();
    Ok(Surface::new(
        spec.kind,
        Vector3::from(spec.origin_m),
        rot.into_inner(),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn surfaces() -> Vec<Surface> {
        let rot = nalgebra::Rotation3::from_euler_angles(0.3, -0.2, 0.7).into_inner();
        let o = Vector3::new(0.01, -0.02, 0.03);
        [
            SurfaceKind::Plane,
            SurfaceKind::Sphere {
                radius_m: 0.2,
                concave: true,
            },
            SurfaceKind::Sphere {
                radius_m: 0.15,
                concave: false,
            },
            SurfaceKind::Cylinder {
                radius_m: 0.1,
                concave: true,
            },
        ]
        .into_iter()
        .map(|k| Surface::new(k, o, rot))
        .collect()
    }

    /// Tangents of the offset surface against central differences of its
    /// points, and the normal against the tangents' cross product.
    #[test]
    fn tangents_match_finite_differences() {
        for s in surfaces() {
            for (u, v, rho) in [(0.03, -0.02, 0.0), (-0.05, 0.04, 0.02), (0.0, 0.07, 0.01)] {
                let h = 1e-6;
                let x = s.offset(u, v, rho);
                let du = (s.offset(u + h, v, rho).p - s.offset(u - h, v, rho).p) / (2.0 * h);
                let dv = (s.offset(u, v + h, rho).p - s.offset(u, v - h, rho).p) / (2.0 * h);
                assert!(
                    (du - x.pu).norm() < 1e-8,
                    "{:?} u: {du} vs {}",
                    s.kind,
                    x.pu
                );
                assert!(
                    (dv - x.pv).norm() < 1e-8,
                    "{:?} v: {dv} vs {}",
                    s.kind,
                    x.pv
                );
                let n0 = s.offset(u, v, 0.0);
                let cross = n0.pu.cross(&n0.pv).normalize();
                assert!((cross - x.n).norm() < 1e-12, "{:?}: normal", s.kind);
            }
        }
    }

    /// The offset of a sphere is the concentric sphere: a bowl's centre
    /// stays R − ρ from the bowl's centre.
    #[test]
    fn a_bowls_offset_is_the_concentric_sphere() {
        let s = Surface::new(
            SurfaceKind::Sphere {
                radius_m: 0.2,
                concave: true,
            },
            Vector3::zeros(),
            Matrix3::identity(),
        );
        let c = Vector3::new(0.0, 0.0, 0.2);
        for (u, v) in [(0.0, 0.0), (0.05, -0.1), (-0.12, 0.03)] {
            let p = s.offset(u, v, 0.03).p;
            assert!(((p - c).norm() - 0.17).abs() < 1e-15);
            let ([pu, pv], d) = s.project(&p, 0.03);
            assert!(d < 1e-14 && (pu - u).abs() < 1e-12 && (pv - v).abs() < 1e-12);
        }
    }
}
