//! The map S(q) from joint rates θ̇ to augmented velocities q̇, and forward
//! kinematics along the joint coordinates.
//!
//! Each joint coordinate d is a world-frame twist t_d = (w_d, v_d): angular
//! velocity w_d and the velocity v_d of the body point at the world origin
//! (a rotation about axis a through p: w = a, v = p × a; a translation along
//! a: w = 0, v = a). A body B moves with every coordinate on its path to
//! the ground:
//!
//! ```text
//! ω_B = Σ w_d θ̇_d,   ṙ_B = Σ (v_d + w_d × r_B) θ̇_d,   ė_B = (|e|²/4) Ω(e)ᵀ ω_B
//! ```
//!
//! The last is `crate::rotation`'s convention read backwards: Ω ė = ω
//! because Ω Ωᵀ = (4/|e|²) I, and eᵀė = 0 because Ω e = 0, so S's columns
//! are tangent to the quaternion-norm rows and M̃ = M on them.
//!
//! A revolute turns about its child end's axis through the child end's
//! anchor, so the tree joint's own rows have zero derivative along S exactly
//! when its anchors coincide (C_tree,q S = 0 on the tree manifold, and of
//! the order of the violation off it).
//!
//! Generalized forces and Jacobian rows go the other way: a row's values g
//! on body B's columns are a world force f = g_r and torque
//! n = (|e|²/4) Ω g_e + r_B × f about the world origin, and row · S_d =
//! n·w_d + f·v_d.

use nalgebra::{Quaternion, UnitQuaternion, Vector3};

use super::ReducedError;
use super::tree::{Freedom, JointTree, TreeJoint};
use crate::rotation::BodyFrame;
use crate::{BodyId, Model};

/// A world twist: angular velocity and velocity of the point at the origin.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub(crate) struct Twist {
    pub w: Vector3<f64>,
    pub v: Vector3<f64>,
}

/// Frames of every body and the twist of every joint coordinate at one q.
#[derive(Debug, Clone)]
pub struct Kinematics {
    /// Per body (model order); fixed bodies at their pose.
    pub(crate) frames: Vec<BodyFrame>,
    /// Per joint coordinate.
    pub(crate) twists: Vec<Twist>,
}

pub(super) fn frame_of(
    model: &Model,
    q: &[f64],
    b: Option<BodyId>,
) -> Result<BodyFrame, ReducedError> {
    match b {
        None => Ok(BodyFrame::IDENTITY),
        Some(b) => model
            .body_frame(q, b)
            .ok_or(ReducedError::Degenerate(b.index())),
    }
}

/// The unit world directions a joint's coordinates act along, and the
/// point the rotations are about.
fn joint_axes(j: &TreeJoint, ends: &[BodyFrame; 2]) -> (Vector3<f64>, [Vector3<f64>; 3]) {
    let c = j.child_end;
    let p = ends[c].point(&j.anchors[c]);
    let axes = match j.freedom {
        Freedom::Revolute { axes } => [ends[c].rot * axes[c], Vector3::zeros(), Vector3::zeros()],
        Freedom::Universal { axes } => [
            ends[0].rot * axes[0],
            ends[1].rot * axes[1],
            Vector3::zeros(),
        ],
        Freedom::Spherical => [Vector3::x(), Vector3::y(), Vector3::z()],
        Freedom::Prismatic { axis } => [ends[0].rot * axis, Vector3::zeros(), Vector3::zeros()],
        Freedom::Fixed => [Vector3::zeros(); 3],
    };
    (p, axes)
}

impl Kinematics {
    /// Buffers for `model`.
    pub fn new(model: &Model, tree: &JointTree) -> Self {
        Self {
            frames: vec![BodyFrame::IDENTITY; model.bodies().len()],
            twists: vec![Twist::default(); tree.dofs],
        }
    }

    /// Frames and twists at `q`. No allocation.
    ///
    /// # Errors
    /// A degenerate quaternion.
    pub fn update(
        &mut self,
        model: &Model,
        tree: &JointTree,
        q: &[f64],
    ) -> Result<(), ReducedError> {
        for (k, f) in self.frames.iter_mut().enumerate() {
            *f = frame_of(model, q, Some(BodyId(k as u32)))?;
        }
        self.set_twists(tree);
        Ok(())
    }

    /// The twists from the frames held (each body's, model order; entries
    /// past the bodies are ignored). No allocation.
    pub(crate) fn set_twists(&mut self, tree: &JointTree) {
        for j in &tree.joints {
            let ends = [self.end(j.ends[0]), self.end(j.ends[1])];
            let (p, axes) = joint_axes(j, &ends);
            for (k, a) in axes.iter().take(j.freedom.dofs()).enumerate() {
                self.twists[j.dof + k] = match j.freedom {
                    Freedom::Prismatic { .. } => Twist {
                        w: Vector3::zeros(),
                        v: *a,
                    },
                    _ => Twist {
                        w: *a,
                        v: p.cross(a),
                    },
                };
            }
        }
    }

    fn end(&self, b: Option<BodyId>) -> BodyFrame {
        b.map_or(BodyFrame::IDENTITY, |b| self.frames[b.index()])
    }

    /// The world force and torque about the origin of a body's 7 generalized
    /// values `g` (r then e): a Jacobian row's or a generalized force's.
    #[inline]
    pub(crate) fn wrench(&self, body: usize, g: &[f64; 7]) -> (Vector3<f64>, Vector3<f64>) {
        let f = &self.frames[body];
        let s_over_4 = 1.0 / f.omega.row(0).norm_squared();
        let lin = Vector3::new(g[0], g[1], g[2]);
        let ang = f.omega * nalgebra::Vector4::new(g[3], g[4], g[5], g[6]) * s_over_4;
        (lin, ang + f.r.cross(&lin))
    }

    /// Adds `g`'s projection on body `body` to `out` (one entry per joint
    /// coordinate): out += S_Bᵀ g. O(depth of the body).
    #[inline]
    pub(crate) fn project(&self, tree: &JointTree, body: BodyId, g: &[f64; 7], out: &mut [f64]) {
        let (f, n) = self.wrench(body.index(), g);
        for j in tree.path(body) {
            let dofs = j.dof..j.dof + j.freedom.dofs();
            for (o, t) in out[dofs.clone()].iter_mut().zip(&self.twists[dofs]) {
                *o += n.dot(&t.w) + f.dot(&t.v);
            }
        }
    }

    /// S as a dense n_coords × dofs matrix (tests and the identity checks).
    pub fn s_dense(&self, model: &Model, tree: &JointTree) -> nalgebra::DMatrix<f64> {
        let mut s = nalgebra::DMatrix::zeros(model.n_coords(), tree.dofs);
        for (b, o) in model.layout().moving_bodies() {
            let f = &self.frames[b.index()];
            let s4 = 1.0 / f.omega.row(0).norm_squared();
            for j in tree.path(b) {
                for d in j.dof..j.dof + j.freedom.dofs() {
                    let t = &self.twists[d];
                    let rd = t.v + t.w.cross(&f.r);
                    let ed = f.omega.transpose() * t.w * s4;
                    for k in 0..3 {
                        s[(o + k, d)] = rd[k];
                    }
                    for k in 0..4 {
                        s[(o + 3 + k, d)] = ed[k];
                    }
                }
            }
        }
        s
    }
}

/// A rigid displacement x ↦ Q x + t.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Rigid {
    q: UnitQuaternion<f64>,
    t: Vector3<f64>,
}

impl Rigid {
    pub(crate) const IDENTITY: Self = Self {
        q: UnitQuaternion::new_unchecked(Quaternion::new(1.0, 0.0, 0.0, 0.0)),
        t: Vector3::new(0.0, 0.0, 0.0),
    };

    fn then(&self, inner: &Rigid) -> Rigid {
        Rigid {
            q: self.q * inner.q,
            t: self.q * inner.t + self.t,
        }
    }

    fn rotation_about(p: &Vector3<f64>, q: UnitQuaternion<f64>) -> Rigid {
        Rigid { q, t: p - q * p }
    }
}

/// Forward kinematics relative to `q_base`: every tree joint moved by
/// `dtheta` from its pose at `q_base` (the twists of `kin`, which must be
/// at `q_base`), written to `out`. Revolute and prismatic coordinates are
/// exact angles and lengths; a universal turns about its child end's axis,
/// then about its parent end's (the parent's axis stays fixed in the
/// parent, the child's in the child: the joint's rows hold exactly), a
/// spherical by the rotation vector of its three coordinates.
/// Allocates its scratch; [`displace_with`] does not.
pub fn displace(
    model: &Model,
    tree: &JointTree,
    kin: &Kinematics,
    q_base: &[f64],
    dtheta: &[f64],
    out: &mut [f64],
) {
    let mut rigid = vec![Rigid::IDENTITY; tree.joints.len()];
    displace_with(model, tree, kin, q_base, dtheta, out, &mut rigid);
}

/// [`displace`] with caller-owned scratch (`rigid`: one entry per tree
/// joint). No allocation.
pub(crate) fn displace_with(
    model: &Model,
    tree: &JointTree,
    kin: &Kinematics,
    q_base: &[f64],
    dtheta: &[f64],
    out: &mut [f64],
    rigid: &mut [Rigid],
) {
    out.copy_from_slice(q_base);
    for (k, j) in tree.joints.iter().enumerate() {
        let t = &kin.twists[j.dof..j.dof + j.freedom.dofs()];
        let th = &dtheta[j.dof..j.dof + j.freedom.dofs()];
        let local = match j.freedom {
            Freedom::Prismatic { .. } => Rigid {
                q: UnitQuaternion::identity(),
                t: t[0].v * th[0],
            },
            Freedom::Fixed => Rigid::IDENTITY,
            Freedom::Spherical => {
                let phi = Vector3::new(th[0], th[1], th[2]);
                let p = kin.frames[j.child.index()].point(&j.anchors[j.child_end]);
                Rigid::rotation_about(&p, exp_rotation(phi))
            }
            _ => {
                // A universal turns about its parent end's axis after its
                // child end's (the parent's axis outermost): the child's
                // axis, turned by both, stays perpendicular to the
                // parent's. Its two axes meet only at its anchor, the
                // pivot. A revolute's pivot is any point of its axis: a
                // rotation about a through p has v = p × a, so p's
                // component off a is a × v (a unit).
                let mut q = UnitQuaternion::identity();
                for i in outer_first(j) {
                    q *= exp_rotation(t[i].w * th[i]);
                }
                let p = if t.len() == 2 {
                    kin.frames[j.child.index()].point(&j.anchors[j.child_end])
                } else {
                    t[0].w.cross(&t[0].v)
                };
                Rigid::rotation_about(&p, q)
            }
        };
        let parent = j.parent_joint.map_or(Rigid::IDENTITY, |p| rigid[p]);
        rigid[k] = parent.then(&local);
        let Some(o) = model.layout().body_offset(j.child) else {
            continue;
        };
        let r = Vector3::new(out[o], out[o + 1], out[o + 2]);
        let e = Quaternion::new(out[o + 3], out[o + 4], out[o + 5], out[o + 6]);
        let (r2, e2) = (rigid[k].q * r + rigid[k].t, rigid[k].q.quaternion() * e);
        out[o..o + 3].copy_from_slice(r2.as_slice());
        out[o + 3..o + 7].copy_from_slice(&[e2.w, e2.i, e2.j, e2.k]);
    }
}

/// The order of a revolute's or universal's coordinates in its rotation's
/// product, outermost first: the parent end's axis, then the child end's (a
/// universal whose child is end i turns about `axes[1]` first, `axes[0]`
/// second). A revolute has one.
#[inline]
fn outer_first(j: &TreeJoint) -> impl Iterator<Item = usize> {
    let n = j.freedom.dofs();
    let flip = n == 2 && j.child_end == 0;
    (0..n).map(move |k| if flip { n - 1 - k } else { k })
}

/// The rotation by the rotation vector `phi`, as
/// `UnitQuaternion::from_scaled_axis` but, below a tenth of a radian a
/// half-angle (every tick's motion), from the Taylor series of cos and
/// sin(x)/x in x² to x⁸, whose next terms (< 3e-17) are below round-off:
/// no sqrt, sin or cos (the library's sincos was 7 % of the Peaucellier
/// joint tick's bench).
#[inline]
pub(crate) fn exp_rotation(phi: Vector3<f64>) -> UnitQuaternion<f64> {
    let x2 = 0.25 * phi.norm_squared();
    // NaN-safe: a NaN x2 takes the library's path.
    if x2.partial_cmp(&1e-2) != Some(std::cmp::Ordering::Less) {
        return UnitQuaternion::from_scaled_axis(phi);
    }
    let c = 1.0 - x2 / 2.0 * (1.0 - x2 / 12.0 * (1.0 - x2 / 30.0 * (1.0 - x2 / 56.0)));
    let sinc = 1.0 - x2 / 6.0 * (1.0 - x2 / 20.0 * (1.0 - x2 / 42.0 * (1.0 - x2 / 72.0)));
    let v = phi * (0.5 * sinc);
    UnitQuaternion::new_unchecked(Quaternion::new(c, v.x, v.y, v.z))
}

#[cfg(test)]
mod exp_tests {
    use super::*;

    /// The series agrees with `from_scaled_axis` to 2 ulp over its range,
    /// and the quaternion is unit to round-off.
    #[test]
    fn the_series_rotation_matches_the_library() {
        let mut worst = 0.0f64;
        for k in 0..2000 {
            let t = k as f64 / 2000.0;
            let phi = Vector3::new(0.3 * t, -0.11 * t, 0.07 * (1.0 - t)) * (0.6 * t + 1e-9);
            let (a, b) = (exp_rotation(phi), UnitQuaternion::from_scaled_axis(phi));
            worst = worst.max((a.coords - b.coords).amax());
            assert!((a.coords.norm() - 1.0).abs() < 4e-16);
        }
        assert!(worst < 4.5e-16, "{worst:e}");
        let big = Vector3::new(0.5, 0.2, -0.1);
        assert_eq!(exp_rotation(big), UnitQuaternion::from_scaled_axis(big));
    }
}
