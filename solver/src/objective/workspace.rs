//! `workspace_volume` (Nelson & Cohen App. D: "maximizing workspace volume
//! ... for mechanical design"): the volume a chain's point can reach,
//! maximised over its link lengths (free anchors).
//!
//! The chain is a `dexterity`-style chain of bodies (base first) joined by
//! revolute, spherical or universal joints; body k's link length l_k is the
//! body-frame distance between its inbound joint's anchor and its outbound
//! joint's (the last body's: to the point x). With every joint turning
//! fully (a chain of spherical joints, no limits; an upper bound for
//! revolutes and universals, whose reach is a subset) the reachable set is
//! the spherical shell about the first joint of radii
//!
//! ```text
//! R_max = Σ l_k,   R_min = max(0, l_max − (Σ l_k − l_max)),   V = 4/3 π (R_max³ − R_min³)
//! ```
//!
//! (two links: 4/3 π ((l1 + l2)³ − |l1 − l2|³)). In m² like every term:
//!
//! ```text
//! F = −(L² / 3) ln(V / V₀)             (V₀ at q0, L the model's length scale)
//! ∂F = −(L² / 3) ∂V / V,  ∂V/∂l_k = 4π (R_max² − R_min² ∂R_min/∂l_k),  ∂R_min/∂l_k = ±1 or 0
//! ```
//!
//! so F is 0 at the start and falls as the shell grows, scale-free like
//! `dexterity`'s log form. The lengths depend only on anchors (body-frame
//! constants unless free), so F moves only free anchors; its gradient jumps
//! where R_min reaches 0 or two links tie for longest. Reported value: V,
//! m³.

use std::f64::consts::PI;

use nalgebra::Vector3;

use crate::constraint::block::Param3;

/// One link: its inbound and outbound anchor on the same body (body frame).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Link {
    pub inbound: Param3,
    pub outbound: Param3,
}

/// The reachable volume of a chain's point.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Workspace {
    pub links: Vec<Link>,
    /// L², m².
    pub scale_m2: f64,
    /// V₀, m³ (> 0).
    pub v0_m3: f64,
}

fn at(q: &[f64], p: &Param3) -> Vector3<f64> {
    match *p {
        Param3::Const(v) => v,
        Param3::Free(c) => Vector3::new(q[c], q[c + 1], q[c + 2]),
        // Refused when the objective is compiled (`objective::compile`).
        Param3::Flex(_) => Vector3::repeat(f64::NAN),
    }
}

/// Shell radii of links of lengths `l`: (R_max, R_min, index of the longest).
fn shell(l: impl Iterator<Item = f64> + Clone) -> (f64, f64, usize) {
    let sum: f64 = l.clone().sum();
    let (k, longest) = l.enumerate().fold(
        (0, f64::NEG_INFINITY),
        |a, (k, x)| if x > a.1 { (k, x) } else { a },
    );
    (sum, (2.0 * longest - sum).max(0.0), k)
}

/// 4/3 π (R_max³ − R_min³).
pub(crate) fn shell_volume(r_max: f64, r_min: f64) -> f64 {
    4.0 / 3.0 * PI * (r_max.powi(3) - r_min.powi(3))
}

impl Workspace {
    fn length(&self, q: &[f64], k: usize) -> (f64, Vector3<f64>) {
        let d = at(q, &self.links[k].outbound) - at(q, &self.links[k].inbound);
        (d.norm(), d)
    }

    /// V at `q`, m³.
    pub fn volume(&self, q: &[f64]) -> f64 {
        let (r_max, r_min, _) = shell((0..self.links.len()).map(|k| self.length(q, k).0));
        shell_volume(r_max, r_min)
    }

    /// F at `q`.
    pub fn value(&self, q: &[f64]) -> f64 {
        let v = self.volume(q).max(1e-300);
        -self.scale_m2 / 3.0 * (v / self.v0_m3).ln()
    }

    /// F, and `w` × ∂F into `out` (free anchor columns only).
    pub fn gradient(&self, q: &[f64], w: f64, out: &mut [f64]) -> f64 {
        let n = self.links.len();
        let (r_max, r_min, longest) = shell((0..n).map(|k| self.length(q, k).0));
        let v = shell_volume(r_max, r_min);
        // Also a NaN volume: no gradient.
        if v.is_nan() || v <= 0.0 {
            return self.value(q);
        }
        let c = -w * self.scale_m2 / 3.0 / v;
        for k in 0..n {
            let (l, d) = self.length(q, k);
            if l == 0.0 {
                continue;
            }
            let d_rmin = match (r_min > 0.0, k == longest) {
                (false, _) => 0.0,
                (true, true) => 1.0,
                (true, false) => -1.0,
            };
            let dv = 4.0 * PI * (r_max * r_max - r_min * r_min * d_rmin);
            let n_l = d / l * (c * dv);
            if let Param3::Free(col) = self.links[k].outbound {
                (0..3).for_each(|j| out[col + j] += n_l[j]);
            }
            if let Param3::Free(col) = self.links[k].inbound {
                (0..3).for_each(|j| out[col + j] -= n_l[j]);
            }
        }
        -self.scale_m2 / 3.0 * (v / self.v0_m3).ln()
    }
}
