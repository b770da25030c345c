//! Shared fixtures: seeded perturbations and the test structures built with
//! the model builder (the 212-variable chain, a hub with spokes, a chain of
//! the same size for comparison).

use haptloop_solver::{
    BodySpec, DesignParam, FingerSpec, JointKind, JointSpec, Model, ModelBuilder,
};
use nalgebra::{UnitQuaternion, Vector3};

/// xorshift64*: a fixed-seed generator (no dependency).
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Self {
        Self(seed.max(1))
    }

    /// Uniform in [0, 1).
    pub fn uniform(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11) as f64 / (1u64 << 53) as f64
    }

    /// A uniformly random unit vector.
    pub fn unit(&mut self) -> Vector3<f64> {
        loop {
            let v = Vector3::new(self.uniform(), self.uniform(), self.uniform()) * 2.0
                - Vector3::repeat(1.0);
            let n = v.norm();
            if n > 0.1 && n <= 1.0 {
                return v / n;
            }
        }
    }
}

/// q with every moving body shifted by `dist_m` and turned by `angle_rad`
/// about random directions (seeded).
pub fn perturbed(model: &Model, q: &[f64], dist_m: f64, angle_rad: f64, seed: u64) -> Vec<f64> {
    let mut rng = Rng::new(seed);
    let mut out = q.to_vec();
    for (_, o) in model.layout().moving_bodies() {
        let dr = rng.unit() * dist_m;
        for k in 0..3 {
            out[o + k] += dr[k];
        }
        let rot =
            UnitQuaternion::from_axis_angle(&nalgebra::Unit::new_normalize(rng.unit()), angle_rad);
        let e = nalgebra::Quaternion::new(out[o + 3], out[o + 4], out[o + 5], out[o + 6]);
        let e = rot.quaternion() * e;
        out[o + 3..o + 7].copy_from_slice(&[e.w, e.i, e.j, e.k]);
    }
    out
}

/// The 212-variable test system (Choi & Cremer's size): a zig-zag chain of
/// 30 bodies (10 cm apart along x, alternately ±2 cm in y, so it is not
/// stretched straight, which would be a singular toggle), spherical joints
/// half-way between neighbours, both ends spherical-jointed to a fixed
/// ground, four distance struts between bodies 3 apart (two with free
/// length: the 2 design variables), a point finger on body 15.
/// 212 coordinates, 130 rows, 1 459 nonzeros in C_q.
pub fn chain212() -> Model {
    let n = 30;
    let p = |i: usize| {
        [
            0.1 * i as f64,
            if i.is_multiple_of(2) { 0.02 } else { -0.02 },
            0.0,
        ]
    };
    let mut b = ModelBuilder::new();
    b.body(BodySpec::fixed("ground"));
    for i in 0..n {
        b.body(BodySpec::new(format!("b{i}")).at(p(i)).mass(0.01));
    }
    let sub = |a: [f64; 3], o: [f64; 3]| -> [f64; 3] { std::array::from_fn(|k| a[k] - o[k]) };
    let mid =
        |a: [f64; 3], c: [f64; 3]| -> [f64; 3] { std::array::from_fn(|k| 0.5 * (a[k] + c[k])) };
    let first = sub(p(0), [0.05, 0.0, 0.0]);
    b.joint(JointSpec::new(JointKind::Spherical, "ground", "b0").anchors(first, sub(first, p(0))));
    for i in 0..n - 1 {
        let m = mid(p(i), p(i + 1));
        b.joint(
            JointSpec::new(JointKind::Spherical, format!("b{i}"), format!("b{}", i + 1))
                .anchors(sub(m, p(i)), sub(m, p(i + 1))),
        );
    }
    let last = [p(n - 1)[0] + 0.05, p(n - 1)[1], 0.0];
    b.joint(
        JointSpec::new(JointKind::Spherical, "ground", format!("b{}", n - 1))
            .anchors(last, sub(last, p(n - 1))),
    );
    for (k, i) in [3usize, 10, 17, 24].into_iter().enumerate() {
        let mut j = JointSpec::new(JointKind::Distance, format!("b{i}"), format!("b{}", i + 3))
            .anchors([0.0, 0.0, 0.02], [0.0, 0.0, 0.02]);
        if k % 2 == 0 {
            j = j.free(&[DesignParam::Length]);
        }
        b.joint(j);
    }
    b.finger(FingerSpec::point("index", "b15", [0.0, 0.0, 0.005]));
    b.build().expect("chain212 is valid")
}

/// Choi & Cremer's star (§5.1): a hub body spherical-jointed to a fixed
/// ground at its centre and to `spokes` bodies around it, each joined only to
/// the hub, so the hub's 7 columns of C_q have 3·spokes + 4 entries. With
/// `chain = true`, the same bodies and joint count but each spoke joined to the
/// previous spoke instead (spoke 0 to the hub): the sparse comparison case.
/// Finger on spoke 0.
pub fn hub(spokes: usize, chain: bool) -> Model {
    let mut b = ModelBuilder::new();
    b.body(BodySpec::fixed("ground"));
    b.body(BodySpec::new("hub"));
    b.joint(JointSpec::new(JointKind::Spherical, "ground", "hub"));
    let dir = |k: usize| {
        let t = 2.0 * std::f64::consts::PI * k as f64 / spokes as f64;
        [t.cos(), t.sin(), 0.0]
    };
    let centre = |k: usize| dir(k).map(|v| 0.1 * v);
    for k in 0..spokes {
        let name = format!("s{k}");
        b.body(BodySpec::new(&name).at(centre(k)));
        // The joint point: half-way between the spoke and the hub (star) or
        // between the spoke and its predecessor (chain).
        let (other, other_at) = if chain && k > 0 {
            (format!("s{}", k - 1), centre(k - 1))
        } else {
            ("hub".to_owned(), [0.0; 3])
        };
        let c = centre(k);
        let p: [f64; 3] = std::array::from_fn(|i| 0.5 * (c[i] + other_at[i]));
        let rel = |o: [f64; 3]| -> [f64; 3] { std::array::from_fn(|i| p[i] - o[i]) };
        b.joint(JointSpec::new(JointKind::Spherical, other, &name).anchors(rel(other_at), rel(c)));
    }
    b.finger(FingerSpec::point("index", "s0", [0.0, 0.0, 0.01]));
    b.build().expect("hub is valid")
}

/// ‖C‖₂ over the equality rows and min(C, 0) over the inequality rows at q.
pub fn residual(model: &Model, q: &[f64], targets: &[haptloop_solver::FingerTarget]) -> f64 {
    let mut ev = model.evaluation();
    ev.evaluate(model, q, targets).expect("evaluate");
    let eq = model.equality_rows().end;
    ev.values()
        .iter()
        .enumerate()
        .map(|(k, v)| if k < eq { *v } else { v.min(0.0) })
        .map(|v| v * v)
        .sum::<f64>()
        .sqrt()
}

/// All entries finite.
pub fn finite(v: &[f64]) -> bool {
    v.iter().all(|x| x.is_finite())
}
