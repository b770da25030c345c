//! `dexterity` (Nelson & Cohen App. C, Eq. 12–14): the manipulability of a
//! chain of bodies at a point x of its last body, maximised; the chain may
//! be closed into a loop (Park & Kim, the paper's ref. 41).
//!
//! **J in augmented coordinates** (Eq. 13 reworked). The chain's joints are
//! the model's joints between successive bodies; each gives columns of the
//! twist of the last body at x per unit joint rate, from the joint's world
//! axis z and point o (body i's axis and anchor, read from q like every
//! constraint), made dimensionless with the chain's reach R:
//!
//! | joint | columns s_c = [linear; angular] |
//! |---|---|
//! | revolute | [z × (x − o) / R; z] (Eq. 13) |
//! | prismatic | [z / R; 0] |
//! | spherical | [e_k × (x − o) / R; e_k], k = x, y, z (world axes) |
//! | universal | [z_i × (x − o) / R; z_i], [z_j × (x − o) / R; z_j] |
//!
//! J̃ has a row d_r · (linear part) per task direction d_r (`directions`,
//! default the world x, y, z; a planar arm names its plane's two) and a row
//! e_s · (angular part) per `angular_directions` entry (Eq. 13's angular
//! row; none by default). R, the chain's reach at q0 (the sum of its
//! joint-to-joint and last-joint-to-x distances), makes both kinds of row
//! dimensionless. G = J̃ J̃ᵀ (m × m) when there are at least as many columns
//! as rows, else J̃ᵀ J̃; det G is the squared volume of the manipulability
//! ellipsoid in both cases, and Eq. 14 is f = det(G)^(−1/2).
//!
//! **Closed chains** (`closure`: bodies leading from the last body back to
//! the base). The loop's joints add columns s_c that are not on the path to
//! x, and the joint rates must keep the loop closed: H θ̇ = 0 with H the
//! 6 × n matrix of every loop column (a loop's twists sum to zero; any
//! reference point and column signs give the same null space). The chain's
//! manipulability over the rates the loop allows (all joints counted, none
//! singled out as actuated, so it stays bounded through the loop's own
//! singularities) is that of J̃ P, P = I − H⁺H the projector onto null(H)
//! (J̃'s columns off the path are zero): G = J̃ P J̃ᵀ, which needs no more
//! task rows than the loop has degrees of freedom (checked at build time).
//! An open chain is the case P = I.
//!
//! **The guarded log form.** Minimising f is minimising ln f = −½ ln det G;
//! near a singular pose det G gets a floor ε = [`DET_FLOOR`]:
//!
//! ```text
//! F = −½ R² ln(det G + ε)                         (m², like the other terms)
//! ∂F = −½ R² tr(adj(G) ∂G) / (det G + ε)
//! tr(adj ∂G) = ⟨W_J, ∂J̃⟩ + ⟨W_H, ∂H⟩
//!   open, G = J̃J̃ᵀ:  W_J = 2 adj J̃        open, G = J̃ᵀJ̃:  W_J = 2 J̃ adj
//!   closed:           W_J = 2 adj J̃ P,     W_H = −2 (H⁺)ᵀ (J̃ᵀ adj J̃) P
//! ```
//!
//! (∂P = −(H⁺ ∂H P + P ∂Hᵀ H⁺ᵀ) at constant rank.) The adjugate is finite
//! at a singular G (`sym6`), so ∂F is finite everywhere; each column's
//! share, ŝ_c = (l̂, â), is a point or direction gradient of the joint's and
//! the tip's bodies (`grad.rs`). Reported value: Eq. 14's f = (det G +
//! ε)^(−1/2) (dimensionless; 1/f is the manipulability in units of R^m).

use nalgebra::{Matrix6, Vector3, Vector6};

use super::grad::BodyGrad;
use super::sym6::{det_adjugate, pseudo_inverse};
use crate::BodyId;
use crate::constraint::block::Param3;

pub(crate) use super::dexterity_loop::DexScratch;

/// The floor ε on det G (J̃ dimensionless): f never exceeds 1/√ε = 10⁴.
pub const DET_FLOOR: f64 = 1e-8;

/// Eigenvalues of H Hᵀ below this × the largest count as zero (the loop's
/// rank for H⁺).
pub(crate) const LOOP_RANK_TOLERANCE: f64 = 1e-10;

/// A row of H within this fraction of its length of the others' span is
/// dependent (the same singular-value ratio as [`LOOP_RANK_TOLERANCE`]).
pub(crate) const LOOP_ROW_TOLERANCE: f64 = 1e-5;

/// Where a column's axis lives.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Axis {
    /// A unit body-frame vector of a body (frame index).
    Body(usize, Vector3<f64>),
    /// A constant world direction (a spherical joint's three).
    World(Vector3<f64>),
}

/// One column: s = [z × (x − o) / R; z], or [z / R; 0] without an origin (a
/// prismatic joint).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Column {
    pub axis: Axis,
    /// The joint point o: a body (frame index) and its anchor there.
    pub origin: Option<(usize, Param3)>,
    /// On the path from the base to x (else a loop-closing joint's).
    pub on_path: bool,
}

/// The manipulability of a chain at a body point.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Dexterity {
    pub columns: Vec<Column>,
    /// The point x: its body and its body-frame position, metres.
    pub tip: (BodyId, Vector3<f64>),
    /// Task directions d_r (unit, world), the first `rows` used.
    pub directions: [Vector3<f64>; 3],
    pub rows: usize,
    /// Angular task directions e_s (unit, world), the first `angular_rows`.
    pub angular: [Vector3<f64>; 3],
    pub angular_rows: usize,
    /// R, metres.
    pub reach_m: f64,
    /// A loop (`closure` given): G = J̃ P J̃ᵀ.
    pub closed: bool,
}

/// G's determinant and adjugate (padded to 6 × 6).
struct Gram {
    det: f64,
    adj: Matrix6<f64>,
    /// G = J̃ᵀ J̃ (more rows than columns, open chains).
    transposed: bool,
}

impl Dexterity {
    fn m(&self) -> usize {
        self.rows + self.angular_rows
    }

    fn axis(&self, g: &BodyGrad, a: &Axis) -> Vector3<f64> {
        match *a {
            Axis::Body(f, h) => g.frames[f].rot * h,
            Axis::World(z) => z,
        }
    }

    fn origin(g: &BodyGrad, q: &[f64], f: usize, k: &Param3) -> (Vector3<f64>, Vector3<f64>) {
        let k = match *k {
            Param3::Const(v) => v,
            Param3::Free(c) => Vector3::new(q[c], q[c + 1], q[c + 2]),
            // A joint on a flexible body: its deformed point (the
            // deformation columns' share of the gradient is left out).
            Param3::Flex(i) => g.flex[i as usize].point(q),
        };
        let lever = g.frames[f].rot * k;
        (g.frames[f].r + lever, lever)
    }

    /// x and its lever arm.
    fn tip(&self, g: &BodyGrad) -> (Vector3<f64>, Vector3<f64>) {
        let f = &g.frames[self.tip.0.index()];
        let lever = f.rot * self.tip.1;
        (f.r + lever, lever)
    }

    /// Task row r of the 6-vector s.
    fn task(&self, r: usize, s: &Vector6<f64>) -> f64 {
        if r < self.rows {
            self.directions[r].dot(&s.fixed_rows::<3>(0))
        } else {
            self.angular[r - self.rows].dot(&s.fixed_rows::<3>(3))
        }
    }

    /// s_c and J̃'s columns into `x`; for a loop, H⁺ and P too.
    pub(super) fn columns(&self, g: &BodyGrad, q: &[f64], x: &mut DexScratch) -> Option<()> {
        let (tip, _) = self.tip(g);
        let r = self.reach_m;
        let n = self.columns.len();
        for (c, col) in self.columns.iter().enumerate() {
            let z = self.axis(g, &col.axis);
            let s = match &col.origin {
                Some((f, k)) => {
                    let lin = z.cross(&(tip - Self::origin(g, q, *f, k).0)) / r;
                    Vector6::new(lin.x, lin.y, lin.z, z.x, z.y, z.z)
                }
                None => Vector6::new(z.x / r, z.y / r, z.z / r, 0.0, 0.0, 0.0),
            };
            x.s[c] = s;
            x.j[c] = Vector6::from_fn(|row, _| {
                if col.on_path && row < self.m() {
                    self.task(row, &s)
                } else {
                    0.0
                }
            });
        }
        if self.closed {
            let hht: Matrix6<f64> = x.s[..n].iter().map(|s| s * s.transpose()).sum();
            let (pinv, _) = pseudo_inverse(&hht, LOOP_RANK_TOLERANCE)?;
            for c in 0..n {
                x.hp[c] = pinv * x.s[c]; // row c of H⁺ = (Hᵀ (HHᵀ)⁺)[c, :]
            }
            self.projector(x);
        }
        Some(())
    }

    /// G (padded with ones), its determinant and adjugate.
    fn gram(&self, x: &DexScratch) -> Option<Gram> {
        let (m, n) = (self.m(), self.columns.len());
        let mut g = Matrix6::identity();
        let transposed = !self.closed && m > n;
        if transposed {
            for a in 0..n {
                for b in 0..n {
                    g[(a, b)] = x.j[a].dot(&x.j[b]);
                }
            }
        } else {
            for a in 0..m {
                for b in 0..m {
                    g[(a, b)] = if self.closed {
                        (0..n)
                            .map(|c| {
                                x.j[c][a] * (0..n).map(|d| x.p[c * n + d] * x.j[d][b]).sum::<f64>()
                            })
                            .sum()
                    } else {
                        (0..n).map(|c| x.j[c][a] * x.j[c][b]).sum()
                    };
                }
            }
        }
        let size = if transposed { n } else { m };
        let (det, adj) = det_adjugate(&g, size)?;
        Some(Gram {
            det: det.max(0.0),
            adj,
            transposed,
        })
    }

    /// F = −½ R² ln(det G + ε) at q (frames in `g`).
    pub fn value(&self, g: &BodyGrad, q: &[f64], x: &mut DexScratch) -> f64 {
        let det = self
            .columns(g, q, x)
            .and_then(|()| self.gram(x))
            .map_or(0.0, |gm| gm.det);
        -0.5 * self.reach_m * self.reach_m * (det + DET_FLOOR).ln()
    }

    /// Eq. 14 with the floor: f = (det G + ε)^(−1/2).
    pub fn report(&self, g: &BodyGrad, q: &[f64], x: &mut DexScratch) -> f64 {
        let det = self
            .columns(g, q, x)
            .and_then(|()| self.gram(x))
            .map_or(0.0, |gm| gm.det);
        1.0 / (det + DET_FLOOR).sqrt()
    }

    /// F, and `w` × ∂F into `g` (free anchors straight into `out`).
    pub fn gradient(
        &self,
        g: &mut BodyGrad,
        q: &[f64],
        x: &mut DexScratch,
        w: f64,
        out: &mut [f64],
    ) -> f64 {
        let r = self.reach_m;
        let Some(gm) = self.columns(g, q, x).and_then(|()| self.gram(x)) else {
            return -0.5 * r * r * DET_FLOOR.ln();
        };
        let value = -0.5 * r * r * (gm.det + DET_FLOOR).ln();
        let kappa = w * -0.5 * r * r / (gm.det + DET_FLOOR);
        self.weights(&gm, x);
        let (tip, tip_lever) = self.tip(g);
        for (c, col) in self.columns.iter().enumerate() {
            // ŝ_c: the column's share of κ tr(adj ∂G), linear then angular.
            // (J̃'s columns off the path are zero whatever q: no share.)
            let mut sh = x.wh[c] * kappa;
            for row in (0..self.m()).filter(|_| col.on_path) {
                let wv = x.wj[c][row] * kappa;
                if row < self.rows {
                    sh.fixed_rows_mut::<3>(0)
                        .axpy(wv, &self.directions[row], 1.0);
                } else {
                    sh.fixed_rows_mut::<3>(3)
                        .axpy(wv, &self.angular[row - self.rows], 1.0);
                }
            }
            let (lin, ang) = (
                sh.fixed_rows::<3>(0).into_owned(),
                sh.fixed_rows::<3>(3).into_owned(),
            );
            let z = self.axis(g, &col.axis);
            match col.origin {
                Some((f, k)) => {
                    let (o, o_lever) = Self::origin(g, q, f, &k);
                    let v = tip - o;
                    if let Axis::Body(fz, _) = col.axis {
                        g.direction(BodyId(fz as u32), &z, &(v.cross(&lin) / r + ang));
                    }
                    let n_x = lin.cross(&z) / r;
                    g.point(self.tip.0, &tip_lever, &n_x);
                    g.point(BodyId(f as u32), &o_lever, &-n_x);
                    if let Param3::Free(col) = k {
                        g.anchor(BodyId(f as u32), col, &-n_x, out);
                    }
                }
                None => {
                    if let Axis::Body(fz, _) = col.axis {
                        g.direction(BodyId(fz as u32), &z, &(lin / r));
                    }
                }
            }
        }
        value
    }

    /// W_J and W_H (see the module docs) into `x.wj`, `x.wh`.
    fn weights(&self, gm: &Gram, x: &mut DexScratch) {
        let (m, n) = (self.m(), self.columns.len());
        let adj = &gm.adj;
        if gm.transposed {
            // W_J = 2 J̃ adj: column c = 2 Σ_a J̃[:, a] adj[a, c].
            for c in 0..n {
                x.wj[c] = (0..n).map(|a| x.j[a] * (2.0 * adj[(a, c)])).sum();
                x.wh[c] = Vector6::zeros();
            }
            return;
        }
        // adj J̃ column by column, in `wh` until W_H is formed.
        for c in 0..n {
            x.wh[c] = Vector6::from_fn(|row, _| {
                if row < m {
                    (0..m).map(|b| adj[(row, b)] * x.j[c][b]).sum()
                } else {
                    0.0
                }
            });
        }
        if !self.closed {
            for c in 0..n {
                x.wj[c] = x.wh[c] * 2.0;
                x.wh[c] = Vector6::zeros();
            }
            return;
        }
        // W_J = 2 (adj J̃) P.
        for c in 0..n {
            x.wj[c] = (0..n).map(|a| x.wh[a] * (2.0 * x.p[a * n + c])).sum();
        }
        // W_H = −2 H⁺ᵀ Z P with Z[a, b] = J̃[:, a] · (adj J̃)[:, b]: column
        // c = −2 Σ_a H⁺[a, :] (Z P)[a, c], built in `s` (no longer needed).
        for c in 0..n {
            let mut acc = Vector6::zeros();
            for a in 0..n {
                let zp: f64 = (0..n).map(|b| x.j[a].dot(&x.wh[b]) * x.p[b * n + c]).sum();
                acc += x.hp[a] * (-2.0 * zp);
            }
            x.s[c] = acc;
        }
        for c in 0..n {
            x.wh[c] = x.s[c];
        }
    }
}
