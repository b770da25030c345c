//! Where everything lives in q.
//!
//! q = [ moving bodies in body order: r (3, metres, world) then e (4, [w, x, y, z]) ]
//!     [ free design variables in joint order, then in the order `free` lists them ]
//!
//! Fixed bodies have no coordinates.

use std::ops::Range;

use super::spec::DesignParam;
use crate::{BodyId, ConstraintId, DesignVarId};

/// One free design variable.
#[derive(Debug, Clone, PartialEq)]
pub struct DesignVar {
    /// `"<joint>.<param>"`, e.g. `"left.length"`.
    pub name: String,
    /// The joint it belongs to.
    pub joint: ConstraintId,
    /// Which parameter.
    pub param: DesignParam,
    /// First column in q.
    pub offset: usize,
    /// 1 (length, metres) or 3 (anchor, metres, body frame).
    pub width: usize,
}

/// Map from bodies and design variables to columns of q.
#[derive(Debug, Clone, PartialEq)]
pub struct Layout {
    pub(crate) body_cols: Vec<Option<usize>>,
    pub(crate) design_vars: Vec<DesignVar>,
    pub(crate) body_coords: usize,
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
