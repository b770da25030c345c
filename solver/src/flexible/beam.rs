//! The beam of a flexible body: Euler–Bernoulli bending along the body's x
//! axis in its y and z directions, by a Rayleigh–Ritz basis of monomials
//! clamped to the body frame at x = x_c (the `clamp`, default 0).
//!
//! With ℓ = max(|x₀ − x_c|, |x₁ − x_c|) over the span [x₀, x₁] and
//! ξ = (x − x_c)/ℓ, the n shape functions of each direction are
//! φ_j = ξ^(j+2), j = 0 … n − 1: zero value and zero slope at the clamp (the
//! floating frame is the beam's tangent frame there; its origin stays the
//! body's, its centre of mass), polynomials of degree 2 … n + 1. Deflections v(x) (along y) and
//! w(x) (along z) are
//!
//! ```text
//! v(x) = Σ_j q_y,j φ_j(x),   w(x) = Σ_j q_z,j φ_j(x)          (q in metres)
//! ```
//!
//! and a section point (x, y, z) of the body moves by
//! (−y v′ − z w′, v, w) in the body frame (sections stay plane and normal to
//! the neutral axis). Per direction, with bending stiffness EI and mass per
//! length μ (the body's mass over the span):
//!
//! ```text
//! K_ij = EI ∫ φ_i″ φ_j″ dx,   M_ij = μ ∫ φ_i φ_j dx,   g_j = μ ∫ φ_j dx
//! ```
//!
//! in closed form (monomials). The strain energy is U = ½ q_fᵀ K q_f
//! (Nelson & Cohen Eq. 4), its force −K q_f (Eq. 6's K_f q_f), the elastic
//! inertia M q̈_f and the gravity load g_j (Rᵀ gravity)_{y,z} per mode.
//!
//! A cantilever of length L under a tip load P deflects by
//! v(x) = P x² (3L − x) / (6 EI), a cubic: with n ≥ 2 it lies in the basis and
//! the Ritz solution is exact (tip deflection P L³/(3EI), tip slope
//! P L²/(2EI)); with n = 1 (ξ² alone) the tip is 4/3 too stiff.

use nalgebra::DMatrix;

/// The most modes per bending direction.
pub const MAX_MODES: usize = 4;

/// A `flexible` table: the beam a body bends as.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BeamSpec {
    /// `[x₀, x₁]`: the beam's extent along the body's x axis, metres, body
    /// frame, x₀ < x₁.
    pub span_m: [f64; 2],
    /// x_c: the section (body x, metres, on the span) where the body frame
    /// is the beam's tangent frame: points there do not move with the
    /// deformation, and joints that use the body's axes sit there.
    pub clamp_m: f64,
    /// Bending stiffness EI for deflection along the body's y and z axes,
    /// N·m² (> 0).
    pub stiffness_n_m2: [f64; 2],
    /// Shape functions per direction, 1 … [`MAX_MODES`].
    pub modes: usize,
}

impl BeamSpec {
    /// A beam over `span_m` clamped at x = 0, with the same EI in both
    /// directions.
    pub fn new(span_m: [f64; 2], ei_n_m2: f64, modes: usize) -> Self {
        Self {
            span_m,
            clamp_m: 0.0,
            stiffness_n_m2: [ei_n_m2; 2],
            modes,
        }
    }

    /// ℓ, the normalising length, metres.
    pub fn scale_m(&self) -> f64 {
        (self.span_m[0] - self.clamp_m)
            .abs()
            .max((self.span_m[1] - self.clamp_m).abs())
    }

    /// What is wrong with the spec, if anything: `(field, why)`.
    pub fn check(&self) -> Result<(), (&'static str, &'static str)> {
        let [x0, x1] = self.span_m;
        if !(x0.is_finite() && x1.is_finite() && x1 > x0) {
            return Err(("span", "must be finite with x0 < x1"));
        }
        if !(self.clamp_m >= x0 && self.clamp_m <= x1) {
            return Err(("clamp", "must lie on the span"));
        }
        if !self
            .stiffness_n_m2
            .iter()
            .all(|k| k.is_finite() && *k > 0.0)
        {
            return Err(("stiffness", "must be finite and > 0 N·m²"));
        }
        if !(1..=MAX_MODES).contains(&self.modes) {
            return Err(("modes", "must be 1 to 4"));
        }
        Ok(())
    }
}

/// φ_j(x) and φ_j′(x) of the n shape functions at body x.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Shape {
    pub phi: [f64; MAX_MODES],
    pub slope: [f64; MAX_MODES],
}

/// The compiled beam: its stiffness, modal mass and gravity load (one
/// direction's n × n; both directions share them up to EI).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Beam {
    pub spec: BeamSpec,
    /// K of one direction with EI = 1, n × n.
    pub unit_stiffness: DMatrix<f64>,
    /// M of one direction, n × n, kg.
    pub mass: DMatrix<f64>,
    /// g_j = μ ∫ φ_j dx, kg·m (times an acceleration: a force).
    pub load: [f64; MAX_MODES],
}

/// ∫_{ξ₀}^{ξ₁} ξ^p dξ.
fn moment(xi: [f64; 2], p: i32) -> f64 {
    (xi[1].powi(p + 1) - xi[0].powi(p + 1)) / f64::from(p + 1)
}

impl Beam {
    /// The matrices of `spec` (already checked) for a body of `mass_kg`.
    pub fn new(spec: BeamSpec, mass_kg: f64) -> Self {
        let n = spec.modes;
        let l = spec.scale_m();
        let c = spec.clamp_m;
        let xi = [(spec.span_m[0] - c) / l, (spec.span_m[1] - c) / l];
        let mu = mass_kg / (spec.span_m[1] - spec.span_m[0]);
        let deg = |j: usize| j as i32 + 2;
        let unit_stiffness = DMatrix::from_fn(n, n, |i, j| {
            let (a, b) = (deg(i), deg(j));
            let c = f64::from(a * (a - 1) * b * (b - 1));
            c / l.powi(3) * moment(xi, a + b - 4)
        });
        let mass = DMatrix::from_fn(n, n, |i, j| mu * l * moment(xi, deg(i) + deg(j)));
        let mut load = [0.0; MAX_MODES];
        for (j, g) in load.iter_mut().enumerate().take(n) {
            *g = mu * l * moment(xi, deg(j));
        }
        Self {
            spec,
            unit_stiffness,
            mass,
            load,
        }
    }

    /// Modes per direction.
    pub fn modes(&self) -> usize {
        self.spec.modes
    }

    /// The full 2n × 2n stiffness, y modes then z modes, N/m.
    pub fn stiffness(&self) -> DMatrix<f64> {
        let n = self.modes();
        let mut k = DMatrix::zeros(2 * n, 2 * n);
        for (d, ei) in self.spec.stiffness_n_m2.iter().enumerate() {
            k.view_mut((d * n, d * n), (n, n))
                .copy_from(&(&self.unit_stiffness * *ei));
        }
        k
    }

    /// The full 2n × 2n modal mass, kg.
    pub fn modal_mass(&self) -> DMatrix<f64> {
        let n = self.modes();
        let mut m = DMatrix::zeros(2 * n, 2 * n);
        for d in 0..2 {
            m.view_mut((d * n, d * n), (n, n)).copy_from(&self.mass);
        }
        m
    }

    /// φ_j and φ_j′ at body x.
    pub fn shape(&self, x: f64) -> Shape {
        let l = self.spec.scale_m();
        let xi = (x - self.spec.clamp_m) / l;
        let mut s = Shape {
            phi: [0.0; MAX_MODES],
            slope: [0.0; MAX_MODES],
        };
        for j in 0..self.modes() {
            let d = j as i32 + 2;
            s.phi[j] = xi.powi(d);
            s.slope[j] = f64::from(d) / l * xi.powi(d - 1);
        }
        s
    }

    /// Whether body x lies on the span (1 µm of slack for written digits).
    pub fn covers(&self, x: f64) -> bool {
        x >= self.spec.span_m[0] - 1e-6 && x <= self.spec.span_m[1] + 1e-6
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Composite Simpson over [a, b] with 2000 panels.
    fn simpson(f: impl Fn(f64) -> f64, a: f64, b: f64) -> f64 {
        let n = 2000;
        let h = (b - a) / n as f64;
        let mut s = f(a) + f(b);
        for k in 1..n {
            s += f(a + k as f64 * h) * if k % 2 == 1 { 4.0 } else { 2.0 };
        }
        s * h / 3.0
    }

    /// The closed-form integrals against quadrature of the shape functions,
    /// on a span across the origin.
    #[test]
    fn matrices_match_quadrature() {
        let spec = BeamSpec {
            clamp_m: -0.02,
            ..BeamSpec::new([-0.05, 0.12], 1.0, 4)
        };
        let beam = Beam::new(spec, 0.3);
        let mu = 0.3 / 0.17;
        let (l, c) = (0.14, -0.02);
        let phi = |j: usize, x: f64| ((x - c) / l).powi(j as i32 + 2);
        let dd = |j: usize, x: f64| {
            let d = j as i32 + 2;
            f64::from(d * (d - 1)) / (l * l) * ((x - c) / l).powi(d - 2)
        };
        for i in 0..4 {
            let g = simpson(|x| mu * phi(i, x), -0.05, 0.12);
            assert!(
                (beam.load[i] - g).abs() < 1e-12 * g.abs().max(1e-9),
                "load {i}"
            );
            for j in 0..4 {
                let k = simpson(|x| dd(i, x) * dd(j, x), -0.05, 0.12);
                let m = simpson(|x| mu * phi(i, x) * phi(j, x), -0.05, 0.12);
                let rel = |a: f64, b: f64| (a - b).abs() / b.abs().max(1e-12);
                assert!(rel(beam.unit_stiffness[(i, j)], k) < 1e-9, "K {i}{j}");
                assert!(rel(beam.mass[(i, j)], m) < 1e-9, "M {i}{j}");
            }
        }
    }

    /// Static condensation of the tip: Φ K⁻¹ Φᵀ is the tip compliance,
    /// L³/(3EI) with two or more modes and 3/4 of it with one.
    #[test]
    fn tip_compliance_is_beam_theory_with_two_modes() {
        let (l, ei) = (0.2, 0.7);
        for (modes, want) in [(1, 0.75), (2, 1.0), (3, 1.0), (4, 1.0)] {
            let beam = Beam::new(BeamSpec::new([0.0, l], ei, modes), 0.1);
            let k = &beam.unit_stiffness * ei;
            let s = beam.shape(l);
            let phi = nalgebra::DVector::from_column_slice(&s.phi[..modes]);
            let c = phi.dot(&(k.clone().try_inverse().unwrap() * &phi));
            let exact = l.powi(3) / (3.0 * ei);
            assert!((c / exact - want).abs() < 1e-10, "{modes}: {}", c / exact);
        }
    }
}
