//! `dexterity` (Nelson & Cohen App. C, Eq. 12–14): the manipulability of a
//! chain of bodies at a point x of its last body, maximised.
//!
//! **J in augmented coordinates** (Eq. 13 reworked). The chain's joints are
//! the model's joints between successive bodies; each gives columns t_c of
//! the velocity of x per unit joint rate, from the joint's world axis z and
//! point o (body i's axis and anchor, read from q like every constraint):
//!
//! | joint | columns t_c |
//! |---|---|
//! | revolute | z × (x − o) |
//! | prismatic | z |
//! | spherical | e_k × (x − o), k = x, y, z (world axes) |
//! | universal | z_i × (x − o), z_j × (x − o) (each body's own axis) |
//!
//! J̃[r, c] = d_r · t_c / R: the rows are the task directions d_r (default
//! the world x, y, z; a planar arm names its plane's two), and R, the
//! chain's reach at q0 (the sum of its joint-to-joint and last-joint-to-x
//! distances), makes J̃ dimensionless. G = J̃ J̃ᵀ (m × m) when there are at
//! least as many columns as directions, else J̃ᵀ J̃; det G is the squared
//! volume of the manipulability ellipsoid in both cases, and Eq. 14 is
//! f = det(G)^(−1/2).
//!
//! **The guarded log form.** Minimising f is minimising ln f = −½ ln det G,
//! which has the same minimisers, is scale-free, and whose gradient does not
//! grow like f itself. Near a singular pose det G → 0; here it gets a floor
//! ε = [`DET_FLOOR`]:
//!
//! ```text
//! F = −½ R² ln(det G + ε)                         (m², like the other terms)
//! ∂F = −½ R² tr(adj(G) ∂G) / (det G + ε)
//! ```
//!
//! The adjugate (cofactors, no inverse) is finite at a singular G, so ∂F is
//! finite everywhere and bounded by ½ R² |∂ det G| / ε; at an exactly
//! singular square J, ∂ det G = 2 det J ∂ det J = 0, so a singular pose is a
//! stationary point, never a NaN or an unbounded pull. tr(adj(G) ∂G) =
//! Σ_c β_c · ∂t_c with β_c = (2/R) Σ_r (adj(G) J̃)[r, c] d_r (or, with
//! G = J̃ᵀ J̃, (2/R²) Σ_a adj(G)[a, c] P t_a, P = Σ_r d_r d_rᵀ), and each
//! ∂(β·t_c) is a point or direction gradient of the joint's and the tip's
//! bodies (`grad.rs`). Reported value: Eq. 14's f = (det G + ε)^(−1/2)
//! (dimensionless; 1/f is the manipulability in units of R^m).

use nalgebra::{Matrix3, Vector3};

use super::grad::BodyGrad;
use crate::BodyId;
use crate::constraint::block::Param3;

/// The floor ε on det G (J̃ dimensionless): f never exceeds 1/√ε = 10⁴.
pub const DET_FLOOR: f64 = 1e-8;

/// Where a column's axis lives.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Axis {
    /// A unit body-frame vector of a body (frame index).
    Body(usize, Vector3<f64>),
    /// A constant world direction (a spherical joint's three).
    World(Vector3<f64>),
}

/// One column of J: t = z × (x − o), or t = z without an origin.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Column {
    pub axis: Axis,
    /// The joint point o: a body (frame index) and its anchor there.
    pub origin: Option<(usize, Param3)>,
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
    /// R, metres.
    pub reach_m: f64,
}

impl Dexterity {
    fn axis(&self, g: &BodyGrad, a: &Axis) -> Vector3<f64> {
        match *a {
            Axis::Body(f, h) => g.frames[f].rot * h,
            Axis::World(z) => z,
        }
    }

    fn origin(
        &self,
        g: &BodyGrad,
        q: &[f64],
        f: usize,
        k: &Param3,
    ) -> (Vector3<f64>, Vector3<f64>) {
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

    /// t_c into `t`, and G padded to 3 × 3 with ones on its unused diagonal.
    fn gram(&self, g: &BodyGrad, q: &[f64], t: &mut [Vector3<f64>]) -> Matrix3<f64> {
        let (x, _) = self.tip(g);
        for (tc, col) in t.iter_mut().zip(&self.columns) {
            let z = self.axis(g, &col.axis);
            *tc = match &col.origin {
                Some((f, k)) => z.cross(&(x - self.origin(g, q, *f, k).0)),
                None => z,
            };
        }
        let (m, n) = (self.rows, self.columns.len());
        let r2 = self.reach_m * self.reach_m;
        let d = &self.directions;
        let mut gm = Matrix3::identity();
        if m <= n {
            for a in 0..m {
                for b in 0..m {
                    gm[(a, b)] = t[..n]
                        .iter()
                        .map(|tc| d[a].dot(tc) * d[b].dot(tc))
                        .sum::<f64>()
                        / r2;
                }
            }
        } else {
            for a in 0..n {
                let pa = self.project(&t[a]);
                for b in 0..n {
                    gm[(a, b)] = pa.dot(&t[b]) / r2;
                }
            }
        }
        gm
    }

    /// P t = Σ_r d_r (d_r · t).
    fn project(&self, t: &Vector3<f64>) -> Vector3<f64> {
        self.directions[..self.rows]
            .iter()
            .map(|d| d * d.dot(t))
            .sum()
    }

    /// F = −½ R² ln(det G + ε) at q (frames in `g`), using `t` as scratch.
    pub fn value(&self, g: &BodyGrad, q: &[f64], t: &mut [Vector3<f64>]) -> f64 {
        let det = self.gram(g, q, t).determinant().max(0.0);
        -0.5 * self.reach_m * self.reach_m * (det + DET_FLOOR).ln()
    }

    /// Eq. 14 with the floor: f = (det G + ε)^(−1/2).
    pub fn report(&self, g: &BodyGrad, q: &[f64], t: &mut [Vector3<f64>]) -> f64 {
        let det = self.gram(g, q, t).determinant().max(0.0);
        1.0 / (det + DET_FLOOR).sqrt()
    }

    /// F, and `w` × ∂F into `g` (free anchors straight into `out`).
    pub fn gradient(
        &self,
        g: &mut BodyGrad,
        q: &[f64],
        t: &mut [Vector3<f64>],
        w: f64,
        out: &mut [f64],
    ) -> f64 {
        let gm = self.gram(g, q, t);
        let det = gm.determinant().max(0.0);
        let adj = adjugate(&gm);
        let r = self.reach_m;
        let value = -0.5 * r * r * (det + DET_FLOOR).ln();
        let kappa = w * -0.5 * r * r / (det + DET_FLOOR);
        let (m, n) = (self.rows, self.columns.len());
        let d = &self.directions;
        let (x, x_lever) = self.tip(g);
        for c in 0..n {
            // β_c: ∂ det G = Σ_c β_c · ∂t_c.
            let beta: Vector3<f64> = if m <= n {
                let v = Vector3::from_fn(|a, _| if a < m { d[a].dot(&t[c]) / r } else { 0.0 });
                let av = adj * v;
                (0..m).map(|a| d[a] * av[a]).sum::<Vector3<f64>>() * (2.0 / r)
            } else {
                (0..n)
                    .map(|a| self.project(&t[a]) * adj[(a, c)])
                    .sum::<Vector3<f64>>()
                    * (2.0 / (r * r))
            };
            let beta = beta * kappa;
            let col = self.columns[c];
            let z = self.axis(g, &col.axis);
            match col.origin {
                Some((f, k)) => {
                    let (o, o_lever) = self.origin(g, q, f, &k);
                    let v = x - o;
                    if let Axis::Body(fz, _) = col.axis {
                        g.direction(BodyId(fz as u32), &z, &v.cross(&beta));
                    }
                    let n_x = beta.cross(&z);
                    g.point(self.tip.0, &x_lever, &n_x);
                    g.point(BodyId(f as u32), &o_lever, &-n_x);
                    if let Param3::Free(col) = k {
                        g.anchor(BodyId(f as u32), col, &-n_x, out);
                    }
                }
                None => {
                    if let Axis::Body(fz, _) = col.axis {
                        g.direction(BodyId(fz as u32), &z, &beta);
                    }
                }
            }
        }
        value
    }
}

/// adj(A) = cofactor matrixᵀ, finite for a singular A (A adj(A) = det(A) I).
fn adjugate(a: &Matrix3<f64>) -> Matrix3<f64> {
    let c = |r0: usize, r1: usize, c0: usize, c1: usize| {
        a[(r0, c0)] * a[(r1, c1)] - a[(r0, c1)] * a[(r1, c0)]
    };
    #[rustfmt::skip]
    let adj = Matrix3::new(
        c(1, 2, 1, 2), -c(0, 2, 1, 2), c(0, 1, 1, 2),
        -c(1, 2, 0, 2), c(0, 2, 0, 2), -c(0, 1, 0, 2),
        c(1, 2, 0, 1), -c(0, 2, 0, 1), c(0, 1, 0, 1),
    );
    adj
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn adjugate_times_matrix_is_det_identity() {
        let a = Matrix3::new(2.0, 0.3, -1.0, 0.5, 1.5, 0.2, -0.7, 0.1, 0.9);
        let p = a * adjugate(&a);
        assert!((p - Matrix3::identity() * a.determinant()).norm() < 1e-12);
        let singular = Matrix3::new(1.0, 2.0, 3.0, 2.0, 4.0, 6.0, 0.0, 1.0, 1.0);
        assert!(adjugate(&singular).iter().all(|v| v.is_finite()));
        assert!((singular * adjugate(&singular)).norm() < 1e-12);
    }
}
