//! Projecting a configuration onto the spanning tree's manifold: every
//! quaternion normalised and every tree joint's rows closed, so that the
//! rows a joint tick never evaluates (it keeps them by forward kinematics)
//! start from zero instead of from whatever an augmented tick left (a
//! fallback, `program/joint_fallback.rs`). The loop-closing rows are left
//! to the joint ticks after it.
//!
//! Parent before child (the tree's breadth-first order), each child body
//! is turned by the smallest world rotation that satisfies its joint's
//! orientation rows with the parent's pose as it now is, then moved so that
//! its anchor satisfies the joint's position rows:
//!
//! - revolute: the child end's axis onto ± the parent end's (the rows
//!   f_i·h_j = g_i·h_j = 0 hold for either sign; the nearer is taken);
//! - universal: the child end's axis into the plane perpendicular to the
//!   parent end's;
//! - prismatic: the axes aligned as a revolute's, then the child turned
//!   about the axis until g_i·m_j = 0 (m_j onto the nearer of ± f_i);
//! - weld: the child's rotation from the parent's and the relative one;
//! - spherical: no orientation row;
//!
//! and the anchors made coincident (a prismatic's: their offset off the
//! axis removed). Each correction is of the order of the rows' residue.

use nalgebra::{Matrix3, Quaternion, Rotation3, UnitQuaternion, Vector3};

use super::ReducedError;
use super::kinematics::frame_of;
use super::tick::JointTick;
use super::tree::{Freedom, TreeJoint};
use crate::Model;
use crate::constraint::Geometry;
use crate::rotation::BodyFrame;

/// The smallest rotation taking direction `from` onto `to` (identity when
/// they are parallel or either is zero).
fn turn(from: &Vector3<f64>, to: &Vector3<f64>) -> UnitQuaternion<f64> {
    UnitQuaternion::rotation_between(from, to).unwrap_or_else(UnitQuaternion::identity)
}

/// `v` onto the nearer of ± `onto`.
fn nearer(v: &Vector3<f64>, onto: &Vector3<f64>) -> Vector3<f64> {
    if v.dot(onto) < 0.0 { -onto } else { *onto }
}

/// The child's new world rotation for joint `j`, given both ends' frames
/// (the child's quaternion normalised).
fn child_rotation(model: &Model, j: &TreeJoint, ends: &[BodyFrame; 2]) -> Matrix3<f64> {
    let (c, p) = (j.child_end, 1 - j.child_end);
    let rc = ends[c].rot;
    match (j.freedom, &model.geometry[j.constraint]) {
        (Freedom::Revolute { axes }, _) => {
            let (ac, ap) = (rc * axes[c], ends[p].rot * axes[p]);
            turn(&ac, &nearer(&ac, &ap))
                .to_rotation_matrix()
                .into_inner()
                * rc
        }
        (Freedom::Universal { axes }, _) => {
            let (ac, ap) = (rc * axes[c], (ends[p].rot * axes[p]).normalize());
            let to = ac - ap * ac.dot(&ap);
            turn(&ac, &to).to_rotation_matrix().into_inner() * rc
        }
        (Freedom::Prismatic { .. }, Geometry::Prismatic(g)) => {
            let a = &g.axes;
            let (hi, hj) = (ends[0].rot * a.h_i, ends[1].rot * a.h_j);
            let (hc, hp) = if c == 0 { (hi, hj) } else { (hj, hi) };
            let rc = turn(&hc, &nearer(&hc, &hp))
                .to_rotation_matrix()
                .into_inner()
                * rc;
            let mut rot = [ends[0].rot, ends[1].rot];
            rot[c] = rc;
            let (fi, mj) = (rot[0] * a.f_i, rot[1] * a.m_j);
            let (vc, vp) = if c == 0 { (fi, mj) } else { (mj, fi) };
            turn(&vc, &nearer(&vc, &vp))
                .to_rotation_matrix()
                .into_inner()
                * rc
        }
        // The rows compare R_i with R_j · relative.
        (Freedom::Fixed, Geometry::Weld(g)) if c == 1 => ends[0].rot * g.relative.transpose(),
        (Freedom::Fixed, Geometry::Weld(g)) => ends[1].rot * g.relative,
        _ => rc,
    }
}

/// `rot` as a unit quaternion `[w, x, y, z]` on the same side as `e` (so
/// that a small correction is a small change of q).
fn quaternion_near(rot: &Matrix3<f64>, e: &[f64]) -> [f64; 4] {
    let u = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(*rot));
    let q: &Quaternion<f64> = u.quaternion();
    let s = if q.w * e[0] + q.i * e[1] + q.j * e[2] + q.k * e[3] < 0.0 {
        -1.0
    } else {
        1.0
    };
    [s * q.w, s * q.i, s * q.j, s * q.k]
}

impl JointTick {
    /// Moves `q` onto the tree's manifold (see the module docs): the
    /// quaternion norms and every tree joint's rows closed to round-off,
    /// the loop rows not looked at.
    ///
    /// # Real-time
    /// No allocation; O(tree joints).
    ///
    /// # Errors
    /// A degenerate quaternion in q (q is then partly moved).
    pub fn project_onto_tree(&self, q: &mut [f64]) -> Result<(), ReducedError> {
        let model = &*self.model;
        for j in &self.space.tree.joints {
            let Some(o) = model.layout().body_offset(j.child) else {
                continue;
            };
            let n = q[o + 3..o + 7].iter().map(|v| v * v).sum::<f64>().sqrt();
            if !(n > 0.0 && n.is_finite()) {
                return Err(ReducedError::Degenerate(j.child.index()));
            }
            q[o + 3..o + 7].iter_mut().for_each(|v| *v /= n);
            let ends = [
                frame_of(model, q, j.ends[0])?,
                frame_of(model, q, j.ends[1])?,
            ];
            let rot = child_rotation(model, j, &ends);
            let e = quaternion_near(&rot, &q[o + 3..o + 7]);
            q[o + 3..o + 7].copy_from_slice(&e);
            let (c, p) = (j.child_end, 1 - j.child_end);
            let child = frame_of(model, q, Some(j.child))?;
            let d = child.point(&j.anchors[c]) - ends[p].point(&j.anchors[p]);
            let shift = match (j.freedom, &model.geometry[j.constraint]) {
                (Freedom::Prismatic { .. }, Geometry::Prismatic(g)) => {
                    let h = if c == 0 { child.rot } else { ends[0].rot } * g.axes.h_i;
                    let h = h.normalize();
                    d - h * h.dot(&d)
                }
                _ => d,
            };
            for k in 0..3 {
                q[o + k] -= shift[k];
            }
        }
        Ok(())
    }
}
