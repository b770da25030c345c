//! The joint tick's violation report without a pass over every row each
//! tick: the rows the joint tick never evaluates (tree joints, quaternion
//! norms) are summed once per resync, the evaluated ones (the loop-closing
//! and finger constraints) each tick, by `Violation::of`'s rules for the
//! rows such a model has (equalities, masked equalities; finger rows left
//! out). The maxima equal `Violation::of` over all rows exactly; the RMS
//! sums in another order (round-off).

use crate::al::scaling::{Role, Scaling};
use crate::al::update::Violation;
use crate::{Model, RowUnit, Sense};

/// The rows joint ticks never evaluate (tree joints, norms) count as
/// closed at a resync within this × L (scaled); beyond it the next joint
/// tick first projects q onto the tree (`joint_fallback`), since joint
/// ticks would keep that residue for the rest of the run.
pub(super) const CLOSED: f64 = 1e-10;

/// Violation statistics over some rows.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct RowStats {
    max_m: f64,
    max_rad: f64,
    max_norm: f64,
    sum_m: f64,
    count_m: usize,
    max_scaled_m: f64,
}

impl RowStats {
    /// Adds row `i` with value `c`.
    #[inline]
    fn add(&mut self, model: &Model, s: &Scaling, i: usize, c: f64) {
        let row = &model.rows()[i];
        let e = match (s.role[i], row.sense) {
            (Role::Finger | Role::Coupling | Role::Friction | Role::Contact, _)
            | (Role::Redundant, Sense::Friction) => return,
            (_, Sense::Equality) => c.abs(),
            _ => (-c).max(0.0),
        };
        match row.unit {
            RowUnit::Length => {
                self.max_m = self.max_m.max(e);
                self.sum_m += e * e;
                self.count_m += 1;
            }
            RowUnit::Angle => self.max_rad = self.max_rad.max(e),
            RowUnit::Dimensionless => self.max_norm = self.max_norm.max(e),
        }
        self.max_scaled_m = self.max_scaled_m.max(s.ell[i] * e);
    }

    /// The statistics of the rows not `evaluated`, at `values`.
    ///
    /// # Real-time
    /// No allocation; O(rows).
    pub fn fixed(model: &Model, s: &Scaling, evaluated: &[bool], values: &[f64]) -> Self {
        let mut st = Self::default();
        for (i, (&c, &e)) in values.iter().zip(evaluated).enumerate() {
            if !e {
                st.add(model, s, i, c);
            }
        }
        st
    }

    /// Whether every row counted is within [`CLOSED`] × `length_m` (scaled
    /// metres: angles and norms times the length).
    pub fn closed(&self, length_m: f64) -> bool {
        self.max_scaled_m <= CLOSED * length_m
    }

    /// These statistics with `rows` at `values` added, as a `Violation`.
    ///
    /// # Real-time
    /// No allocation; O(rows given).
    pub fn with(mut self, model: &Model, s: &Scaling, rows: &[usize], values: &[f64]) -> Violation {
        for &i in rows {
            self.add(model, s, i, values[i]);
        }
        Violation {
            max_m: self.max_m,
            max_rad: self.max_rad,
            max_norm: self.max_norm,
            rms_m: if self.count_m > 0 {
                (self.sum_m / self.count_m as f64).sqrt()
            } else {
                0.0
            },
            max_scaled_m: self.max_scaled_m,
            max_penetration_m: 0.0,
        }
    }
}
