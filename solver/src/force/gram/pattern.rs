//! The pattern of A: each row's slot, the per-body and per-auxiliary-block
//! cliques, A_JJ's lower-triangle pattern and every product's destination.
//! Built once per pattern (allocates); the assembly (`gram.rs`) runs over it.

use faer::sparse::SymbolicSparseColMat;
use nalgebra::Matrix4;

use super::{AuxRows, BodyRows, Entry, Gram, NormRow, Slot};
use crate::constraint::Geometry;
use crate::force::inertia::BodyMass;
use crate::{Jacobian, Model};

impl Gram {
    /// [`new`](Self::new), the quaternion-norm rows taken out of their
    /// bodies' cliques where their coupling is zero in exact arithmetic
    /// (`decouple_norms`) or left in (false: the coupled pattern, for the
    /// comparison tests). Allocates.
    pub fn with_norms(
        model: &Model,
        jac: &Jacobian,
        masses: &[BodyMass],
        excluded: &[bool],
        decouple_norms: bool,
    ) -> Self {
        let (slot, finger_rows, j_rows) = slots(model, excluded);
        let (n_j, m_f) = (j_rows.len(), finger_rows.len());
        let Cliques {
            entries,
            mut bodies,
            pairs,
            mut lower,
            dropped,
        } = body_cliques(model, jac, masses, &slot, n_j, decouple_norms);
        // Rows sharing an auxiliary block couple through its metric.
        let aux_pairs = aux_cliques(model, jac, &slot, &mut lower);
        let (cp, ri) = lower_pattern(lower, n_j);
        let dest = Destinations {
            slot: &slot,
            cp: &cp,
            ri: &ri,
            n_j,
            m_f,
        };
        let diag: Vec<usize> = (0..n_j).map(|j| dest.find(j, j)).collect();
        for b in &mut bodies {
            if let Some(n) = &mut b.norm
                && let Slot::J(j) = slot[n.row]
            {
                n.dest = diag[j] as u32;
            }
        }
        let products = pairs
            .iter()
            .map(|&(_, _, ra, rb)| dest.of(ra, rb))
            .collect();
        let aux: Vec<AuxRows> = aux_pairs
            .into_iter()
            .map(|(block, entries)| {
                let mut products = Vec::new();
                for a in 0..entries.len() {
                    for b in 0..=a {
                        products.push(dest.of(entries[a].0, entries[b].0));
                    }
                }
                AuxRows {
                    block,
                    entries,
                    products,
                }
            })
            .collect();
        let nnz = ri.len();
        let aux_blocks = model.layout().aux_blocks().to_vec();
        let aux_cu = vec![
            0.0;
            aux.iter()
                .map(|a| 2 * aux_blocks[a.block].width * a.entries.len())
                .max()
                .unwrap_or(0)
        ];
        let max_entries = bodies.iter().map(|b| b.entries.len()).max().unwrap_or(0);
        let pattern = SymbolicSparseColMat::new_checked(n_j, n_j, cp, None, ri);
        Self {
            slot,
            finger_rows,
            j_rows,
            n_j,
            m_f,
            pattern,
            diag,
            bodies,
            entries,
            products,
            dropped,
            values: vec![0.0; nnz + m_f * n_j + m_f * m_f],
            cu: vec![0.0; 14 * max_entries],
            live: vec![false; max_entries],
            decoupled: vec![false; n_j],
            minv_e: vec![Matrix4::zeros(); masses.len()],
            minv_key: vec![None; masses.len()],
            aux_blocks,
            aux,
            aux_cu,
        }
    }
}

/// Each row's [`Slot`], the finger rows (F order) and the other rows (J
/// order), leaving out the rows `excluded` marks.
fn slots(model: &Model, excluded: &[bool]) -> (Vec<Slot>, Vec<usize>, Vec<usize>) {
    let (mut slot, mut finger_rows, mut j_rows) = (Vec::new(), Vec::new(), Vec::new());
    for (i, row) in model.rows().iter().enumerate() {
        if excluded.get(i).copied().unwrap_or(false) {
            slot.push(Slot::Out);
        } else if model.constraints()[row.constraint.index()].finger.is_some() {
            slot.push(Slot::F(finger_rows.len()));
            finger_rows.push(i);
        } else {
            slot.push(Slot::J(j_rows.len()));
            j_rows.push(i);
        }
    }
    (slot, finger_rows, j_rows)
}

/// The per-body cliques of A before their destinations are known.
struct Cliques {
    entries: Vec<Entry>,
    bodies: Vec<BodyRows>,
    /// (a, b, row of a, row of b) per product, per body (`Gram::products`).
    pairs: Vec<(u32, u32, usize, usize)>,
    /// (row, column) of A_JJ's lower triangle, J indices, with repeats.
    lower: Vec<(usize, usize)>,
    /// `Gram::dropped`.
    dropped: Vec<(usize, usize)>,
}

/// Every moving body's rows and their products (see [`Cliques`]), each
/// body's quaternion-norm row out of its clique where `decouple_norms` and
/// its coupling is zero in exact arithmetic.
fn body_cliques(
    model: &Model,
    jac: &Jacobian,
    masses: &[BodyMass],
    slot: &[Slot],
    n_j: usize,
    decouple_norms: bool,
) -> Cliques {
    let (row_ptr, col_idx) = (jac.row_ptr(), jac.col_idx());
    let (col_ptr, col_rows, col_val) = (jac.col_ptr(), jac.col_rows(), jac.col_value_index());
    let mut c = Cliques {
        entries: Vec::new(),
        bodies: Vec::new(),
        pairs: Vec::new(),
        lower: Vec::new(),
        dropped: Vec::new(),
    };
    for (mass, m) in masses.iter().enumerate() {
        let (o, first, first_pair) = (m.offset, c.entries.len(), c.pairs.len());
        for k in col_ptr[o + 3]..col_ptr[o + 4] {
            let (row, p3) = (col_rows[k], col_val[k]);
            if slot[row] == Slot::Out {
                continue;
            }
            let has_r = p3 >= row_ptr[row] + 3 && col_idx[p3 - 3] == o;
            let (pos, width) = if has_r { (p3 - 3, 7) } else { (p3, 4) };
            c.entries.push(Entry { row, pos, width });
        }
        let norm = if decouple_norms {
            decouple_norm(model, slot, n_j, &mut c.entries, first, &mut c.dropped)
        } else {
            None
        };
        let n = c.entries.len() - first;
        for a in 0..n {
            for b in 0..=a {
                let (ra, rb) = (c.entries[first + a].row, c.entries[first + b].row);
                if let (Slot::J(x), Slot::J(y)) = (slot[ra], slot[rb]) {
                    c.lower.push((x.max(y), x.min(y)));
                }
                c.pairs.push((a as u32, b as u32, ra, rb));
            }
        }
        c.bodies.push(BodyRows {
            mass,
            entries: first..c.entries.len(),
            products: first_pair..c.pairs.len(),
            norm,
        });
    }
    c
}

/// Takes the body's quaternion-norm row (among `entries[first..]`) out of
/// its clique when it is the body's only one, a joint row, and every other
/// row on the body is `Geometry::scale_free_in_e`; notes the pairs left out
/// (J then n_J + F indices) in `dropped`.
fn decouple_norm(
    model: &Model,
    slot: &[Slot],
    n_j: usize,
    entries: &mut Vec<Entry>,
    first: usize,
    dropped: &mut Vec<(usize, usize)>,
) -> Option<NormRow> {
    let geometry = |row: usize| &model.geometry[model.rows()[row].constraint.index()];
    let index = |row: usize| match slot[row] {
        Slot::J(j) => j,
        Slot::F(f) => n_j + f,
        Slot::Out => unreachable!("excluded rows have no entries"),
    };
    let body = &entries[first..];
    let is_norm = |e: &Entry| matches!(geometry(e.row), Geometry::QuatNorm(_));
    if !(body.iter().filter(|e| is_norm(e)).count() == 1
        && body
            .iter()
            .all(|e| is_norm(e) || geometry(e.row).scale_free_in_e()))
    {
        return None;
    }
    let at = first + body.iter().position(is_norm).expect("one norm row");
    let e = entries.remove(at);
    if let Slot::J(j) = slot[e.row] {
        dropped.extend(entries[first..].iter().map(|o| (j, index(o.row))));
        Some(NormRow {
            row: e.row,
            pos: e.pos,
            dest: 0,
        })
    } else {
        entries.insert(at, e);
        None
    }
}

/// Per auxiliary block: its index and its rows (row, value index of the
/// block's first column); the J pairs they couple go into `lower`.
#[allow(clippy::type_complexity)]
fn aux_cliques(
    model: &Model,
    jac: &Jacobian,
    slot: &[Slot],
    lower: &mut Vec<(usize, usize)>,
) -> Vec<(usize, Vec<(usize, usize)>)> {
    let (col_ptr, col_rows, col_val) = (jac.col_ptr(), jac.col_rows(), jac.col_value_index());
    let mut aux_pairs = Vec::new();
    for (k, blk) in model.layout().aux_blocks().iter().enumerate() {
        let o = blk.offset;
        let entries: Vec<(usize, usize)> = (col_ptr[o]..col_ptr[o + 1])
            .map(|p| (col_rows[p], col_val[p]))
            .filter(|&(row, _)| slot[row] != Slot::Out)
            .collect();
        for a in 0..entries.len() {
            for b in 0..=a {
                let (ra, rb) = (entries[a].0, entries[b].0);
                if let (Slot::J(x), Slot::J(y)) = (slot[ra], slot[rb]) {
                    lower.push((x.max(y), x.min(y)));
                }
            }
        }
        aux_pairs.push((k, entries));
    }
    aux_pairs
}

/// The CSC pattern (column pointers, row indices) of A_JJ's lower
/// triangle: the pairs `lower` names and every diagonal.
fn lower_pattern(mut lower: Vec<(usize, usize)>, n_j: usize) -> (Vec<usize>, Vec<usize>) {
    lower.extend((0..n_j).map(|j| (j, j)));
    lower.sort_unstable_by_key(|&(r, c)| (c, r));
    lower.dedup();
    let mut cp = vec![0usize; n_j + 1];
    for &(_, c) in &lower {
        cp[c + 1] += 1;
    }
    for c in 0..n_j {
        cp[c + 1] += cp[c];
    }
    let ri = lower.iter().map(|&(r, _)| r).collect();
    (cp, ri)
}

/// Where a product of two rows goes in `Gram::values`.
struct Destinations<'a> {
    slot: &'a [Slot],
    cp: &'a [usize],
    ri: &'a [usize],
    n_j: usize,
    m_f: usize,
}

impl Destinations<'_> {
    /// The value index of (r, c), r ≥ c, in A_JJ's lower triangle.
    fn find(&self, r: usize, c: usize) -> usize {
        let (cp, ri) = (self.cp, self.ri);
        cp[c] + ri[cp[c]..cp[c + 1]].binary_search(&r).unwrap()
    }

    /// The value index of the product of rows `ra` and `rb`.
    fn of(&self, ra: usize, rb: usize) -> u32 {
        let (nnz, n_j, m_f) = (self.ri.len(), self.n_j, self.m_f);
        (match (self.slot[ra], self.slot[rb]) {
            (Slot::J(x), Slot::J(y)) => self.find(x.max(y), x.min(y)),
            (Slot::F(f), Slot::J(j)) | (Slot::J(j), Slot::F(f)) => nnz + f * n_j + j,
            (Slot::F(x), Slot::F(y)) => nnz + m_f * n_j + x.max(y) * m_f + x.min(y),
            (Slot::Out, _) | (_, Slot::Out) => unreachable!("excluded rows have no entries"),
        }) as u32
    }
}
