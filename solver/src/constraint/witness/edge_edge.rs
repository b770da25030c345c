//! Edge–edge (Choi & Cremer §3.1.4, Eq. 2–3). Edge E_A (point V_p, unit
//! direction V_e) on one end; on the other, edge E_B with one of its adjacent
//! face planes EP1 (point F_p on E_B, unit normal F_pn) and its separating
//! plane SP (through E_B, normal S_pn = the mean of its faces' normals). The
//! intersection point of E_A's line with EP1,
//!
//! ```text
//! IP = V_p + t V_e,   t = ((F_p − V_p)·F_pn) / (V_e·F_pn)          (Eq. 2)
//! C  = (IP − F_p)·S_pn − m ≥ 0                                      (Eq. 3)
//! ```
//!
//! is kept analytic in q (all five vectors move with their bodies). With
//! D = V_e·F_pn and k = (V_e·S_pn)/D, the gradient is
//!
//! ```text
//! ∂C/∂V_p = S_pn − k F_pn = −∂C/∂F_p,   ∂C/∂V_e = t ∂C/∂V_p,
//! ∂C/∂F_pn = k (F_p − IP),              ∂C/∂S_pn = IP − F_p.
//! ```
//!
//! EP1 is the face of E_B least parallel to E_A (largest |D|). Where D → 0
//! (E_A parallel to EP1) the division is guarded: |D| is clamped to
//! [`MIN_DENOMINATOR`] with its sign kept, the gradient treats the clamped D
//! as constant, and the value stays finite. Parallel edges (E_A parallel to
//! both faces, i.e. to E_B) are not an edge–edge witness at all: the
//! constructor refuses them and the caller reduces the pair to vertex–edge
//! primitives.

use nalgebra::{Matrix3, Vector3};

use super::{FeatureKey, WitnessType, ends};
use crate::constraint::block::{Ctx, Pair, RowGrad};

/// Smallest |V_e·F_pn| used in Eq. 2 (the sine of the angle between E_A and
/// EP1): below it the intersection point is clamped, not divided by ~0.
pub const MIN_DENOMINATOR: f64 = 1e-6;

/// Below this |V_e·F_pn| for both faces of E_B, the edges are parallel and
/// the constructor refuses (the intersection point would run off to
/// infinity within a small rotation).
pub const PARALLEL_SINE: f64 = 1e-2;

/// Eq. 2–3 (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EdgeWitness {
    /// Which witness case produced it.
    pub origin: WitnessType,
    /// The features it was built from.
    pub features: FeatureKey,
    /// End carrying E_A (0 or 1).
    pub edge_end: u8,
    /// V_p, its body's frame.
    pub edge_point: Vector3<f64>,
    /// V_e (unit), its body's frame.
    pub edge_dir: Vector3<f64>,
    /// F_p: a point of E_B (on EP1 and SP), the other body's frame.
    pub face_point: Vector3<f64>,
    /// F_pn (unit), the other body's frame.
    pub face_normal: Vector3<f64>,
    /// S_pn (unit), the other body's frame.
    pub sep_normal: Vector3<f64>,
    /// Metres.
    pub margin: f64,
}

impl EdgeWitness {
    /// Builds the witness of edge `a` (two points, frame of end `edge_end`)
    /// against edge `b` (frame of the other end) with face normals `faces`
    /// and separating normal `sep`. `a_to_b` rotates A-end vectors into the
    /// B end's frame at the current configuration. `None` for parallel edges.
    #[allow(clippy::too_many_arguments)]
    pub fn build(
        edge_end: u8,
        a: [Vector3<f64>; 2],
        b: [Vector3<f64>; 2],
        faces: [Vector3<f64>; 2],
        sep: Vector3<f64>,
        a_to_b: &Matrix3<f64>,
        margin: f64,
        features: FeatureKey,
    ) -> Option<Self> {
        let dir = (a[1] - a[0]).try_normalize(1e-15)?;
        let dir_b = a_to_b * dir;
        let (d0, d1) = (dir_b.dot(&faces[0]).abs(), dir_b.dot(&faces[1]).abs());
        if d0.max(d1) < PARALLEL_SINE {
            return None;
        }
        let face = if d0 >= d1 { faces[0] } else { faces[1] };
        Some(Self {
            origin: WitnessType::EdgeEdge,
            features,
            edge_end,
            edge_point: a[0],
            edge_dir: dir,
            face_point: b[0],
            face_normal: face.normalize(),
            sep_normal: sep.normalize(),
            margin,
        })
    }

    /// Value and gradient.
    #[inline(always)]
    pub(crate) fn row(&self, pair: &Pair, x: &Ctx) -> (f64, RowGrad) {
        let (p, s) = ends(self.edge_end);
        let (fp, fs) = (x.frame(pair.frame[p]), x.frame(pair.frame[s]));
        let lever_v = fp.rot * self.edge_point;
        let v = fp.r + lever_v;
        let e = fp.rot * self.edge_dir;
        let lever_f = fs.rot * self.face_point;
        let f = fs.r + lever_f;
        let n1 = fs.rot * self.face_normal;
        let sn = fs.rot * self.sep_normal;
        let raw = e.dot(&n1);
        let clamped = raw.abs() < MIN_DENOMINATOR;
        let d = if clamped {
            if raw < 0.0 {
                -MIN_DENOMINATOR
            } else {
                MIN_DENOMINATOR
            }
        } else {
            raw
        };
        let t = (f - v).dot(&n1) / d;
        let ip = v + e * t;
        let k = e.dot(&sn) / d;
        let g_v = sn - n1 * k;
        let g_e = if clamped { sn * t } else { g_v * t };
        let g_n1 = if clamped { (f - v) * k } else { (f - ip) * k };
        let mut g = RowGrad::default();
        g.point(p, &lever_v, &g_v)
            .direction(p, &e, &g_e)
            .point(s, &lever_f, &-g_v)
            .direction(s, &n1, &g_n1)
            .direction(s, &sn, &(ip - f));
        ((ip - f).dot(&sn) - self.margin, g)
    }
}
