//! The constraint list's assembly: [`Assembler`] appends constraints and
//! their rows; the quaternion-norm rows, the tail of rolling, design and
//! limit rows, and q0 at the scene's poses.

use super::Body;
use super::layout::{DesignOwner, DesignVar};
use crate::constraint::bound::DesignBound;
use crate::constraint::quat_norm::QuatNorm;
use crate::constraint::{ConstraintInfo, ConstraintKind, Geometry, RowInfo};
use crate::{BodyId, ConstraintId};

/// One quaternion-norm row per free body.
pub(super) fn push_norms(bodies: &[Body], body_cols: &[Option<usize>], out: &mut Assembler) {
    for (i, b) in bodies.iter().enumerate() {
        if let Some(col) = body_cols[i] {
            let info = ConstraintInfo {
                name: format!("{}.norm", b.name),
                kind: ConstraintKind::QuaternionNorm,
                rows: 0..0,
                bodies: [Some(BodyId(i as u32)), None],
                finger: None,
                limits: None,
            };
            out.push(info, Geometry::QuatNorm(QuatNorm { col }));
        }
    }
}

/// Rolling joints' no-slip rows and pinned design components (equalities),
/// then the joint limits and the design bounds (inequalities). Returns the
/// rolling constraints' indices and the number of equality rows.
pub(super) fn push_tail_rows(
    rolls: Vec<(ConstraintInfo, Geometry)>,
    limits: Vec<(ConstraintInfo, Geometry, ConstraintId)>,
    design_vars: &[DesignVar],
    out: &mut Assembler,
) -> (Vec<usize>, usize) {
    let mut rolling = Vec::with_capacity(rolls.len());
    for (slot, (info, mut g)) in rolls.into_iter().enumerate() {
        if let Geometry::Rolling(r) = &mut g {
            r.slot = slot as u32;
        }
        rolling.push(out.infos.len());
        out.push(info, g);
    }
    let bounds = design_bounds(design_vars);
    for (info, g) in bounds.iter().filter(|(_, g)| g.lo == g.hi) {
        out.push(info.clone(), Geometry::Bound(*g));
    }
    let equality_rows = out.rows.len();
    for (mut info, geometry, joint) in limits {
        info.limits = Some(joint);
        out.push(info, geometry);
    }
    for (info, g) in bounds.iter().filter(|(_, g)| g.lo != g.hi) {
        out.push(info.clone(), Geometry::Bound(*g));
    }
    (rolling, equality_rows)
}

/// q at the scene's poses: each free body's position and quaternion, then
/// the design and auxiliary tail (undeformed flexible bodies at 0).
pub(super) fn initial_q(bodies: &[Body], tail: &[f64], len: usize) -> Vec<f64> {
    let mut q0 = Vec::with_capacity(len);
    for b in bodies.iter().filter(|b| !b.fixed) {
        let o = b.orientation.quaternion();
        q0.extend_from_slice(b.position_m.as_slice());
        q0.extend_from_slice(&[o.w, o.i, o.j, o.k]);
    }
    q0.extend_from_slice(tail);
    q0.resize(len, 0.0);
    q0
}

/// Appends constraints, assigning their row ranges and row metadata.
#[derive(Default)]
pub(super) struct Assembler {
    pub infos: Vec<ConstraintInfo>,
    pub geometry: Vec<Geometry>,
    pub rows: Vec<RowInfo>,
}

impl Assembler {
    pub fn push(&mut self, mut info: ConstraintInfo, geometry: Geometry) {
        let id = ConstraintId(self.infos.len() as u32);
        let n = geometry.rows();
        let start = self.rows.len();
        info.rows = start..start + n;
        self.rows.extend((0..n).map(|r| RowInfo {
            constraint: id,
            sense: info.kind.sense(),
            unit: info.kind.row_unit(r),
        }));
        self.infos.push(info);
        self.geometry.push(geometry);
    }
}

/// One bound constraint per bounded design-variable component: its info
/// (named `"<component>.bounds"`, the owner's bodies) and geometry.
fn design_bounds(vars: &[DesignVar]) -> Vec<(ConstraintInfo, DesignBound)> {
    let mut out = Vec::new();
    for d in vars {
        let Some(b) = d.bounds else { continue };
        let bodies = match d.owner {
            DesignOwner::Body(id) => [Some(id), None],
            DesignOwner::Joint(_) => [None, None],
        };
        for (k, &[lo, hi]) in b.iter().take(d.width).enumerate() {
            let kind = if lo == hi {
                ConstraintKind::DesignPin
            } else {
                ConstraintKind::DesignBound
            };
            let info = ConstraintInfo {
                name: format!("{}.bounds", d.component_name(k)),
                kind,
                rows: 0..0,
                bodies,
                finger: None,
                limits: None,
            };
            out.push((
                info,
                DesignBound {
                    col: d.offset + k,
                    lo,
                    hi,
                },
            ));
        }
    }
    out
}
