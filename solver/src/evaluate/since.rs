//! An evaluation that rewrites only the contact rows whose inputs changed
//! since the Jacobian was last written ("as of which q").
//!
//! A contact row (`constraint::witness`) reads its two bodies' frames and
//! its witness slots, nothing else. The Jacobian's rows were all written by
//! the last Jacobian evaluation, at `q_jac` with the table `w_jac`; a row
//! whose two bodies still have those coordinates and whose slots still hold
//! those witnesses (bit for bit: a table handed over by the slow loop
//! rewrites slots of bodies that did not move) would be rewritten with the
//! same bits, so it is left alone. Its value is left alone too when it was
//! last written from the same inputs (`synced`); value-only evaluations at
//! another q (the projected steps) clear that. On `cluttered` the end-of-tick
//! evaluation then writes the rows of the few bodies the tick moved.
//!
//! The table is private to [`Evaluation`]: [`Evaluation::witnesses_mut`] is
//! its only writer and bumps a counter, so a tick without a handover never
//! compares witnesses.

use crate::constraint::Geometry;
use crate::constraint::witness::{BallWitness, EdgeWitness, LineWitness, PlaneWitness, Witness};
use crate::{Evaluation, Model};
use nalgebra::Vector3;

/// The inputs the Jacobian's rows were written from, and which rows a call
/// can leave alone. Off (and empty) until [`Evaluation::track_unmoved`].
#[derive(Debug, Clone, Default)]
pub(crate) struct Since {
    on: bool,
    /// `q_jac` and `w_jac` hold the inputs of every Jacobian row.
    known: bool,
    q_jac: Vec<f64>,
    w_jac: Vec<Witness>,
    /// Bumped by every `witnesses_mut`; `seen` when `wdiff` was computed.
    table: u64,
    seen: u64,
    /// Per constraint: its slots differ from `w_jac` (contacts only).
    wdiff: Vec<bool>,
    /// Per constraint: its values were written from `q_jac` and `w_jac`.
    synced: Vec<bool>,
    /// Per constraint: inputs equal `q_jac` and `w_jac` (contacts only).
    same: Vec<bool>,
    /// Per frame: coordinates differ from `q_jac`.
    moved: Vec<bool>,
    /// Moving bodies: frame index and first column.
    bodies: Vec<(usize, usize)>,
    /// Contact constraints: index, the two frames, the slot range.
    contacts: Vec<(usize, [usize; 2], std::ops::Range<usize>)>,
    /// Contact constraints left alone by Jacobian evaluations, summed.
    pub(super) skipped: u64,
}

impl Since {
    /// True where the shortcut applies: contact rows, no design variables,
    /// freed origins or flexible anchors (rows that read q elsewhere).
    fn applies(model: &Model) -> bool {
        let layout = model.layout();
        model
            .geometry
            .iter()
            .any(|g| matches!(g, Geometry::Contact(_)))
            && layout.design_vars().is_empty()
            && layout.origin_cols.iter().all(Option::is_none)
            && model.flex_anchors.is_empty()
    }

    fn build(model: &Model, table: usize) -> Self {
        let n = model.geometry.len();
        let contacts = model
            .geometry
            .iter()
            .enumerate()
            .filter_map(|(k, g)| match g {
                Geometry::Contact(c) => {
                    // Slots past the table read `Off` (`ContactRows::eval`).
                    let s = (c.first_slot as usize).min(table);
                    Some((k, c.pair.frame, s..(s + c.rows as usize).min(table)))
                }
                _ => None,
            })
            .collect();
        Self {
            on: true,
            q_jac: vec![0.0; model.n_coords()],
            w_jac: vec![Witness::Off; table],
            wdiff: vec![false; n],
            synced: vec![false; n],
            same: vec![false; n],
            // Fixed bodies and the world never move; `mark` sets the others.
            moved: vec![false; model.bodies().len() + 1],
            bodies: model
                .layout()
                .moving_bodies()
                .map(|(b, o)| (b.index(), o))
                .collect(),
            contacts,
            ..Self::default()
        }
    }

    pub(super) fn on(&self) -> bool {
        self.on
    }

    pub(super) fn touch(&mut self) {
        self.table = self.table.wrapping_add(1);
    }

    /// Marks constraint `k`'s values as written from other inputs.
    #[inline]
    pub(super) fn unsync(&mut self, k: usize) {
        if let Some(s) = self.synced.get_mut(k) {
            *s = false;
        }
    }

    /// Fills `same` for a call at `q` with `table`.
    ///
    /// # Real-time
    /// No allocation; O(coordinates + contact constraints), plus the
    /// witness comparisons after a table change.
    pub(super) fn mark(&mut self, q: &[f64], table: &[Witness]) {
        if !self.known {
            self.same.fill(false);
            return;
        }
        for &(f, o) in &self.bodies {
            self.moved[f] = q[o..o + 7] != self.q_jac[o..o + 7];
        }
        if self.seen != self.table {
            for (k, _, slots) in &self.contacts {
                let (now, then) = (&table[slots.clone()], &self.w_jac[slots.clone()]);
                self.wdiff[*k] = !now.iter().zip(then).all(|(a, b)| same_bits(a, b));
            }
            self.seen = self.table;
        }
        for (k, [f0, f1], _) in &self.contacts {
            self.same[*k] = !self.moved[*f0] && !self.moved[*f1] && !self.wdiff[*k];
        }
    }

    /// Constraint `k` needs no writing: a contact with unchanged inputs
    /// whose values were written from them.
    #[inline]
    pub(super) fn keeps(&self, k: usize) -> bool {
        self.same[k] && self.synced[k]
    }

    /// After a value-only write of constraint `k` (at the marked q).
    #[inline]
    pub(super) fn wrote_value(&mut self, k: usize) {
        self.synced[k] = self.same[k];
    }

    /// After a Jacobian call at `q` with `table` that wrote every constraint
    /// `keeps` did not leave alone.
    pub(super) fn wrote_jacobian(&mut self, q: &[f64], table: &[Witness]) {
        let mut kept = 0;
        for (k, _, slots) in &self.contacts {
            if self.known && self.keeps(*k) {
                kept += 1;
            } else {
                self.w_jac[slots.clone()].copy_from_slice(&table[slots.clone()]);
            }
            self.wdiff[*k] = false;
        }
        self.synced.fill(true);
        self.q_jac.copy_from_slice(q);
        self.known = true;
        self.seen = self.table;
        self.skipped += kept;
    }
}

impl Evaluation {
    /// Makes [`evaluate`](Self::evaluate) and
    /// [`evaluate_values`](Self::evaluate_values) leave alone the contact
    /// rows whose bodies and witnesses are unchanged since they were written
    /// (`on`, where the model allows it: contact rows, no design variables,
    /// freed origins or flexible anchors), or write every row. The same
    /// values and Jacobian bit for bit either way.
    ///
    /// Allocates the first time it is turned on; no-op when unchanged.
    pub fn track_unmoved(&mut self, model: &Model, on: bool) {
        let on = on && Since::applies(model);
        if on == self.since.on() {
            return;
        }
        if on && self.since.q_jac.len() == model.n_coords() {
            self.since.on = true;
            self.since.known = false;
        } else if on {
            self.since = Since::build(model, self.witnesses.len());
        } else {
            self.since.on = false;
            self.since.known = false;
        }
    }

    /// Contact constraints the Jacobian evaluations left alone, summed
    /// over this evaluation's life.
    pub fn unmoved_contacts_skipped(&self) -> u64 {
        self.since.skipped
    }
}

/// `a` and `b` are the same bits (`==` would take -0.0 for 0.0, which can
/// flip the sign of a zero in a row).
fn same_bits(a: &Witness, b: &Witness) -> bool {
    match (a, b) {
        (Witness::Off, Witness::Off) => true,
        (Witness::Plane(a), Witness::Plane(b)) => plane_key(a) == plane_key(b),
        (Witness::Ball(a), Witness::Ball(b)) => ball_key(a) == ball_key(b),
        (Witness::Line(a), Witness::Line(b)) => line_key(a) == line_key(b),
        (Witness::EdgeEdge(a), Witness::EdgeEdge(b)) => edge_key(a) == edge_key(b),
        _ => false,
    }
}

type Head = (crate::constraint::witness::WitnessType, [u32; 2], u8);

fn bits<const N: usize>(v: [&Vector3<f64>; N], m: f64) -> ([[u64; 3]; N], u64) {
    (
        v.map(|v| [v.x.to_bits(), v.y.to_bits(), v.z.to_bits()]),
        m.to_bits(),
    )
}

// Exhaustive destructuring: a field added to a witness fails to compile here.
fn plane_key(w: &PlaneWitness) -> (Head, ([[u64; 3]; 3], u64)) {
    let PlaneWitness {
        origin,
        features,
        point_end,
        point,
        plane_point,
        normal,
        margin,
    } = w;
    (
        (*origin, *features, *point_end),
        bits([point, plane_point, normal], *margin),
    )
}

fn ball_key(w: &BallWitness) -> (Head, ([[u64; 3]; 3], u64)) {
    let BallWitness {
        origin,
        features,
        point_a,
        point_b,
        fallback,
        margin,
    } = w;
    (
        (*origin, *features, 0),
        bits([point_a, point_b, fallback], *margin),
    )
}

fn line_key(w: &LineWitness) -> (Head, ([[u64; 3]; 4], u64)) {
    let LineWitness {
        origin,
        features,
        point_end,
        point,
        line_point,
        line_dir,
        fallback,
        margin,
    } = w;
    (
        (*origin, *features, *point_end),
        bits([point, line_point, line_dir, fallback], *margin),
    )
}

fn edge_key(w: &EdgeWitness) -> (Head, ([[u64; 3]; 5], u64)) {
    let EdgeWitness {
        origin,
        features,
        edge_end,
        edge_point,
        edge_dir,
        face_point,
        face_normal,
        sep_normal,
        margin,
    } = w;
    (
        (*origin, *features, *edge_end),
        bits(
            [edge_point, edge_dir, face_point, face_normal, sep_normal],
            *margin,
        ),
    )
}
