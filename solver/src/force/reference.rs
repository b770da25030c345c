//! The exact, dense reference for the finger wrenches of Eq. 7–8: for tests,
//! and for the slow thread to measure the fast loop's force error. Allocates
//! freely; O(n³) in the number of body coordinates.
//!
//! It solves the same physics as the fast path ([`super::solve`]) by a
//! different route, the null-space method: with T an orthonormal basis of the
//! motions the joints allow (null(C_J), by SVD) and R = Tᵀ M T, the finger
//! multipliers are the minimum-norm least-squares solution of
//!
//! ```text
//! L⁻¹ Tᵀ C_Fᵀ λ_F ≈ L⁻¹ Tᵀ b,     R = L Lᵀ,   b = Q_e + Q_v − M q̈
//! ```
//!
//! i.e. the smallest finger load that balances b along every free motion, with
//! any imbalance measured in the kinetic-energy metric (angle rows of a rigid
//! grasp scaled to metres by the model's characteristic length, as in the fast
//! path). Design variables are frozen (no inertia). Auxiliary columns
//! (flexible deformations) take part with their metric (K_f, as in the
//! fast path) and their generalized force (−K_f q_f − M_f q̈_f + g_f).

use nalgebra::{DMatrix, DVector, Quaternion, UnitQuaternion, Vector3, Vector4};

use super::inertia::{BodyMass, angular_motion};
use super::wrench::on_finger;
use crate::rotation::BodyFrame;
use crate::{EvalError, FingerId, FingerTarget, Model, RowUnit, Sense};

/// Tolerance of the inequality active sets, metres or radians. The reference
/// counts a row as active (carrying load in Eq. 7) when C ≤ this. A
/// [`Program`](crate::Program), which knows each row's multiplier ν, when
/// ν > 0 or C < −this (violated): a row resting exactly on its bound without
/// load is free to leave it.
pub const INEQUALITY_ACTIVE_BAND: f64 = 1e-6;

/// The wrench a mechanism exerts on one finger.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FingerWrench {
    /// The finger.
    pub finger: FingerId,
    /// Force on the finger, newtons, world frame.
    pub force_n: Vector3<f64>,
    /// Torque on the finger about its attachment point, N·m, world frame (zero
    /// for a point grasp).
    pub torque_nm: Vector3<f64>,
}

/// Why the reference could not be computed.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum ReferenceError {
    /// A vector has the wrong length.
    #[error("{what} has {got} entries; the model has {expected} coordinates")]
    Length {
        /// `q`, `q_dot` or `q_ddot`.
        what: &'static str,
        /// Coordinates of the model.
        expected: usize,
        /// Entries given.
        got: usize,
    },
    /// C or C_q could not be evaluated at q.
    #[error("evaluation failed: {0}")]
    Eval(#[from] EvalError),
    /// A motion the joints allow moves no mass (R = Tᵀ M T is singular).
    #[error("a free motion of the mechanism carries no mass")]
    Massless,
}

/// The wrench on every finger (model finger order) at configuration `q` with
/// augmented velocities `q_dot` and accelerations `q_ddot` (e-parts are ė, ë),
/// each finger exactly holding its attachment point (targets at q).
pub fn reference_finger_wrenches(
    model: &Model,
    q: &[f64],
    q_dot: &[f64],
    q_ddot: &[f64],
) -> Result<Vec<FingerWrench>, ReferenceError> {
    let n = model.n_coords();
    for (what, v) in [("q", q), ("q_dot", q_dot), ("q_ddot", q_ddot)] {
        if v.len() != n {
            return Err(ReferenceError::Length {
                what,
                expected: n,
                got: v.len(),
            });
        }
    }
    let mut ev = model.evaluation();
    ev.anchor_rolling(model, q);
    ev.evaluate(model, q, &holding_targets(model, q))?;
    let cq = ev.jacobian().to_dense();
    let motion = Motion { q, q_dot, q_ddot };
    let dense = Dense::new(model, &motion, cq)?;
    let (j_rows, f_rows) = partition_rows(model, ev.values());
    let lambda_f = dense.finger_multipliers(model, &j_rows, &f_rows)?;
    finger_wrenches(model, q, &dense.cq, &lambda_f)
}

/// The body frame of the body whose coordinates start at `o` in `q`.
fn frame_at(q: &[f64], o: usize) -> Result<BodyFrame, ReferenceError> {
    BodyFrame::new(
        Vector3::new(q[o], q[o + 1], q[o + 2]),
        [q[o + 3], q[o + 4], q[o + 5], q[o + 6]],
    )
    .ok_or(EvalError::NonFiniteCoordinate { index: o + 3 }.into())
}

/// Each finger exactly holds its attachment point (and, rigid, its body's
/// orientation); a degenerate e fails in `evaluate`.
fn holding_targets(model: &Model, q: &[f64]) -> Vec<FingerTarget> {
    model
        .fingers()
        .iter()
        .enumerate()
        .map(|(k, f)| {
            let o = model.layout().body_offset(f.body).unwrap_or(0);
            FingerTarget {
                position_m: model
                    .finger_point(q, FingerId(k as u32))
                    .unwrap_or(Vector3::zeros()),
                orientation: UnitQuaternion::new_normalize(Quaternion::new(
                    q[o + 3],
                    q[o + 4],
                    q[o + 5],
                    q[o + 6],
                )),
            }
        })
        .collect()
}

/// Configuration, augmented velocities and accelerations.
struct Motion<'a> {
    q: &'a [f64],
    q_dot: &'a [f64],
    q_ddot: &'a [f64],
}

/// The dense system over the columns with a metric.
struct Dense {
    /// C_q, every row and column of the model.
    cq: DMatrix<f64>,
    /// The columns with a metric: the bodies', then the auxiliary blocks'.
    cols: Vec<usize>,
    /// The metric over `cols`: M of the bodies, K_f of the auxiliary blocks.
    m: DMatrix<f64>,
    /// b = Q_e + Q_v − M q̈ over `cols` (auxiliary: −K_f q_f − M_f q̈_f + g_f).
    b: DVector<f64>,
}

impl Dense {
    /// The metric and generalized force of `model` at `motion`, with its C_q.
    fn new(model: &Model, motion: &Motion, cq: DMatrix<f64>) -> Result<Self, ReferenceError> {
        let Motion { q, q_dot, q_ddot } = *motion;
        let nb0 = model.layout().body_coords();
        // The columns with a metric: the bodies', then the auxiliary blocks'
        // (flexible deformations: metric K_f, b = −K_f q_f − M_f q̈_f + g_f).
        let cols: Vec<usize> = (0..nb0)
            .chain(
                model
                    .layout()
                    .aux_blocks()
                    .iter()
                    .flat_map(|a| a.offset..a.offset + a.width),
            )
            .collect();
        let nb = cols.len();
        let g = model.gravity_m_s2();
        let (mut m, mut b) = (DMatrix::zeros(nb, nb), DVector::zeros(nb));
        let mut at = nb0;
        for a in model.layout().aux_blocks() {
            m.view_mut((at, at), (a.width, a.width))
                .copy_from(&a.metric_matrix());
            at += a.width;
        }
        let mut flex_b = vec![0.0; model.n_coords()];
        for fb in &model.flexible {
            let o = model.layout().body_offset(fb.body).unwrap_or(0);
            let f = frame_at(q, o)?;
            let (c, w) = (fb.col, fb.width());
            fb.generalized_force(q, &f.rot, &g, &q_ddot[c..c + w], &mut flex_b[c..c + w]);
        }
        for (k, &c) in cols.iter().enumerate().skip(nb0) {
            b[k] = flex_b[c];
        }
        for bm in &BodyMass::of_model(model) {
            let o = bm.offset;
            let f = frame_at(q, o)?;
            let v4 = |x: &[f64]| Vector4::new(x[o + 3], x[o + 4], x[o + 5], x[o + 6]);
            let (w, alpha) = angular_motion(&f, &v4(q), &v4(q_dot), &v4(q_ddot));
            let a = Vector3::new(q_ddot[o], q_ddot[o + 1], q_ddot[o + 2]);
            let mut out = [0.0; 7];
            bm.generalized_force(&f, &g, &a, &w, &alpha, &mut out);
            b.rows_mut(o, 7).copy_from_slice(&out);
            m.view_mut((o, o), (3, 3)).fill_diagonal(bm.mass);
            m.view_mut((o + 3, o + 3), (4, 4))
                .copy_from(&bm.rotational_mass(&f));
        }
        Ok(Self { cq, cols, m, b })
    }

    /// An orthonormal basis T of the null space of C_J (the joint rows
    /// `j_rows` over `cols`), by SVD: right singular vectors of C_J padded
    /// with zero rows to a square matrix, so the SVD returns all of V. `None`
    /// when the joints allow no motion.
    fn free_motions(&self, j_rows: &[usize]) -> Option<DMatrix<f64>> {
        let nb = self.cols.len();
        let mut padded = DMatrix::zeros(j_rows.len().max(nb), nb);
        for (k, &i) in j_rows.iter().enumerate() {
            for (x, &c) in self.cols.iter().enumerate() {
                padded[(k, x)] = self.cq[(i, c)];
            }
        }
        let svd = padded.svd(false, true);
        let vt = svd.v_t.expect("requested");
        let top = svd.singular_values.max();
        let free: Vec<usize> = (0..nb)
            .filter(|&k| svd.singular_values[k] <= 1e-10 * top)
            .collect();
        (!free.is_empty()).then(|| DMatrix::from_fn(nb, free.len(), |r, k| vt[(free[k], r)]))
    }

    /// λ_F: the minimum-norm least-squares solution of L⁻¹ Tᵀ C_Fᵀ λ_F ≈
    /// L⁻¹ Tᵀ b (R = Tᵀ M T = L Lᵀ), angle rows scaled to metres by the
    /// model's characteristic length; zero when the joints allow no motion.
    fn finger_multipliers(
        &self,
        model: &Model,
        j_rows: &[usize],
        f_rows: &[usize],
    ) -> Result<DVector<f64>, ReferenceError> {
        let nb = self.cols.len();
        let Some(t) = self.free_motions(j_rows) else {
            return Ok(DVector::zeros(f_rows.len()));
        };
        let chol = (t.transpose() * &self.m * &t)
            .cholesky()
            .ok_or(ReferenceError::Massless)?;
        let l = chol.l();
        let ell = model.characteristic_length_m();
        let scale: Vec<f64> = f_rows
            .iter()
            .map(|&i| {
                if model.rows()[i].unit == RowUnit::Length {
                    1.0
                } else {
                    ell
                }
            })
            .collect();
        let cf = DMatrix::from_fn(nb, f_rows.len(), |r, k| {
            self.cq[(f_rows[k], self.cols[r])] * scale[k]
        });
        let lhs = l
            .solve_lower_triangular(&(t.transpose() * cf))
            .ok_or(ReferenceError::Massless)?;
        let rhs = l
            .solve_lower_triangular(&(t.transpose() * &self.b))
            .ok_or(ReferenceError::Massless)?;
        let scaled = min_norm_solve(&lhs, &rhs, 1e-10);
        Ok(DVector::from_fn(f_rows.len(), |k, _| scaled[k] * scale[k]))
    }
}

/// The joint rows (equalities and active inequalities, `c` the values) and
/// the finger rows of `model`, ascending.
fn partition_rows(model: &Model, c: &[f64]) -> (Vec<usize>, Vec<usize>) {
    let (mut j_rows, mut f_rows) = (Vec::new(), Vec::new());
    for (i, row) in model.rows().iter().enumerate() {
        if model.constraints()[row.constraint.index()].finger.is_some() {
            f_rows.push(i);
        } else if row.sense == Sense::Equality || c[i] <= INEQUALITY_ACTIVE_BAND {
            j_rows.push(i);
        }
    }
    (j_rows, f_rows)
}

/// Each finger's wrench from the finger multipliers `lambda_f` (finger rows
/// in model order) through C_q's rows of its constraint.
fn finger_wrenches(
    model: &Model,
    q: &[f64],
    cq: &DMatrix<f64>,
    lambda_f: &DVector<f64>,
) -> Result<Vec<FingerWrench>, ReferenceError> {
    let mut out = Vec::with_capacity(model.fingers().len());
    let mut lam = lambda_f.iter();
    for (k, finger) in model.fingers().iter().enumerate() {
        let o = model.layout().body_offset(finger.body).unwrap_or(0);
        let mut w_c = [0.0; 7];
        for (r, l) in model.constraints()[finger.constraint.index()]
            .rows
            .clone()
            .zip(&mut lam)
        {
            for (c, w) in w_c.iter_mut().enumerate() {
                *w += cq[(r, o + c)] * l;
            }
        }
        let f = frame_at(q, o)?;
        let p = model
            .finger_point(q, FingerId(k as u32))
            .unwrap_or(Vector3::zeros());
        let (force_n, torque_nm) = on_finger(&f, &p, &w_c);
        out.push(FingerWrench {
            finger: FingerId(k as u32),
            force_n,
            torque_nm,
        });
    }
    Ok(out)
}

/// The minimum-norm least-squares solution of `a x ≈ b`, singular values
/// below `relative` × the largest treated as zero; by faer's SVD (nalgebra's
/// mis-converged on a 6 × 3 matrix with 1e-30 entries beside O(1) ones: a
/// singular value off by 6e-4 relative, a flexible cantilever's tip load by
/// 1e-3). Zero when the SVD fails.
fn min_norm_solve(a: &DMatrix<f64>, b: &DVector<f64>, relative: f64) -> DVector<f64> {
    let (m, n) = a.shape();
    let mat = faer::Mat::<f64>::from_fn(m, n, |i, j| a[(i, j)]);
    let Ok(svd) = mat.thin_svd() else {
        return DVector::zeros(n);
    };
    let (u, v, s) = (svd.U(), svd.V(), svd.S().column_vector());
    let k = s.nrows();
    let top = (0..k).map(|i| s[i]).fold(0.0, f64::max);
    let mut x = DVector::zeros(n);
    for i in 0..k {
        if s[i] <= relative * top || s[i] == 0.0 {
            continue;
        }
        let ub: f64 = (0..m).map(|r| u[(r, i)] * b[r]).sum();
        for c in 0..n {
            x[c] += v[(c, i)] * ub / s[i];
        }
    }
    x
}
