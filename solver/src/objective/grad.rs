//! The objectives' shared algebra: body frames at q, and a gradient written
//! per body as world-frame virtual displacement δr and rotation δθ (the
//! constraints' convention, `constraint::block`), mapped once per body into
//! q's columns.
//!
//! A term adds ∂F/∂p for a body point p ([`BodyGrad::point`]) or ∂F/∂a for a
//! body-fixed direction a ([`BodyGrad::direction`]); [`BodyGrad::flush`] then
//! writes r and Ωᵀ·(δθ part) into a moving body's 7 columns, the δr part into
//! a fixed body's free-position columns, and drops what falls on a fixed
//! body. Free anchors get Rᵀ n directly ([`BodyGrad::anchor`]). A point of a
//! flexible body is deformed ([`BodyGrad::lever`]) and its gradient also
//! reaches the body's deformation columns, Φᵀ Rᵀ n
//! ([`BodyGrad::point_at`], `crate::flexible::anchor`).

use nalgebra::Vector3;

use crate::constraint::block::{Pair, Param3, RowGrad};
use crate::model::initial_frame;
use crate::rotation::BodyFrame;
use crate::{BodyId, EvalError, Model};

/// Per-body world-frame gradient accumulators and the frames they refer to.
#[derive(Debug, Clone)]
pub(crate) struct BodyGrad {
    /// One frame per body at the last [`frames`](Self::frames) call, then
    /// the world's.
    pub frames: Vec<BodyFrame>,
    lin: Vec<Vector3<f64>>,
    ang: Vec<Vector3<f64>>,
    /// The model's deforming points (joint-limit terms evaluate joints on
    /// flexible bodies through them).
    pub flex: Vec<crate::flexible::anchor::FlexAnchor>,
    /// Per body: its flexible body's index in the model, if any.
    flexible: Vec<Option<usize>>,
    /// The flexible bodies (columns, beams).
    beams: Vec<crate::flexible::body::FlexBody>,
    /// q's auxiliary columns at the last `frames` call, and where they start.
    q_aux: Vec<f64>,
    aux_start: usize,
    /// ∂F on the auxiliary columns, flushed with the bodies'.
    aux_grad: Vec<f64>,
}

impl BodyGrad {
    /// Buffers for `model`. Allocates.
    pub fn new(model: &Model) -> Self {
        let n = model.bodies.len();
        let mut frames: Vec<BodyFrame> = model.bodies.iter().map(initial_frame).collect();
        frames.push(BodyFrame::IDENTITY);
        let mut flexible = vec![None; n];
        for (k, f) in model.flexible.iter().enumerate() {
            flexible[f.body.index()] = Some(k);
        }
        let aux = model.layout.aux_coords();
        Self {
            frames,
            lin: vec![Vector3::zeros(); n],
            ang: vec![Vector3::zeros(); n],
            flex: model.flex_anchors.clone(),
            flexible,
            beams: model.flexible.clone(),
            q_aux: vec![0.0; aux],
            aux_start: model.n_coords() - aux,
            aux_grad: vec![0.0; aux],
        }
    }

    /// The lever arm R k(q_f) of body point `k` of `body` (deformed when
    /// the body is flexible), at the last [`frames`](Self::frames).
    #[inline]
    pub fn lever(&self, body: BodyId, k: &Vector3<f64>) -> Vector3<f64> {
        let f = &self.frames[body.index()];
        match self.flexible.get(body.index()).copied().flatten() {
            None => f.rot * k,
            Some(b) => f.rot * self.anchor_of(b, k).point(&self.q_aux),
        }
    }

    /// The deforming point `k` of flexible body `b`, with columns relative
    /// to the auxiliary block.
    fn anchor_of(&self, b: usize, k: &Vector3<f64>) -> crate::flexible::anchor::FlexAnchor {
        let fb = &self.beams[b];
        crate::flexible::anchor::FlexAnchor {
            k: *k,
            col: fb.col - self.aux_start,
            modes: fb.beam.modes(),
            shape: fb.beam.shape(k.x),
        }
    }

    /// [`point`](Self::point) for body point `k` (body frame, undeformed)
    /// with lever arm `lever` from [`lever`](Self::lever): on a flexible
    /// body the gradient also reaches its deformation columns.
    #[inline]
    pub fn point_at(
        &mut self,
        body: BodyId,
        k: &Vector3<f64>,
        lever: &Vector3<f64>,
        n: &Vector3<f64>,
    ) {
        self.point(body, lever, n);
        if let Some(b) = self.flexible.get(body.index()).copied().flatten() {
            let a = self.anchor_of(b, k);
            let d = self.frames[body.index()].rot.tr_mul(n);
            let mut g = [0.0; 2 * crate::flexible::MAX_MODES];
            a.gradient(&d, &mut g[..a.width()]);
            for (j, v) in g[..a.width()].iter().enumerate() {
                self.aux_grad[a.col + j] += v;
            }
        }
    }

    /// Every body's frame at `q` (fixed bodies: their pose, with a free
    /// position read from q), and the accumulators cleared.
    ///
    /// # Real-time
    /// No allocation; O(bodies).
    pub fn frames(&mut self, model: &Model, q: &[f64]) -> Result<(), EvalError> {
        if q.len() != model.n_coords() {
            return Err(EvalError::CoordinateCount {
                expected: model.n_coords(),
                got: q.len(),
            });
        }
        for (b, o) in model.layout.moving_bodies() {
            let r = Vector3::new(q[o], q[o + 1], q[o + 2]);
            let e = [q[o + 3], q[o + 4], q[o + 5], q[o + 6]];
            self.frames[b.index()] =
                BodyFrame::new(r, e).ok_or(EvalError::DegenerateQuaternion { body: b })?;
        }
        for (b, o) in model.layout.origin_cols.iter().enumerate() {
            if let Some(o) = *o {
                self.frames[b].r = Vector3::new(q[o], q[o + 1], q[o + 2]);
            }
        }
        self.lin.fill(Vector3::zeros());
        self.ang.fill(Vector3::zeros());
        self.q_aux.copy_from_slice(&q[self.aux_start..]);
        self.aux_grad.fill(0.0);
        Ok(())
    }

    /// F depends on the body point with lever arm `lever` (= R k, world) on
    /// `body` with gradient `n`: δF = n·δr + (lever × n)·δθ.
    #[inline]
    pub fn point(&mut self, body: BodyId, lever: &Vector3<f64>, n: &Vector3<f64>) {
        self.lin[body.index()] += n;
        self.ang[body.index()] += lever.cross(n);
    }

    /// F depends on the world direction `a` of a vector fixed to `body` with
    /// gradient `g`: δa = δθ × a, so δF = (a × g)·δθ.
    #[inline]
    pub fn direction(&mut self, body: BodyId, a: &Vector3<f64>, g: &Vector3<f64>) {
        self.ang[body.index()] += a.cross(g);
    }

    /// F depends on a free anchor (body frame, columns `col..col + 3`) of
    /// `body` through its world point with gradient `n`: ∂F/∂k = Rᵀ n.
    #[inline]
    pub fn anchor(&self, body: BodyId, col: usize, n: &Vector3<f64>, out: &mut [f64]) {
        let dk = self.frames[body.index()].rot.tr_mul(n);
        for j in 0..3 {
            out[col + j] += dk[j];
        }
    }

    /// F depends on a two-ended constraint geometry (a joint coordinate)
    /// through the row gradient `rg` of `pair`'s ends, scaled by `w`; free
    /// anchors of the pair get their columns in `out` directly.
    pub fn row(&mut self, pair: &Pair, rg: &RowGrad, w: f64, out: &mut [f64]) {
        for end in 0..2 {
            let f = pair.frame[end];
            if f >= self.lin.len() {
                continue; // the world
            }
            self.lin[f] += rg.lin[end] * w;
            self.ang[f] += rg.ang[end] * w;
            if let Param3::Free(col) = pair.anchor[end] {
                self.anchor(BodyId(f as u32), col, &(rg.lin[end] * w), out);
            }
        }
    }

    /// Adds the accumulated gradient into `out` (q's columns).
    ///
    /// # Real-time
    /// No allocation; O(bodies).
    pub fn flush(&self, model: &Model, out: &mut [f64]) {
        for (b, o) in model.layout.moving_bodies() {
            let (lin, ang) = (self.lin[b.index()], self.ang[b.index()]);
            let de = self.frames[b.index()].omega.tr_mul(&ang);
            for j in 0..3 {
                out[o + j] += lin[j];
            }
            for j in 0..4 {
                out[o + 3 + j] += de[j];
            }
        }
        for (b, o) in model.layout.origin_cols.iter().enumerate() {
            if let Some(o) = *o {
                for j in 0..3 {
                    out[o + j] += self.lin[b][j];
                }
            }
        }
        for (o, g) in out[self.aux_start..].iter_mut().zip(&self.aux_grad) {
            *o += g;
        }
    }
}
