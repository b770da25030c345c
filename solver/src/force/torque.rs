//! Joint torques (Nelson & Cohen §5.2): "this force and torque may be
//! projected in the direction of a joint axis to provide the amount of
//! torque required by a controls system to produce a motion".
//!
//! For the joints a scene names (`report_torque`), each a motor on its axis:
//! what those motors would have to apply, instead of the user's fingers, for
//! the mechanism to make the motion it makes. Each motor is a row a_i = ∂θ_i
//! (the joint's coordinate: a revolute's angle, a prismatic's slide; see
//! `constraint::limit`) added to Eq. 7 in place of the finger rows; its
//! multiplier μ_i is the constraint force of that row, the joint's load
//! projected onto its axis, and the motor applies τ_i = −μ_i (Eq. 6's sign:
//! M q̈ + C_qᵀλ = Q, so a row's force on the mechanism is −aᵀμ). With the
//! joints' rows J (the Eq. 7 matrix A_JJ = D C_J M⁻¹ C_Jᵀ D and its factor,
//! active limits and contacts included) eliminated:
//!
//! ```text
//! y_i = M⁻¹ a_iᵀ − M⁻¹ C_Jᵀ D A_JJ⁻¹ D C_J M⁻¹ a_iᵀ      (the motion a unit of motor i makes)
//! S_ij = a_i · y_j,   r_i = y_i · b,   μ = S⁺ r,   τ = −μ
//! ```
//!
//! with b = Q_e + Q_v − M q̈ of the tick (Eq. 7's right-hand side). For a
//! mechanism whose named joints drive every degree of freedom this is the
//! usual inverse-dynamics torque, the generalised force along each joint's
//! coordinate with the others held (a pendulum held still: τ = m g l sin θ
//! from hanging); with fewer, the rest of the mechanism moves freely with
//! least inertia; two named joints locked to each other (a gear pair) split
//! the load with the smallest norm (S⁺). A joint held at a limit has no free
//! motion left: its torque is 0 (the limit carries the load).
//!
//! # Real-time
//! No allocation (buffers sized by `new`); per named joint one coordinate,
//! one M⁻¹ product, C_q·v, C_qᵀ·v and a pair of triangular solves with the
//! tick's factor, then a k × k pseudo-inverse.

use super::gram::{Gram, Slot};
use super::inertia::BodyMass;
use super::small::min_norm_solve;
use super::solve::MultiplierSolve;
use crate::constraint::Geometry;
use crate::constraint::block::{Ctx, Pair, RowGrad};
use crate::constraint::limit::Limited;
use crate::{Evaluation, Model};

/// The named joints' coordinates and every buffer of their solve.
#[derive(Debug, Clone)]
pub(crate) struct JointTorques {
    joints: Vec<Limited>,
    n: usize,
    /// k × n: the motors' rows a_i, then their motions y_i.
    a: Vec<f64>,
    y: Vec<f64>,
    /// Scratch: one per row of C, one per J row, one per coordinate.
    rows: Vec<f64>,
    joint_rows: Vec<f64>,
    coords: Vec<f64>,
    minv: Vec<f64>,
    /// k × k, k, k × k.
    s: Vec<f64>,
    r: Vec<f64>,
    eig: Vec<f64>,
    /// τ_i of the last solve: N·m (revolute) or N (prismatic); NaN when the
    /// last tick failed.
    pub torque: Vec<f64>,
    /// The model's deforming points (a motor joint on a flexible body).
    flex: Vec<crate::flexible::anchor::FlexAnchor>,
}

impl JointTorques {
    /// For `model`'s named joints with `n_j` rows in the Eq. 7 solve; `None`
    /// when it names none. Allocates.
    pub fn new(model: &Model, n_j: usize) -> Option<Self> {
        let joints: Vec<Limited> = model
            .torque_joints()
            .iter()
            .filter_map(|c| match model.geometry[c.index()] {
                Geometry::Revolute(j) => Some(Limited::Angle(j)),
                Geometry::Prismatic(j) => Some(Limited::Displacement(j)),
                _ => None,
            })
            .collect();
        if joints.is_empty() {
            return None;
        }
        let (k, n, m) = (joints.len(), model.n_coords(), model.n_rows());
        Some(Self {
            joints,
            n,
            a: vec![0.0; k * n],
            y: vec![0.0; k * n],
            rows: vec![0.0; m],
            joint_rows: vec![0.0; n_j],
            coords: vec![0.0; n],
            minv: vec![0.0; n],
            s: vec![0.0; k * k],
            r: vec![0.0; k],
            eig: vec![0.0; k * k],
            torque: vec![f64::NAN; k],
            flex: model.flex_anchors.clone(),
        })
    }

    /// Marks the torques unknown (a failed tick).
    pub fn clear(&mut self) {
        self.torque.fill(f64::NAN);
    }

    /// τ for the factor `solve` holds of `gram` (rows scaled by `scale`),
    /// the tick's right-hand side `b` and the evaluation `ev` at `q`.
    ///
    /// # Real-time
    /// See the module docs.
    #[allow(clippy::too_many_arguments)]
    pub fn compute(
        &mut self,
        gram: &Gram,
        solve: &mut MultiplierSolve,
        masses: &[BodyMass],
        scale: &[f64],
        b: &[f64],
        q: &[f64],
        ev: &Evaluation,
    ) {
        let (k, n) = (self.joints.len(), self.n);
        let x = Ctx {
            q,
            frames: ev.frames(),
            targets: &[],
            witnesses: &[],
            flex: &self.flex,
            surfaces: &[],
            rolling: &[],
        };
        let jac = ev.jacobian();
        for i in 0..k {
            let (_, g) = match &self.joints[i] {
                Limited::Angle(j) => j.coordinate(&x),
                Limited::Displacement(j) => j.coordinate(&x),
                Limited::Length(j) => j.coordinate(&x),
            };
            let pair = *limited_pair(&self.joints[i]);
            let a = &mut self.a[i * n..(i + 1) * n];
            columns(&pair, &g, ev, a);
            // u = M⁻¹ aᵀ, then u − M⁻¹ C_Jᵀ D A_JJ⁻¹ D C_J u.
            let y = &mut self.y[i * n..(i + 1) * n];
            gram.apply_inverse_mass(masses, a, y);
            if jac.mul_vec(y, &mut self.rows).is_err() {
                self.torque.fill(f64::NAN);
                return;
            }
            for (j, &row) in gram.j_rows.iter().enumerate() {
                self.joint_rows[j] = scale[row] * self.rows[row];
            }
            solve.solve_joint(&mut self.joint_rows);
            for (row, v) in self.rows.iter_mut().enumerate() {
                *v = match gram.slot[row] {
                    Slot::J(j) => scale[row] * self.joint_rows[j],
                    Slot::F(_) | Slot::Out => 0.0,
                };
            }
            let _ = jac.mul_t_vec(&self.rows, &mut self.coords);
            gram.apply_inverse_mass(masses, &self.coords, &mut self.minv);
            for (yc, mc) in y.iter_mut().zip(&self.minv) {
                *yc -= mc;
            }
        }
        for i in 0..k {
            let yi = &self.y[i * n..(i + 1) * n];
            self.r[i] = dot(yi, b);
            for j in 0..k {
                self.s[i * k + j] = dot(&self.a[i * n..(i + 1) * n], &self.y[j * n..(j + 1) * n]);
            }
        }
        // Symmetric in exact arithmetic (a_i M⁻¹ P a_j); symmetrise round-off.
        for i in 0..k {
            for j in 0..i {
                let v = 0.5 * (self.s[i * k + j] + self.s[j * k + i]);
                self.s[i * k + j] = v;
                self.s[j * k + i] = v;
            }
        }
        let reference = (0..k).map(|i| self.s[i * k + i]).fold(0.0, f64::max);
        min_norm_solve(
            &mut self.s,
            &self.r,
            &mut self.torque,
            &mut self.eig,
            reference,
        );
        for t in &mut self.torque {
            *t = -*t;
        }
    }
}

fn limited_pair(l: &Limited) -> &Pair {
    match l {
        Limited::Angle(j) => &j.pair,
        Limited::Displacement(j) => &j.pair,
        Limited::Length(j) => &j.pair,
    }
}

/// A row gradient of `pair`'s ends written into q's columns (r: δr part;
/// e: Ωᵀ times the δθ part), zero elsewhere.
fn columns(pair: &Pair, g: &RowGrad, ev: &Evaluation, out: &mut [f64]) {
    out.fill(0.0);
    for end in 0..2 {
        let Some(o) = pair.col[end] else { continue };
        let f = &ev.frames()[pair.frame[end]];
        out[o..o + 3].copy_from_slice(g.lin[end].as_slice());
        let de = f.omega.tr_mul(&g.ang[end]);
        out[o + 3..o + 7].copy_from_slice(de.as_slice());
    }
}

#[inline]
fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}
