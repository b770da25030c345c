//! The joint tick's evaluation: only the loop-closing and finger
//! constraints (the tree joints hold by construction, the quaternion norms
//! too), their values and, at the end of a tick, their rows of J_r S
//! written straight from each row's world-frame gradient, without the
//! augmented Jacobian: a row's gradient (lin, ang) on a body at r is a force
//! lin and a torque ang + r × lin about the origin, and its entry for joint
//! coordinate d on the body's path is that wrench dotted with the twist
//! (`kinematics`).

use nalgebra::Vector3;

use super::kinematics::Twist;
use super::tree::JointTree;
use crate::constraint::block::{Ctx, NoJacobian, RowGrad, Sink, Slot};
use crate::rotation::BodyFrame;
use crate::{BodyId, FingerTarget, Model};

/// One evaluated constraint.
#[derive(Debug, Clone)]
struct Evaluated {
    constraint: usize,
    /// First model row and row count.
    row0: usize,
    rows: usize,
    /// The moving body of each end (body index), `None` for ground.
    ends: [Option<usize>; 2],
}

/// Which constraints the joint tick evaluates and where their kept rows go.
#[derive(Debug, Clone)]
pub(crate) struct RowSet {
    list: Vec<Evaluated>,
    /// Per model row: its index among the kept rows, or `u32::MAX`.
    slot: Vec<u32>,
}

/// Writes the kept rows of one constraint into J_r S (scaled).
struct JointRows<'a> {
    out: &'a mut [f64],
    slot: &'a [u32],
    scale: &'a [f64],
    grads: &'a mut [RowGrad],
    ends: [Option<(usize, Vector3<f64>)>; 2],
    tree: &'a JointTree,
    twists: &'a [Twist],
    n: usize,
    raw: bool,
}

impl Sink for JointRows<'_> {
    #[inline]
    fn row(&mut self, row: usize, g: &RowGrad) {
        let i = self.slot[row];
        if i == u32::MAX {
            return;
        }
        let i = i as usize;
        self.grads[i] = *g;
        let out = &mut self.out[i * self.n..(i + 1) * self.n];
        out.fill(0.0);
        for (end, e) in self.ends.iter().enumerate() {
            let Some((b, r)) = e else { continue };
            let f = g.lin[end];
            let t = g.ang[end] + r.cross(&f);
            for j in self.tree.path(BodyId(*b as u32)) {
                let dofs = j.dof..j.dof + j.freedom.dofs();
                for (o, tw) in out[dofs.clone()].iter_mut().zip(&self.twists[dofs]) {
                    *o += t.dot(&tw.w) + f.dot(&tw.v);
                }
            }
        }
        let s = self.scale[i];
        for v in out.iter_mut() {
            *v *= s;
        }
    }

    #[inline]
    fn set(&mut self, row: usize, slot: Slot, _: usize, _: f64) {
        // A raw entry on a body's columns (only the quaternion norms write
        // one, and they are not evaluated here) has no joint-space form.
        let body = matches!(slot, Slot::BodyI | Slot::BodyJ);
        self.raw |= body && self.slot[row] != u32::MAX;
    }
}

impl RowSet {
    /// The constraints holding `rows` (model rows, kept order) or any of
    /// `also` (rows evaluated for their values only).
    pub fn new(model: &Model, rows: &[usize], also: &[usize]) -> Self {
        let mut slot = vec![u32::MAX; model.n_rows()];
        for (i, &r) in rows.iter().enumerate() {
            slot[r] = i as u32;
        }
        let nb = model.bodies().len();
        let mut list = Vec::new();
        for (k, info) in model.constraints().iter().enumerate() {
            let wanted = info
                .rows
                .clone()
                .any(|r| slot[r] != u32::MAX || also.contains(&r));
            if !wanted {
                continue;
            }
            let frames = model.geometry[k].frames();
            let ends = frames.map(|f| {
                (f < nb && model.layout().body_offset(BodyId(f as u32)).is_some()).then_some(f)
            });
            list.push(Evaluated {
                constraint: k,
                row0: info.rows.start,
                rows: info.rows.len(),
                ends,
            });
        }
        Self { list, slot }
    }

    /// Every row of the evaluated constraints (model rows).
    pub fn evaluated(&self) -> impl Iterator<Item = usize> + '_ {
        self.list.iter().flat_map(|e| e.row0..e.row0 + e.rows)
    }

    /// Values of the evaluated constraints at `frames` (bodies, then the
    /// world) into `values` (model rows). No allocation.
    pub fn values(
        &self,
        model: &Model,
        q: &[f64],
        frames: &[BodyFrame],
        targets: &[FingerTarget],
        values: &mut [f64],
    ) {
        let x = ctx(model, q, frames, targets);
        for e in &self.list {
            let c = &mut values[e.row0..e.row0 + e.rows];
            model.geometry[e.constraint].eval(&x, c, &mut NoJacobian);
        }
    }

    /// Values, and the kept rows of J_r S scaled by `scale` into `out`
    /// (kept rows × dofs, row-major) with each kept row's gradient in
    /// `grads`. False if a kept row has an entry with no joint-space form.
    #[allow(clippy::too_many_arguments)]
    pub fn jacobian(
        &self,
        model: &Model,
        tree: &JointTree,
        q: &[f64],
        frames: &[BodyFrame],
        twists: &[Twist],
        targets: &[FingerTarget],
        scale: &[f64],
        values: &mut [f64],
        out: &mut [f64],
        grads: &mut [RowGrad],
    ) -> bool {
        let x = ctx(model, q, frames, targets);
        let mut ok = true;
        for e in &self.list {
            let mut sink = JointRows {
                out: &mut *out,
                slot: &self.slot[e.row0..e.row0 + e.rows],
                scale,
                grads: &mut *grads,
                ends: e.ends.map(|b| b.map(|b| (b, frames[b].r))),
                tree,
                twists,
                n: tree.dofs,
                raw: false,
            };
            let c = &mut values[e.row0..e.row0 + e.rows];
            model.geometry[e.constraint].eval(&x, c, &mut sink);
            ok &= !sink.raw;
        }
        ok
    }
}

fn ctx<'a>(
    model: &'a Model,
    q: &'a [f64],
    frames: &'a [BodyFrame],
    targets: &'a [FingerTarget],
) -> Ctx<'a> {
    Ctx {
        q,
        frames,
        targets,
        witnesses: &[],
        flex: &model.flex_anchors,
        surfaces: &model.surfaces,
        rolling: &[],
    }
}
