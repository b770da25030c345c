//! The AL iteration fused with the evaluation: C and the weighted gradient
//! C_qᵀ w in one pass, without storing C_q.
//!
//! Every constraint writes each row's gradient with respect to its two ends'
//! world-frame virtual displacement δr and rotation δθ (a [`RowGrad`]); the
//! stored Jacobian maps each row's δθ part to the four Euler-parameter columns
//! through Ω(e) and a separate pass multiplies by w. Here, as soon as a
//! constraint's rows are known, their weights w_i (multiplier, penalty) are
//! formed and w_i × gradient is added to per-body world force/torque
//! accumulators; Ω is applied once per body at the end:
//!
//! ```text
//! (C_qᵀ w)[r_b] = Σ_i w_i ∂C_i/∂r_b,      (C_qᵀ w)[e_b] = Ω(e_b)ᵀ Σ_i w_i ∂C_i/∂θ_b
//! ```
//!
//! It is the same C_qᵀ w to round-off (a test compares it with the stored
//! Jacobian's product), at a fraction of the memory traffic: no Jacobian
//! values are written or read back.

use nalgebra::Vector3;

use super::scaling::Scaling;
use super::update::{clamp_finger_pull, row_weight};
use crate::constraint::block::{Ctx, Groups, RowGrad, Sink, Slot};
use crate::evaluate::{all_finite, check_inputs};
use crate::model::initial_frame;
use crate::rotation::BodyFrame;
use crate::{BodyId, ConstraintKind, EvalError, FingerTarget, Model};

/// Most rows of one constraint (rigid finger, weld, revolute: ≤ 6).
const MAX_ROWS: usize = 6;
/// Most raw (column-wise) entries one constraint writes (a norm row: 4).
const MAX_RAW: usize = 8;

/// Per constraint: its rows, the accumulators of its ends, its free columns.
#[derive(Debug, Clone)]
struct Plan {
    rows: (usize, usize),
    frame: [usize; 2],
    /// Body index of each end if it moves (its accumulator).
    moving: [bool; 2],
    /// The rows depend on the ends' poses (not a norm or design-bound row,
    /// which write raw entries only).
    ends: bool,
    groups: Groups,
    finger: bool,
    /// Column of e for a quaternion-norm row (evaluated inline: C = eᵀe − 1,
    /// ∂C/∂e = 2eᵀ), else `None`.
    norm: Option<usize>,
}

/// Collects one constraint's row gradients and raw entries.
struct GradSink {
    rows: [RowGrad; MAX_ROWS],
    raw: [(u8, u8, u8, f64); MAX_RAW],
    n_raw: usize,
}

impl Sink for GradSink {
    #[inline(always)]
    fn row(&mut self, row: usize, g: &RowGrad) {
        self.rows[row] = *g;
    }

    #[inline(always)]
    fn set(&mut self, row: usize, slot: Slot, k: usize, v: f64) {
        if self.n_raw < MAX_RAW {
            self.raw[self.n_raw] = (row as u8, slot as u8, k as u8, v);
            self.n_raw += 1;
        }
    }
}

/// Frames, plans and accumulators of the fused iteration.
#[derive(Debug, Clone)]
pub(crate) struct Fused {
    frames: Vec<BodyFrame>,
    plans: Vec<Plan>,
    lin: Vec<Vector3<f64>>,
    ang: Vec<Vector3<f64>>,
    /// (body index, column of r) of every moving body.
    moving: Vec<(usize, usize)>,
    /// C at the last pass.
    pub values: Vec<f64>,
}

impl Fused {
    /// Plans for `model`. Allocates.
    pub fn new(model: &Model) -> Self {
        let n_bodies = model.bodies.len();
        let mut frames: Vec<BodyFrame> = model.bodies.iter().map(initial_frame).collect();
        frames.push(BodyFrame::IDENTITY);
        let plans = model
            .geometry
            .iter()
            .zip(&model.constraints)
            .enumerate()
            .map(|(k, (g, info))| {
                let frame = g.frames();
                let moving = frame.map(|f| f < n_bodies && model.layout.body_cols[f].is_some());
                Plan {
                    rows: (info.rows.start, info.rows.end),
                    frame,
                    moving,
                    ends: g.has_ends(),
                    groups: model.constraint_groups(k),
                    finger: info.finger.is_some(),
                    norm: match info.kind {
                        ConstraintKind::QuaternionNorm => {
                            g.groups()[Slot::BodyI as usize].map(|(c, _)| c)
                        }
                        _ => None,
                    },
                }
            })
            .collect();
        let moving = model
            .layout
            .moving_bodies()
            .map(|(id, o)| (id.index(), o))
            .collect();
        Self {
            frames,
            plans,
            lin: vec![Vector3::zeros(); n_bodies + 1],
            ang: vec![Vector3::zeros(); n_bodies + 1],
            moving,
            values: vec![0.0; model.n_rows()],
        }
    }

    /// One AL iteration at `q` (see [`super::update`] for the per-row rules):
    /// updates `lambda`, writes C into `values` and C_qᵀ w into `g`, then
    /// steps `q`. On error nothing but `values`/`g` scratch has changed.
    ///
    /// # Real-time
    /// No allocation, no locks; O(bodies + rows), one pass over the constraints.
    #[allow(clippy::too_many_arguments)]
    pub fn iterate(
        &mut self,
        model: &Model,
        s: &Scaling,
        h: f64,
        q: &mut [f64],
        q_ref: &[f64],
        targets: &[FingerTarget],
        lambda: &mut [f64],
        g: &mut [f64],
        witnesses: &[crate::constraint::witness::Witness],
    ) -> Result<(), EvalError> {
        self.prepare(model, q, targets)?;
        g.fill(0.0);
        let x = Ctx {
            q: &*q,
            frames: &self.frames,
            targets,
            witnesses,
            flex: &model.flex_anchors,
            surfaces: &model.surfaces,
            rolling: &[],
        };
        let mut sink = GradSink {
            rows: [RowGrad::default(); MAX_ROWS],
            raw: [(0, 0, 0, 0.0); MAX_RAW],
            n_raw: 0,
        };
        let mut w = [0.0; MAX_ROWS];
        for (geo, p) in model.geometry.iter().zip(&self.plans) {
            let (r0, r1) = p.rows;
            if let Some(col) = p.norm {
                let e = &x.q[col..col + 4];
                let c = e.iter().map(|v| v * v).sum::<f64>() - 1.0;
                self.values[r0] = c;
                let wk = 2.0 * row_weight(s, r0, c, &mut lambda[r0]);
                for j in 0..4 {
                    g[col + j] += wk * e[j];
                }
                continue;
            }
            let c = &mut self.values[r0..r1];
            sink.n_raw = 0;
            geo.eval(&x, c, &mut sink);
            for (k, wk) in w[..r1 - r0].iter_mut().enumerate() {
                let i = r0 + k;
                *wk = row_weight(s, i, c[k], &mut lambda[i]);
            }
            if p.finger {
                clamp_finger_pull(s, r0, c, &mut w[..r1 - r0]);
            }
            // Σ_k w_k ∂C_k/∂(δr, δθ) of each end, then once into the body.
            let mut acc = RowGrad::default();
            if p.ends {
                for (rg, &wk) in sink.rows[..r1 - r0].iter().zip(&w) {
                    acc.add_scaled(wk, rg);
                }
            }
            for end in 0..2 {
                if p.moving[end] {
                    let b = p.frame[end];
                    self.lin[b] += acc.lin[end];
                    self.ang[b] += acc.ang[end];
                }
                if let Some((col, _)) = p.groups[Slot::anchor(end) as usize] {
                    let dk = self.frames[p.frame[end]].rot.tr_mul(&acc.lin[end]);
                    for j in 0..3 {
                        g[col + j] += dk[j];
                    }
                }
                if let Some((col, _)) = p.groups[Slot::origin(end) as usize] {
                    for j in 0..3 {
                        g[col + j] += acc.lin[end][j];
                    }
                }
            }
            for &(row, slot, k, v) in &sink.raw[..sink.n_raw] {
                if let Some((col, _)) = p.groups[slot as usize] {
                    g[col + k as usize] += w[row as usize] * v;
                }
            }
        }
        if !all_finite(&self.values) {
            let row = self.values.iter().position(|v| !v.is_finite()).unwrap_or(0);
            return Err(EvalError::NonFiniteValue { row });
        }
        for &(b, o) in &self.moving {
            let (lin, ang) = (self.lin[b], self.ang[b]);
            self.lin[b] = Vector3::zeros();
            self.ang[b] = Vector3::zeros();
            let de = self.frames[b].omega.tr_mul(&ang);
            for j in 0..3 {
                g[o + j] += lin[j];
            }
            for j in 0..4 {
                g[o + 3 + j] += de[j];
            }
        }
        super::update::step(s, h, q, q_ref, g);
        Ok(())
    }

    /// Input checks and the moving bodies' frames (as `Evaluation::evaluate`).
    fn prepare(
        &mut self,
        model: &Model,
        q: &[f64],
        targets: &[FingerTarget],
    ) -> Result<(), EvalError> {
        check_inputs(model, q, targets)?;
        for &(b, o) in &self.moving {
            let r = Vector3::new(q[o], q[o + 1], q[o + 2]);
            let e = [q[o + 3], q[o + 4], q[o + 5], q[o + 6]];
            self.frames[b] = BodyFrame::new(r, e).ok_or(EvalError::DegenerateQuaternion {
                body: BodyId(b as u32),
            })?;
        }
        for (b, o) in model.layout.origin_cols.iter().enumerate() {
            if let Some(o) = *o {
                self.frames[b].r = Vector3::new(q[o], q[o + 1], q[o + 2]);
            }
        }
        Ok(())
    }
}
