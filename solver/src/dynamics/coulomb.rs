//! Coulomb friction with the constrained step's own forces.
//!
//! A contact pair with friction has two stick rows at the centre of its
//! contact (a fingertip's centre, or the middle of the points a body pair's
//! witness primitives hold: four corners of a block act as one contact).
//!
//! - **Sticking**: the rows are active joint rows of the step; they hold the
//!   two bodies' points together exactly (a positional anchor: no creep).
//!   After the step their multipliers are the friction force F_t the contact
//!   supplied and the pair's normal rows give N (both forces of the step
//!   itself, M (q − q̂)/dt², so they include gravity, inertia and every
//!   push). The pair keeps sticking while |F_t| ≤ μ N; beyond, it slips: the
//!   tick is solved again without its rows, with the kinetic force μ N along
//!   F_t (what the contact could not supply in full, it supplies at the
//!   cone's edge).
//! - **Slipping**: the rows are off; the kinetic force μ N acts on both
//!   bodies at the contact point, opposite their relative slip (the last
//!   step's), as a known force of the prediction. When a step ends with the
//!   slip stopped or reversed (the friction force would have overshot), the
//!   pair sticks again, anchored where it was at the tick's start, and the
//!   tick is solved again.
//!
//! Both transitions re-solve the tick (one refactorisation and the tick's
//! steps), at most [`MAX_RESOLVES`] times a tick; a pair that leaves contact
//! forgets its state. One coefficient serves both states (see the module
//! docs of [`dynamics`](super) for why).

use nalgebra::Vector3;

/// Re-solves of a tick for friction transitions (each: a refactorisation
/// and the tick's steps again). Two cover a pair that re-sticks and then
/// breaks loose in the other direction within one tick.
pub const MAX_RESOLVES: u32 = 2;

/// Relative slack of the cone test: |F_t| ≤ μ N (1 + this) sticks, so a
/// load exactly at the cone does not flicker between the states on
/// round-off.
pub const CONE_SLACK: f64 = 1e-9;

/// Below this relative slip speed (m/s) a slipping pair has stopped.
pub const STOPPED_M_S: f64 = 1e-9;

/// The kinetic state of one friction pair.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(crate) struct Slip {
    /// Unit direction of the kinetic friction force on end A (world); zero
    /// while the pair has none (sticking, or not yet decided).
    pub dir: Vector3<f64>,
    /// The pair's normal force in the last step, N.
    pub normal_n: f64,
    /// Two bodies' torsional friction radius, m (0 at a fingertip): the
    /// patch resists twisting with up to μ N times this.
    pub twist_m: f64,
}

/// What a friction pair does next.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Verdict {
    /// As it was.
    Keep,
    /// Release the stick rows: kinetic friction from now on.
    Slip,
    /// Anchor and stick (again).
    Stick,
}

/// A sticking pair whose step needed the tangential force `f_a` (N, on end
/// A, world) and the twisting moment `twist_nm` about the normal, with
/// normal force `normal_n`, coefficient `mu` and torsional radius
/// `twist_m`: it keeps sticking while (|F|/μN)² + (|τ|/(μ N r))² ≤ 1, the
/// cone and a patch's torsional limit together (an ellipsoid).
pub(crate) fn sticking(
    f_a: &Vector3<f64>,
    twist_nm: f64,
    mu: f64,
    normal_n: f64,
    twist_m: f64,
) -> Verdict {
    let limit = mu * normal_n.max(0.0);
    let twist = if twist_m > 0.0 {
        twist_nm / (limit * twist_m)
    } else {
        0.0
    };
    let load = (f_a.norm() / limit).hypot(twist);
    if load.is_nan() || load > 1.0 + CONE_SLACK {
        Verdict::Slip
    } else {
        Verdict::Keep
    }
}

/// The moment of kinetic friction about the normal of a sliding patch
/// (N·m, opposing the relative spin `spin_rad_s` about the normal), with
/// the pair's slip speed `slip_m_s`: μ N r scaled by the spin's share of
/// the patch's sliding, r ω / (r ω + |s|) (a patch that only spins feels
/// the whole torsional limit, one that slides fast hardly any), and never
/// more than stops the spin within the tick (`inv_inertia`: the pair's
/// inverse moment about the normal, 1/(kg·m²)).
pub(crate) fn twisting(
    slip: &Slip,
    mu: f64,
    spin_rad_s: f64,
    slip_m_s: f64,
    dt_s: f64,
    inv_inertia: f64,
) -> f64 {
    let r = slip.twist_m;
    if r <= 0.0 || spin_rad_s == 0.0 {
        return 0.0;
    }
    let share = (r * spin_rad_s.abs()) / (r * spin_rad_s.abs() + slip_m_s.abs());
    let moment = mu * slip.normal_n.max(0.0) * r * share;
    let stop = if inv_inertia > 0.0 {
        spin_rad_s.abs() / (inv_inertia * dt_s)
    } else {
        f64::INFINITY
    };
    -spin_rad_s.signum() * moment.min(stop)
}

/// A slipping pair whose step ended with relative tangential velocity `s`
/// (A's contact point against B's, m/s, world) while the kinetic force on A
/// pointed along `dir`: it sticks when the slip stopped or turned to follow
/// the force (the force overshot).
pub(crate) fn slipping(s: &Vector3<f64>, dir: &Vector3<f64>) -> Verdict {
    if dir.norm_squared() == 0.0 || s.norm() <= STOPPED_M_S || s.dot(dir) >= 0.0 {
        Verdict::Stick
    } else {
        Verdict::Keep
    }
}

/// A slip slower than this many ticks' worth of the kinetic force's
/// velocity change is judged implicitly (see [`slow`]).
pub const SLOW_TICKS: f64 = 4.0;

/// True when a slip of `speed_m_s` is too slow for an explicit kinetic
/// force: μ N along the last slip changes the relative velocity by
/// μ N dt w per tick (w: the pair's inverse mass, 1/kg), and a direction
/// taken from a slip not much faster than that overshoots and turns the
/// slip sideways (at 250 Hz a 100 g block pushed at 1 cm/s yawed until its
/// friction pointed 35° off the push). Such a pair tries to stick first
/// on the next tick, and slips, if it must, along the force that sticking
/// needed: the direction is then the implicit one.
pub(crate) fn slow(speed_m_s: f64, mu: f64, normal_n: f64, dt_s: f64, inv_mass: f64) -> bool {
    speed_m_s < SLOW_TICKS * mu * normal_n * dt_s * inv_mass
}

/// The kinetic force on A (N, world) of a slipping pair: μ N along `dir`.
pub(crate) fn kinetic(slip: &Slip, mu: f64) -> Vector3<f64> {
    slip.dir * (mu * slip.normal_n.max(0.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_cone_decides_and_a_reversed_slip_sticks() {
        let f = Vector3::new(0.3, 0.4, 0.0);
        assert_eq!(sticking(&f, 0.0, 0.5, 1.0, 0.0), Verdict::Keep);
        assert_eq!(sticking(&f, 0.0, 0.5, 0.99, 0.0), Verdict::Slip);
        // Twist: within the cone alone, out of it with the moment.
        assert_eq!(sticking(&f, 0.001, 0.5, 1.0, 0.02), Verdict::Slip);
        assert_eq!(sticking(&(f * 0.5), 0.004, 0.5, 1.0, 0.02), Verdict::Keep);
        let dir = Vector3::new(-1.0, 0.0, 0.0);
        assert_eq!(slipping(&Vector3::new(0.01, 0.0, 0.0), &dir), Verdict::Keep);
        assert_eq!(
            slipping(&Vector3::new(-0.01, 0.0, 0.0), &dir),
            Verdict::Stick
        );
        assert_eq!(slipping(&Vector3::zeros(), &dir), Verdict::Stick);
        let s = Slip {
            dir,
            normal_n: 2.0,
            twist_m: 0.02,
        };
        assert_eq!(kinetic(&s, 0.25), Vector3::new(-0.5, 0.0, 0.0));
        // A pure spin feels μ N r, capped by what stops it.
        assert!((twisting(&s, 0.25, 3.0, 0.0, 1e-3, 1.0) + 0.01).abs() < 1e-12);
        assert!((twisting(&s, 0.25, -3.0, 0.0, 1e-3, 1e6) - 3e-3).abs() < 1e-12);
    }
}
