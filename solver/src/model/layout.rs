//! Where everything lives in q.
//!
//! q = [ moving bodies in body order: r (3, metres, world) then e (4, [w, x, y, z]) ]
//!     [ free positions of fixed bodies, in body order (3 each, metres, world) ]
//!     [ free design variables of joints in joint order, then in the order `free` lists them ]
//!     [ auxiliary blocks: flexible bodies' deformations, surface contacts' (u, v) ]
//!
//! Fixed bodies have no coordinates of their own; a fixed body whose position
//! is free (`free = ["position"]`) has it among the design variables: its
//! frame's origin is read from q, its orientation stays the initial one.

use std::ops::Range;

use super::spec::DesignParam;
use crate::{BodyId, ConstraintId, DesignVarId};

/// What a design variable belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DesignOwner {
    /// A joint's length or anchor.
    Joint(ConstraintId),
    /// A fixed body's position.
    Body(BodyId),
}

/// One free design variable.
#[derive(Debug, Clone, PartialEq)]
pub struct DesignVar {
    /// `"<joint>.<param>"` or `"<body>.position"`, e.g. `"left.length"`.
    pub name: String,
    /// The joint or fixed body it belongs to.
    pub owner: DesignOwner,
    /// Which parameter.
    pub param: DesignParam,
    /// First column in q.
    pub offset: usize,
    /// 1 (length, metres) or 3 (anchor, metres, body frame; position,
    /// metres, world frame).
    pub width: usize,
    /// `[lo, hi]` per component (the first `width` entries), if bounded.
    pub bounds: Option<[[f64; 2]; 3]>,
}

impl DesignVar {
    /// The name of component `k`: the variable's own name when it has one
    /// component, else `"<name>.x"`, `".y"`, `".z"`.
    pub fn component_name(&self, k: usize) -> String {
        if self.width == 1 {
            self.name.clone()
        } else {
            format!("{}.{}", self.name, ["x", "y", "z"][k.min(2)])
        }
    }
}

/// Map from bodies and design variables to columns of q.
#[derive(Debug, Clone, PartialEq)]
pub struct Layout {
    pub(crate) body_cols: Vec<Option<usize>>,
    /// Per body: the first of the three design columns of a fixed body's
    /// free position.
    pub(crate) origin_cols: Vec<Option<usize>>,
    pub(crate) design_vars: Vec<DesignVar>,
    pub(crate) body_coords: usize,
    /// Auxiliary blocks (`super::auxiliary`), after the design variables.
    pub(crate) aux: Vec<super::auxiliary::AuxBlock>,
    pub(crate) len: usize,
}

impl Layout {
    /// Number of coordinates (columns of C_q).
    pub fn len(&self) -> usize {
        self.len
    }

    /// True when there are no coordinates at all.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Number of body coordinates (7 per moving body); design variables start here.
    pub fn body_coords(&self) -> usize {
        self.body_coords
    }

    /// Column of r for a moving body (`None` for a fixed or unknown body). Its
    /// r occupies `offset..offset + 3`, its e = [w, x, y, z] `offset + 3..offset + 7`.
    pub fn body_offset(&self, body: BodyId) -> Option<usize> {
        self.body_cols.get(body.index()).copied().flatten()
    }

    /// First design column of a fixed body's free position (metres, world
    /// frame: `offset..offset + 3`); `None` for other bodies.
    pub fn origin_offset(&self, body: BodyId) -> Option<usize> {
        self.origin_cols.get(body.index()).copied().flatten()
    }

    /// Number of design-variable columns (those after the bodies' and before
    /// the auxiliary blocks).
    pub fn design_coords(&self) -> usize {
        self.len - self.body_coords - self.aux_coords()
    }

    /// The design-variable columns.
    pub fn design_range(&self) -> Range<usize> {
        self.body_coords..self.body_coords + self.design_coords()
    }

    /// The auxiliary blocks (flexible bodies' deformations, surface
    /// contacts' parameters), in column order.
    pub fn aux_blocks(&self) -> &[super::auxiliary::AuxBlock] {
        &self.aux
    }

    /// Number of auxiliary columns (all at the end of q).
    pub fn aux_coords(&self) -> usize {
        self.aux.iter().map(|b| b.width).sum()
    }

    /// Columns of r (metres, world frame) of a moving body.
    pub fn position_range(&self, body: BodyId) -> Option<Range<usize>> {
        self.body_offset(body).map(|o| o..o + 3)
    }

    /// Columns of e = [w, x, y, z] of a moving body.
    pub fn rotation_range(&self, body: BodyId) -> Option<Range<usize>> {
        self.body_offset(body).map(|o| o + 3..o + 7)
    }

    /// Moving bodies and their offsets, in body order.
    pub fn moving_bodies(&self) -> impl Iterator<Item = (BodyId, usize)> + '_ {
        self.body_cols
            .iter()
            .enumerate()
            .filter_map(|(i, c)| c.map(|c| (BodyId(i as u32), c)))
    }

    /// The free design variables.
    pub fn design_vars(&self) -> &[DesignVar] {
        &self.design_vars
    }

    /// Columns of one design variable.
    pub fn design_var_range(&self, id: DesignVarId) -> Option<Range<usize>> {
        self.design_vars
            .get(id.index())
            .map(|d| d.offset..d.offset + d.width)
    }

    /// The design variable called `name` (`"<joint>.<param>"`).
    pub fn design_var_id(&self, name: &str) -> Option<DesignVarId> {
        self.design_vars
            .iter()
            .position(|d| d.name == name)
            .map(|i| DesignVarId(i as u32))
    }
}
