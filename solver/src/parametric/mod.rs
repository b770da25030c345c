//! Surface contact and rolling (Nelson & Cohen Appendix E, Eq. 16): a point
//! held on a parametric surface with the contact's parameters (u, v) as
//! coordinates, a ball sliding on a curved surface, and a ball rolling on one
//! without slipping (a nonholonomic, velocity-level constraint, stepped as
//! a constraint on each tick's displacement).
//!
//! | file | what |
//! |---|---|
//! | `surface.rs` | surfaces S(u, v): plane, sphere (bowl, dome), cylinder (trough, ridge); offset by a ball's radius |
//! | `contact.rs` | `on_surface`: p_i = r_j + R_j (S + ρ n)(u, v), 3 rows, (u, v) two coordinates |
//! | `rolling.rs` | `rolling`: the contact point's tick displacement has no tangential part, 2 rows |
//! | `rate.rs` | Eq. 16: u̇ = D q̇ in closed form, D = u_q |
//! | `anchor.rs` | the rolling rows' tick-start anchors, set by the program |
//!
//! **Coordinates.** Each surface contact's (u, v) (metres along the
//! surface's local x and y) is an auxiliary block at the end of q named
//! `<joint>.uv` (`model::auxiliary`), with rest "current" (least
//! astonishment) and a small metric (10⁻³ × the point body's mass per m²),
//! so the projected update slides the contact freely and Eq. 7's least
//! squares holds the (u, v) columns' balance (S_uᵀ λ = S_vᵀ λ = 0: the
//! contact force is normal to the surface) far more tightly than the
//! bodies'. The paper obtains the constraint's gradient through the rate
//! of the parametric contact coordinates, u̇ = D q̇ (Eq. 16); with (u, v) as
//! coordinates the solver needs only ∂C/∂(u, v) = −R_j [P_u P_v], and D is
//! what the update's step does to them: `rate.rs` gives D in closed form
//! and a test holds the update's (u, v) to it.
//!
//! **Friction.** `on_surface` is frictionless (a ball sliding); `rolling`
//! adds the two no-slip rows, whose multipliers are the contact's
//! tangential (static friction) force in Eq. 7, unlimited (no Coulomb cone:
//! it rolls, it never slips).

pub(crate) mod anchor;
pub(crate) mod contact;
pub mod rate;
pub mod rolling;
pub mod surface;

pub use contact::SurfaceContact;

/// The metric of a surface contact's (u, v) columns per kilogram of the
/// point's body, per m²: small, so the update slides the contact freely
/// and Eq. 7's weight H⁻¹ on its balance is large (a ball held on a bowl's
/// slope loads the finger with its tangential weight to 1e-9 N in the
/// tests: the contact force is normal).
pub const UV_METRIC: f64 = 1e-3;
pub use surface::{Surface, SurfaceKind, SurfacePoint};
