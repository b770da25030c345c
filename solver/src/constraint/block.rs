//! Shared block helpers: every constraint kind is written in terms of these, so
//! the Jacobian algebra of points, directions and dot products lives here once.
//!
//! A constraint row is differentiated with respect to each end's world-frame
//! virtual displacement δr (3) and virtual rotation δθ (3), accumulated in a
//! [`RowGrad`]. The [`Sink`] then maps δθ to the four Euler-parameter columns
//! through Ω(e) (see [`crate::rotation`]) and, for a free anchor, maps the
//! world-frame point gradient n to the anchor's body-frame columns Rᵀn; for a
//! fixed body with a free position, n itself goes to its three origin columns.

use nalgebra::{Matrix3, Vector3};

use crate::FingerTarget;
use crate::rotation::BodyFrame;

/// Everything a constraint reads during one evaluation.
pub(crate) struct Ctx<'a> {
    /// The coordinate vector (bodies then design variables).
    pub q: &'a [f64],
    /// One frame per body, then the world frame.
    pub frames: &'a [BodyFrame],
    /// One target per finger, world frame.
    pub targets: &'a [FingerTarget],
    /// The witness table (contact rows' parameters).
    pub witnesses: &'a [crate::constraint::witness::Witness],
    /// The model's deforming points (`Param3::Flex` indexes them; empty
    /// for a rigid model).
    pub flex: &'a [crate::flexible::anchor::FlexAnchor],
    /// The model's surface contacts (`crate::parametric`; empty without).
    pub surfaces: &'a [crate::parametric::SurfaceContact],
    /// The rolling rows' tick-start anchors (`crate::parametric::rolling`).
    pub rolling: &'a [crate::parametric::rolling::RollAnchor],
}

impl Ctx<'_> {
    #[inline]
    pub fn frame(&self, index: usize) -> &BodyFrame {
        &self.frames[index]
    }

    #[inline]
    pub fn vec3(&self, p: &Param3) -> Vector3<f64> {
        match *p {
            Param3::Const(v) => v,
            Param3::Free(col) => Vector3::new(self.q[col], self.q[col + 1], self.q[col + 2]),
            Param3::Flex(i) => flex_point(self.flex, i, self.q),
        }
    }

    #[inline]
    pub fn scalar(&self, p: &Param1) -> f64 {
        match *p {
            Param1::Const(v) => v,
            Param1::Free(col) => self.q[col],
        }
    }
}

/// The deformed point of a flexible body's anchor `i`: out of line and
/// cold, so the rigid path's `Ctx::vec3` stays two arms of straight code
/// (inlined into every anchor's evaluation; the flexible arm inline cost a
/// rigid four-bar 20 % of its evaluation, `haptloop bench`).
#[cold]
#[inline(never)]
fn flex_point(flex: &[crate::flexible::anchor::FlexAnchor], i: u32, q: &[f64]) -> Vector3<f64> {
    flex[i as usize].point(q)
}

/// Φᵀ d into a flexible anchor's columns (out of line, as [`flex_point`]).
#[cold]
#[inline(never)]
fn flex_gradient(a: &crate::flexible::anchor::FlexAnchor, d: &Vector3<f64>, out: &mut [f64]) {
    a.gradient(d, out);
}

/// A 3-vector that is a constant, a free design variable (its column in
/// q), or a point of a flexible body that moves with its deformation (an
/// index into the model's deforming points, `crate::flexible::anchor`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Param3 {
    Const(Vector3<f64>),
    Free(usize),
    Flex(u32),
}

/// A scalar that is a constant or a free design variable (its column in q).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Param1 {
    Const(f64),
    Free(usize),
}

/// The logical column groups a constraint may touch. Rows store them sorted by
/// column; [`crate::jacobian`] records where each one landed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Slot {
    BodyI = 0,
    BodyJ = 1,
    AnchorI = 2,
    AnchorJ = 3,
    /// A distance joint's free length (1 column), or a surface contact's
    /// (u, v) (2 columns): written through `Sink::set` only.
    Length = 4,
    /// The free position (3 design columns, world frame) of a fixed body at
    /// end 0 or 1 (see `Model::constraint_groups`).
    OriginI = 5,
    OriginJ = 6,
}

impl Slot {
    /// The body group of end 0 or 1.
    #[inline]
    pub fn body(end: usize) -> Self {
        if end == 0 { Self::BodyI } else { Self::BodyJ }
    }

    /// The anchor design-variable group of end 0 or 1.
    #[inline]
    pub fn anchor(end: usize) -> Self {
        if end == 0 {
            Self::AnchorI
        } else {
            Self::AnchorJ
        }
    }

    /// The free-position design group of a fixed body at end 0 or 1.
    #[inline]
    pub fn origin(end: usize) -> Self {
        if end == 0 {
            Self::OriginI
        } else {
            Self::OriginJ
        }
    }
}

/// Number of [`Slot`]s.
pub(crate) const SLOTS: usize = 7;

/// For each slot, `(first column, width)` if the constraint touches it.
pub(crate) type Groups = [Option<(usize, usize)>; SLOTS];

/// The two ends of a two-body constraint: frame indices (a fixed body's frame is
/// constant; index `n_bodies` is the world), the q column of each moving body's
/// r, and each end's body-frame anchor point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Pair {
    pub frame: [usize; 2],
    pub col: [Option<usize>; 2],
    pub anchor: [Param3; 2],
}

/// A body-fixed point evaluated in the world: position and lever arm R·k.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Point {
    pub p: Vector3<f64>,
    pub lever: Vector3<f64>,
}

impl Pair {
    /// Column groups of the two bodies and of any free anchors (a flexible
    /// anchor's deformation columns are added by `Model::constraint_groups`,
    /// which knows where they are).
    pub fn groups(&self) -> Groups {
        let mut g: Groups = [None; SLOTS];
        for end in 0..2 {
            g[Slot::body(end) as usize] = self.col[end].map(|c| (c, 7));
            if let Param3::Free(c) = self.anchor[end] {
                g[Slot::anchor(end) as usize] = Some((c, 3));
            }
        }
        g
    }

    /// World positions and lever arms of both anchors.
    #[inline]
    pub fn points(&self, x: &Ctx) -> [Point; 2] {
        // Written out: `[0, 1].map(…)` compiled to an out-of-line array-drain
        // closure that cost about a quarter of a value-only evaluation.
        [self.point(x, 0), self.point(x, 1)]
    }

    /// World position and lever arm of the anchor of `end`.
    #[inline(always)]
    fn point(&self, x: &Ctx, end: usize) -> Point {
        let f = x.frame(self.frame[end]);
        let lever = f.rot * x.vec3(&self.anchor[end]);
        Point {
            p: f.r + lever,
            lever,
        }
    }

    /// World direction of the body-frame vector `h` on end `end`.
    #[inline]
    pub fn dir(&self, x: &Ctx, end: usize, h: &Vector3<f64>) -> Vector3<f64> {
        x.frame(self.frame[end]).rot * h
    }
}

/// ∂row/∂(δr, δθ) of both ends, world frame. `lin[end]` is also ∂row/∂p for the
/// end's anchor point p, because ∂p/∂r = I.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct RowGrad {
    pub lin: [Vector3<f64>; 2],
    pub ang: [Vector3<f64>; 2],
}

impl RowGrad {
    /// The row depends on the anchor point of `end` (lever arm `lever`) with
    /// gradient `n`: δp = δr + δθ × lever, so δrow = n·δr + (lever × n)·δθ.
    #[inline]
    pub fn point(&mut self, end: usize, lever: &Vector3<f64>, n: &Vector3<f64>) -> &mut Self {
        self.lin[end] += n;
        self.ang[end] += lever.cross(n);
        self
    }

    /// The row depends on the world direction `a` of a body-fixed vector of
    /// `end` with gradient `g`: δa = δθ × a, so δrow = (a × g)·δθ.
    #[inline]
    pub fn direction(&mut self, end: usize, a: &Vector3<f64>, g: &Vector3<f64>) -> &mut Self {
        self.ang[end] += a.cross(g);
        self
    }

    /// Adds `k · other`.
    #[inline]
    pub fn add_scaled(&mut self, k: f64, other: &RowGrad) -> &mut Self {
        for end in 0..2 {
            self.lin[end] += other.lin[end] * k;
            self.ang[end] += other.ang[end] * k;
        }
        self
    }

    /// `k · self`.
    #[inline]
    pub fn scaled(mut self, k: f64) -> Self {
        for end in 0..2 {
            self.lin[end] *= k;
            self.ang[end] *= k;
        }
        self
    }
}

/// Value and gradient of a dot product a·b between a direction on end 0 and a
/// direction on end 1 (both world frame).
#[inline]
pub(crate) fn dot_row(a: &Vector3<f64>, b: &Vector3<f64>) -> (f64, RowGrad) {
    let mut g = RowGrad::default();
    g.direction(0, a, b).direction(1, b, a);
    (a.dot(b), g)
}

/// The three rows p_i − p_j = 0 (or p_i − target when end 1 is the world and
/// its anchor is the target), written at local rows `row0..row0 + 3`.
#[inline]
pub(crate) fn coincidence_rows<S: Sink>(
    pts: &[Point; 2],
    row0: usize,
    c: &mut [f64],
    sink: &mut S,
) {
    let d = pts[0].p - pts[1].p;
    for k in 0..3 {
        c[row0 + k] = d[k];
        let e = Vector3::ith(k, 1.0);
        let mut g = RowGrad::default();
        g.point(0, &pts[0].lever, &e).point(1, &pts[1].lever, &-e);
        sink.row(row0 + k, &g);
    }
}

/// Cross-sum orientation error between two frames given by their world axes
/// (columns of `a` on end 0 and `b` on end 1): e = ½ Σ_k a_k × b_k, three rows.
/// Near alignment e ≈ δθ₁ − δθ₀ (radians); its Jacobian is ½(a bᵀ − tr(aᵀb) I)
/// with respect to δθ₀ and the negated transpose form for δθ₁. Smooth
/// everywhere; like every 3-row orientation error it also vanishes at 180°
/// misalignments, which the fast loop never approaches from an assembled state.
#[inline]
pub(crate) fn orientation_rows<S: Sink>(
    a: &Matrix3<f64>,
    b: &Matrix3<f64>,
    row0: usize,
    c: &mut [f64],
    sink: &mut S,
) {
    let mut e = Vector3::zeros();
    for k in 0..3 {
        e += a.column(k).cross(&b.column(k));
    }
    let tr = a.tr_mul(b).trace();
    let j0 = (a * b.transpose() - Matrix3::identity() * tr) * 0.5;
    let j1 = (b * a.transpose() - Matrix3::identity() * tr) * -0.5;
    for k in 0..3 {
        c[row0 + k] = 0.5 * e[k];
        let mut g = RowGrad::default();
        g.ang[0] = j0.row(k).transpose();
        g.ang[1] = j1.row(k).transpose();
        sink.row(row0 + k, &g);
    }
}

/// Receives Jacobian rows. [`Block`] writes them into the sparse values;
/// [`NoJacobian`] drops them (value-only evaluation).
pub(crate) trait Sink {
    /// Writes local row `row` from its world-frame gradient.
    fn row(&mut self, row: usize, g: &RowGrad);
    /// Writes one raw value: column `k` of group `slot` in local row `row`.
    fn set(&mut self, row: usize, slot: Slot, k: usize, v: f64);
}

/// A sink that ignores the Jacobian.
pub(crate) struct NoJacobian;

impl Sink for NoJacobian {
    #[inline]
    fn row(&mut self, _: usize, _: &RowGrad) {}
    #[inline]
    fn set(&mut self, _: usize, _: Slot, _: usize, _: f64) {}
}

/// A constraint's dense row-major block inside the CSR values.
pub(crate) struct Block<'a> {
    /// rows × width values.
    pub vals: &'a mut [f64],
    pub width: usize,
    /// Position of each slot's first column inside a row (`u16::MAX`: absent).
    pub pos: [u16; SLOTS],
    /// Frames of the two ends (for Ω and Rᵀ).
    pub frames: [&'a BodyFrame; 2],
    /// A deforming anchor at either end: its anchor slot holds the
    /// deformation columns, ∂/∂q_f = Φᵀ Rᵀ n (`None` on rigid models).
    pub flex: [Option<&'a crate::flexible::anchor::FlexAnchor>; 2],
}

impl Sink for Block<'_> {
    #[inline]
    fn row(&mut self, row: usize, g: &RowGrad) {
        let base = row * self.width;
        for end in 0..2 {
            let f = self.frames[end];
            let p = self.pos[Slot::body(end) as usize];
            if p != u16::MAX {
                let out = &mut self.vals[base + p as usize..base + p as usize + 7];
                out[..3].copy_from_slice(g.lin[end].as_slice());
                let de = f.omega.tr_mul(&g.ang[end]);
                out[3..].copy_from_slice(de.as_slice());
            }
            let p = self.pos[Slot::anchor(end) as usize];
            if p != u16::MAX {
                let dk = f.rot.tr_mul(&g.lin[end]);
                let at = base + p as usize;
                match self.flex[end] {
                    None => self.vals[at..at + 3].copy_from_slice(dk.as_slice()),
                    Some(a) => flex_gradient(a, &dk, &mut self.vals[at..at + a.width()]),
                }
            }
            let p = self.pos[Slot::origin(end) as usize];
            if p != u16::MAX {
                self.vals[base + p as usize..base + p as usize + 3]
                    .copy_from_slice(g.lin[end].as_slice());
            }
        }
    }

    #[inline]
    fn set(&mut self, row: usize, slot: Slot, k: usize, v: f64) {
        let p = self.pos[slot as usize];
        if p != u16::MAX {
            self.vals[row * self.width + p as usize + k] = v;
        }
    }
}

/// Value and gradient of a·(p_other − p_end), where `a` is a world direction
/// fixed to `end` and p are the two anchors: a signed offset along a body axis
/// (prismatic rows, point–plane distance).
#[inline]
pub(crate) fn separation_row(end: usize, a: &Vector3<f64>, pts: &[Point; 2]) -> (f64, RowGrad) {
    let other = 1 - end;
    let d = pts[other].p - pts[end].p;
    let mut g = RowGrad::default();
    g.direction(end, a, &d)
        .point(other, &pts[other].lever, a)
        .point(end, &pts[end].lever, &-a);
    (a.dot(&d), g)
}
