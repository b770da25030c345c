//! The scaled Gram matrix A = D C_q M̃⁻¹ C_qᵀ D of the Eq. 7 multiplier
//! solve, assembled in place over a pattern fixed at construction.
//!
//! Rows split into J (every non-finger row: joints, quaternion norms,
//! inequalities) and F (finger rows). A_JJ is stored as the lower triangle of
//! a sparse CSC matrix (the input of the sparse Cholesky); A_FJ (m_f × n_J,
//! row-major) and A_FF (m_f × m_f, lower triangle then mirrored) are dense
//! (m_f is 3 or 6 per finger). Two rows couple iff they share a moving body,
//! so the pattern is a union of dense per-body cliques: for each body the
//! assembly forms c_a and u_a = M̃_b⁻¹ c_a for every row a touching it (c_a:
//! the row's 7 or 4 Jacobian values on the body's columns, times the row's
//! scale) and adds c_a · u_b to each precomputed destination. Design-variable
//! columns have no inertia: they are frozen in Eq. 7 (M⁻¹ = 0 there).
//! Auxiliary blocks (flexible deformations, surface parameters;
//! `model::auxiliary`) have their metric H: the rows touching a block add
//! c_a · H⁻¹ c_b over its columns, in a pass of their own that a model
//! without such blocks never runs.

use faer::sparse::SymbolicSparseColMat;
use nalgebra::{Matrix4, Vector3, Vector4};

use super::inertia::BodyMass;
use crate::Jacobian;
use crate::rotation::BodyFrame;

/// The pattern and destinations, built once (`Gram::with_norms`).
mod pattern;

/// Where a row of C goes in the solve.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Slot {
    /// Index among the non-finger rows.
    J(usize),
    /// Index among the finger rows.
    F(usize),
    /// Left out of the solve altogether (a row found dependent before A is
    /// built: it has no place in A's pattern).
    Out,
}

/// One row touching one body: its first value index on the body's columns.
#[derive(Debug, Clone, Copy)]
struct Entry {
    row: usize,
    pos: usize,
    /// 7 (r and e) or 4 (e only: quaternion-norm rows).
    width: usize,
}

/// The rows touching one auxiliary block and where their products go.
#[derive(Debug, Clone)]
struct AuxRows {
    /// Index into the model's auxiliary blocks.
    block: usize,
    /// (row, value index of the block's first column in that row).
    entries: Vec<(usize, usize)>,
    /// Destination of c_a · H⁻¹ c_b for (a, b), b ≤ a, in that order.
    products: Vec<u32>,
}

#[derive(Debug, Clone)]
struct BodyRows {
    mass: usize,
    entries: std::ops::Range<usize>,
    products: std::ops::Range<usize>,
    /// The body's quaternion-norm row when it is out of the clique (every
    /// other row on the body is `Geometry::scale_free_in_e`): A's only
    /// entry in its row and column is its diagonal.
    norm: Option<NormRow>,
}

/// A quaternion-norm row decoupled from its body's clique: its Jacobian's
/// first value (4 values, on e) and its diagonal's value index.
#[derive(Debug, Clone, Copy)]
struct NormRow {
    row: usize,
    pos: usize,
    dest: u32,
}

/// Pattern, destinations and values of A (see the module docs).
#[derive(Debug, Clone)]
pub(crate) struct Gram {
    pub slot: Vec<Slot>,
    /// Finger rows in F order.
    pub finger_rows: Vec<usize>,
    /// Non-finger rows in J order.
    pub j_rows: Vec<usize>,
    pub n_j: usize,
    pub m_f: usize,
    /// Lower triangle of A_JJ.
    pub pattern: SymbolicSparseColMat<usize>,
    /// Value index of each J row's diagonal.
    pub diag: Vec<usize>,
    bodies: Vec<BodyRows>,
    entries: Vec<Entry>,
    /// Where each product c_a · u_b of two local entries of a body goes, per
    /// body in the order (a, b) for a = 0, 1, … and b = 0..=a.
    products: Vec<u32>,
    /// (norm row, other row) pairs (J indices, then n_J + F index) of the
    /// coupled pattern that this one leaves out: entries zero in exact
    /// arithmetic (`Geometry::scale_free_in_e`).
    dropped: Vec<(usize, usize)>,
    /// `[A_JJ lower (nnz) | A_FJ (m_f × n_J) | A_FF (m_f × m_f)]`.
    pub values: Vec<f64>,
    /// c and u of one body's entries (14 per entry).
    cu: Vec<f64>,
    /// Per entry of the body being assembled: its row takes part (scale ≠ 0).
    live: Vec<bool>,
    /// Per joint row (J order): switched off in the last assembly (scale
    /// 0), so nothing couples it: the factor can skip it
    /// (`Cholesky::factor_decoupled`).
    pub decoupled: Vec<bool>,
    /// M̃_e⁻¹ of each body (layout order) at the last assembly.
    minv_e: Vec<Matrix4<f64>>,
    /// The bits `minv_e[k]` was computed from (Euler parameters, inverse
    /// principal inertia, norm mass), `None` before the first: a body whose
    /// rotation and mass did not change since keeps its M̃_e⁻¹ without
    /// recomputing it (the same bits; on `cluttered` most bodies rest).
    minv_key: Vec<Option<[u64; 8]>>,
    /// The model's auxiliary blocks (metric and columns).
    aux_blocks: Vec<crate::model::AuxBlock>,
    /// Their rows (empty for a model without auxiliary columns).
    aux: Vec<AuxRows>,
    /// c and H⁻¹ c of one block's entries (2 × width per entry).
    aux_cu: Vec<f64>,
}

impl Gram {
    /// The pivot regularisation every factor of this matrix uses: a pivot
    /// at most 1e-14 of the largest diagonal is replaced by 1e-10 of it.
    pub(crate) fn regularization(&self) -> crate::cholesky::Regularization {
        let max_diag = self
            .diag
            .iter()
            .map(|&d| self.values[d])
            .fold(0.0, f64::max);
        crate::cholesky::Regularization {
            delta: 1e-10 * max_diag,
            epsilon: 1e-14 * max_diag,
        }
    }

    /// The pattern of `model`'s A from its Jacobian pattern, without the rows
    /// `excluded` marks (empty: none). Allocates.
    #[cfg(test)]
    pub fn new(
        model: &crate::Model,
        jac: &Jacobian,
        masses: &[BodyMass],
        excluded: &[bool],
    ) -> Self {
        Self::with_norms(model, jac, masses, excluded, true)
    }

    /// Number of stored values of A_JJ's lower triangle.
    pub fn nnz(&self) -> usize {
        self.pattern.row_idx().len()
    }

    /// The J rows (J indices) touching each moving body: A_JJ is the union
    /// of these cliques (the nested dissection splits along them).
    /// Allocates.
    pub fn cliques(&self) -> Vec<Vec<usize>> {
        self.bodies
            .iter()
            .map(|b| {
                self.entries[b.entries.clone()]
                    .iter()
                    .filter_map(|e| match self.slot[e.row] {
                        Slot::J(j) => Some(j),
                        _ => None,
                    })
                    .collect()
            })
            .collect()
    }

    /// [`cliques`](Self::cliques) with each decoupled quaternion-norm row
    /// back in its body's clique (the coupled pattern's). Allocates.
    pub fn coupled_cliques(&self) -> Vec<Vec<usize>> {
        let mut out = self.cliques();
        for (c, b) in out.iter_mut().zip(&self.bodies) {
            if let Some(n) = b.norm
                && let Slot::J(j) = self.slot[n.row]
            {
                c.push(j);
            }
        }
        out
    }

    /// The lower-triangle entries (row, column, no value: `usize::MAX`) of
    /// the coupled pattern that this one leaves out, in
    /// [`factor_entries`](Self::factor_entries)' indices: each decoupled
    /// norm row with every other row on its body. Allocates.
    pub fn dropped_entries(&self) -> Vec<(usize, usize, usize)> {
        (self.dropped.iter())
            .map(|&(a, b)| (a.max(b), a.min(b), usize::MAX))
            .collect()
    }

    /// Per decoupled norm row: its body's r column and the value index of
    /// its first Jacobian value (`masses`: the bodies' mass data this
    /// Gram was built with). Allocates.
    pub fn norm_checks(&self, masses: &[BodyMass]) -> Vec<(usize, usize)> {
        (self.bodies.iter())
            .filter_map(|b| b.norm.map(|n| (masses[b.mass].offset, n.pos)))
            .collect()
    }

    /// Rows out of their body's clique (the decoupled quaternion norms).
    #[cfg(test)]
    pub fn decoupled_norms(&self) -> usize {
        self.bodies.iter().filter(|b| b.norm.is_some()).count()
    }

    /// The whole (n_J + m_f)-square matrix's lower triangle as (row, column,
    /// index in `values`), J rows first then F rows: A_JJ's pattern, the
    /// entries of A_FJ the assembly can write (rows sharing a body with a
    /// finger), and all of A_FF's lower triangle. Allocates.
    pub fn factor_entries(&self) -> Vec<(usize, usize, usize)> {
        let (nnz, n_j, m_f) = (self.nnz(), self.n_j, self.m_f);
        let (cp, ri) = (self.pattern.col_ptr(), self.pattern.row_idx());
        let mut e: Vec<(usize, usize, usize)> = (0..n_j)
            .flat_map(|c| (cp[c]..cp[c + 1]).map(move |p| (ri[p], c, p)))
            .collect();
        let mut fj: Vec<usize> = self
            .products
            .iter()
            .chain(self.aux.iter().flat_map(|a| &a.products))
            .map(|&d| d as usize)
            .filter(|&d| d >= nnz && d < nnz + m_f * n_j)
            .collect();
        fj.sort_unstable();
        fj.dedup();
        e.extend(
            fj.iter()
                .map(|&d| (n_j + (d - nnz) / n_j, (d - nnz) % n_j, d)),
        );
        for f in 0..m_f {
            for g in 0..=f {
                e.push((n_j + f, n_j + g, nnz + m_f * n_j + f * m_f + g));
            }
        }
        e
    }

    /// out = M̃⁻¹ g at the configuration of the last assembly (zero on
    /// design-variable columns, which have no inertia).
    ///
    /// # Real-time
    /// No allocation; O(coordinates).
    pub fn apply_inverse_mass(&self, masses: &[BodyMass], g: &[f64], out: &mut [f64]) {
        out.fill(0.0);
        for (m, minv) in masses.iter().zip(&self.minv_e) {
            let o = m.offset;
            for c in 0..3 {
                out[o + c] = g[o + c] / m.mass;
            }
            let ge = Vector4::new(g[o + 3], g[o + 4], g[o + 5], g[o + 6]);
            out[o + 3..o + 7].copy_from_slice((minv * ge).as_slice());
        }
        for blk in &self.aux_blocks {
            blk.apply_inverse(g, out);
        }
    }

    /// Assembles A with row `i` scaled by `scale[i]` (ℓ_i, or 0 to drop an
    /// inactive row), and y = M̃⁻¹ b (design-variable entries 0).
    ///
    /// # Real-time
    /// No allocation; O(Σ_bodies rows_b²) products of length 7, fewer when
    /// rows are dropped (inactive limits and contacts cost nothing).
    pub fn assemble(
        &mut self,
        q: &[f64],
        jac: &Jacobian,
        scale: &[f64],
        masses: &[BodyMass],
        b: &[f64],
        y: &mut [f64],
    ) {
        self.values.fill(0.0);
        y.fill(0.0);
        for (d, &row) in self.decoupled.iter_mut().zip(&self.j_rows) {
            *d = scale[row] == 0.0;
        }
        let vals = jac.values();
        for body in &self.bodies {
            let m = &masses[body.mass];
            let o = m.offset;
            let k = body.mass;
            let Some(minv) = body_minv(&mut self.minv_e[k], &mut self.minv_key[k], m, q) else {
                continue;
            };
            for c in 0..3 {
                y[o + c] = b[o + c] / m.mass;
            }
            let be = Vector4::new(b[o + 3], b[o + 4], b[o + 5], b[o + 6]);
            y[o + 3..o + 7].copy_from_slice((minv * be).as_slice());
            if let Some(n) = body.norm {
                // Its only entry: the diagonal (c · M̃_e⁻¹ c, summed as the
                // clique's products are).
                let s = scale[n.row];
                if s != 0.0 {
                    let v = &vals[n.pos..n.pos + 4];
                    let c = Vector4::new(v[0] * s, v[1] * s, v[2] * s, v[3] * s);
                    let u = minv * c;
                    let mut acc = 0.0;
                    for i in 0..4 {
                        acc += c[i] * u[i];
                    }
                    self.values[n.dest as usize] += acc;
                }
            }
            let entries = &self.entries[body.entries.clone()];
            for (k, ent) in entries.iter().enumerate() {
                let s = scale[ent.row];
                // A dropped row (scale 0) contributes nothing: no products.
                self.live[k] = s != 0.0;
                if s == 0.0 {
                    continue;
                }
                let cu = &mut self.cu[14 * k..14 * k + 14];
                let src = &vals[ent.pos..ent.pos + ent.width];
                let (c, u) = cu.split_at_mut(7);
                c.fill(0.0);
                for (d, v) in c[7 - ent.width..].iter_mut().zip(src) {
                    *d = v * s;
                }
                for i in 0..3 {
                    u[i] = c[i] / m.mass;
                }
                let ue = minv * Vector4::new(c[3], c[4], c[5], c[6]);
                u[3..].copy_from_slice(ue.as_slice());
            }
            // Products in the order `new` listed them: (a, b) for b ≤ a.
            let products = &self.products[body.products.clone()];
            let mut first = 0;
            for a in 0..entries.len() {
                if self.live[a] {
                    let ca: &[f64; 7] = self.cu[14 * a..14 * a + 7]
                        .try_into()
                        .expect("seven values");
                    for (b, &dest) in products[first..=first + a].iter().enumerate() {
                        if !self.live[b] {
                            continue;
                        }
                        let ub: &[f64; 7] = self.cu[14 * b + 7..14 * b + 14]
                            .try_into()
                            .expect("seven values");
                        let mut acc = 0.0;
                        for i in 0..7 {
                            acc += ca[i] * ub[i];
                        }
                        self.values[dest as usize] += acc;
                    }
                }
                first += a + 1;
            }
        }
        if !self.aux.is_empty() {
            self.assemble_aux(jac, scale, b, y);
        }
        let (nnz, m_f, n_j) = (self.nnz(), self.m_f, self.n_j);
        let ff = &mut self.values[nnz + m_f * n_j..];
        for x in 0..m_f {
            for z in 0..x {
                ff[z * m_f + x] = ff[x * m_f + z];
            }
        }
    }
}

impl Gram {
    /// The auxiliary blocks' share of A (c_a · H⁻¹ c_b per pair of rows on
    /// a block) and of y = M̃⁻¹ b (H⁻¹ b on the block's columns).
    ///
    /// # Real-time
    /// No allocation; O(Σ_blocks rows² · width + rows · width²).
    fn assemble_aux(&mut self, jac: &Jacobian, scale: &[f64], b: &[f64], y: &mut [f64]) {
        let vals = jac.values();
        for a in &self.aux {
            let blk = &self.aux_blocks[a.block];
            let w = blk.width;
            blk.apply_inverse(b, y);
            for (k, &(row, pos)) in a.entries.iter().enumerate() {
                let s = scale[row];
                let cu = &mut self.aux_cu[2 * w * k..2 * w * (k + 1)];
                let (c, u) = cu.split_at_mut(w);
                for (d, v) in c.iter_mut().zip(&vals[pos..pos + w]) {
                    *d = v * s;
                }
                blk.inverse_times(c, u);
            }
            let mut next = 0;
            for x in 0..a.entries.len() {
                for z in 0..=x {
                    let dest = a.products[next] as usize;
                    next += 1;
                    let c = &self.aux_cu[2 * w * x..2 * w * x + w];
                    let u = &self.aux_cu[2 * w * z + w..2 * w * (z + 1)];
                    let acc: f64 = c.iter().zip(u).map(|(p, q)| p * q).sum();
                    if acc != 0.0 {
                        self.values[dest] += acc;
                    }
                }
            }
        }
    }
}

/// M̃_e⁻¹ of body `m` at `q` into `minv_e`: recomputed only when
/// its Euler parameters or its mass changed bit for bit since the last
/// time (`None`, and the entry untouched, for a degenerate rotation).
///
/// # Real-time
/// No allocation; O(1).
#[inline]
fn body_minv(
    minv_e: &mut Matrix4<f64>,
    minv_key: &mut Option<[u64; 8]>,
    m: &BodyMass,
    q: &[f64],
) -> Option<Matrix4<f64>> {
    let o = m.offset;
    let e = Vector4::new(q[o + 3], q[o + 4], q[o + 5], q[o + 6]);
    let j = &m.inv_inertia;
    let key = [
        e[0].to_bits(),
        e[1].to_bits(),
        e[2].to_bits(),
        e[3].to_bits(),
        j.x.to_bits(),
        j.y.to_bits(),
        j.z.to_bits(),
        m.norm_mass.to_bits(),
    ];
    if *minv_key == Some(key) {
        return Some(*minv_e);
    }
    // The frame's rotation reads e only; its position is not used.
    let Some(frame) = BodyFrame::new(Vector3::zeros(), [e[0], e[1], e[2], e[3]]) else {
        *minv_key = None;
        return None;
    };
    let minv = m.inv_rotational_mass(&frame, &e);
    *minv_e = minv;
    *minv_key = Some(key);
    Some(minv)
}

#[cfg(test)]
mod tests;
