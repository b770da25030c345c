//! Auxiliary coordinates: columns of q that belong to no rigid body and no
//! design variable, with a metric of their own. Two kinds use them: a
//! flexible body's deformation coordinates (`crate::flexible`) and a surface
//! contact's parameters (u, v) (`crate::parametric`).
//!
//! They sit at the end of q, after the design variables, one block per
//! owner. Each block has a constant symmetric positive definite metric H
//! (width × width): the projected update's least-astonishment metric on its
//! columns (the mass matrix's role for a body) and, through H⁻¹, their
//! weight in Eq. 7's least squares (the same factor serves both). Each tick
//! the update's anchor q₀ puts them at their [`Rest`]. A model without
//! auxiliary blocks has none of this: q, C_q's pattern and every solve are
//! what they were.

use nalgebra::DMatrix;

/// Where a block's columns rest in the update's objective ½ (q − q₀)ᵀ H (q − q₀).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Rest {
    /// q₀ = 0: with H = K_f the objective is the strain energy U = ½ qᵀ K_f q
    /// (a flexible body's deformation, Nelson & Cohen Eq. 4).
    Zero,
    /// q₀ = the tick's start (least astonishment: surface parameters).
    Current,
}

/// What owns a block.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AuxOwner {
    /// The deformation columns of a flexible body (index into the model's
    /// flexible bodies).
    Flexible(usize),
    /// The (u, v) columns of a surface contact (index into the model's
    /// surface contacts).
    Surface(usize),
}

/// One block of auxiliary columns.
#[derive(Debug, Clone, PartialEq)]
pub struct AuxBlock {
    /// `"<body>.flex"` or `"<joint>.uv"`.
    pub name: String,
    /// First column in q.
    pub offset: usize,
    /// Number of columns.
    pub width: usize,
    /// Its owner.
    pub owner: AuxOwner,
    /// Where q₀ puts the columns each tick.
    pub rest: Rest,
    /// H, row-major.
    pub(crate) metric: Vec<f64>,
    /// H⁻¹, row-major.
    pub(crate) inv_metric: Vec<f64>,
}

impl AuxBlock {
    /// A block with metric `h` (symmetric positive definite; `None` if it
    /// is not).
    pub(crate) fn new(
        name: String,
        owner: AuxOwner,
        rest: Rest,
        offset: usize,
        h: &DMatrix<f64>,
    ) -> Option<Self> {
        let inv = h.clone().cholesky()?.inverse();
        let row_major = |m: &DMatrix<f64>| m.transpose().as_slice().to_vec();
        Some(Self {
            name,
            offset,
            width: h.nrows(),
            owner,
            rest,
            metric: row_major(h),
            inv_metric: row_major(&inv),
        })
    }

    /// `out = H⁻¹ g` on this block's columns (other entries untouched).
    ///
    /// # Real-time
    /// No allocation; O(width²).
    #[inline]
    pub(crate) fn apply_inverse(&self, g: &[f64], out: &mut [f64]) {
        let (o, w) = (self.offset, self.width);
        for (i, x) in out[o..o + w].iter_mut().enumerate() {
            let row = &self.inv_metric[i * w..(i + 1) * w];
            *x = row.iter().zip(&g[o..o + w]).map(|(a, b)| a * b).sum();
        }
    }

    /// H⁻¹ c for a vector `c` of this block's width, into `out`.
    #[inline]
    pub(crate) fn inverse_times(&self, c: &[f64], out: &mut [f64]) {
        let w = self.width;
        for (i, x) in out.iter_mut().enumerate().take(w) {
            let row = &self.inv_metric[i * w..(i + 1) * w];
            *x = row.iter().zip(c).map(|(a, b)| a * b).sum();
        }
    }

    /// H as a dense matrix.
    pub(crate) fn metric_matrix(&self) -> DMatrix<f64> {
        DMatrix::from_row_slice(self.width, self.width, &self.metric)
    }
}
