//! Passivity / maximum stable stiffness of a virtual wall rendered on a
//! simulated arm held by the simulated hand.
//!
//! # The experiment
//! A unilateral wall (floor) at the tip's start, normal +y, rendered at the loop
//! rate from the **quantised, sampled** tip position as F = max(0, K·pen − B·v̂)
//! with v̂ the backward difference of the sampled position, held constant
//! between ticks (zero-order hold), on the sub-stepped arm dynamics
//! ([`crate::SimPhantom`], thermal cut and torque saturation off so that growth
//! is not hidden by a limiter). The hand target sits below the surface so that
//! the grip pushes with `push_force_n` at equilibrium (penetration F/K); the tip
//! starts at rest on the surface. The energy of the coupled system
//!
//! ```text
//! E = ½ m |v|² + ½ K pen² + ½ k_h |x_target − x|²   (− hand work, zero here: the target is still)
//! ```
//!
//! is compared with its equilibrium value. Its excess starts at
//! ½F²/K·(1 + k_h/K) and, for a passive loop, decays (down to a floor set by
//! encoder quantisation). The loop is declared to **grow** when the largest
//! excess over the last fifth of the run exceeds the initial excess
//! (growth ratio > 1): reported as a number, never hidden.
//!
//! # The bound
//! Colgate & Schenkel's passivity condition for a sampled spring–damper wall is
//! b > K·T/2 + |B|, i.e. K_max = 2(b − |B|)/T, where T is the loop period, B the
//! *virtual* damping rendered by the wall, and b the *physical* damping acting
//! on the device. Here b = the arm's viscous damping + the grip's damping: the
//! hand's damper dissipates energy on the tip exactly as friction in the arm
//! does. (The arm alone, ~0.01 N·s/m, would allow only ~23 N/m at 1 kHz: the
//! hand is what makes real devices usable.) The condition is sufficient, not
//! necessary, and it ignores quantisation; the measured figure is reported next
//! to it, not forced to agree.

use std::time::Duration;

use nalgebra::Vector3;

use crate::device::Device;
use crate::error::DeviceError;
use crate::hand::{Grip, Hand, Trajectory};
use crate::phantom::{PhantomModel, SimOptions, SimPhantom};

/// One wall experiment.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WallTest {
    /// Arm model.
    pub model: &'static PhantomModel,
    /// Loop period T.
    pub loop_period: Duration,
    /// Physics sub-steps per period (≥ 4).
    pub substeps_per_period: u32,
    /// Wall stiffness K, N/m.
    pub stiffness_n_per_m: f64,
    /// Virtual wall damping B, N·s/m.
    pub virtual_damping_n_s_per_m: f64,
    /// The hand's grip.
    pub grip: Grip,
    /// Force the grip pushes with at equilibrium, newtons (default 2 N: well
    /// above the quantisation-limited force floor at the highest stiffness).
    pub push_force_n: f64,
    /// Simulated time (default 3 s ≥ 10 decay time constants m/b of a light grip).
    pub duration: Duration,
}

impl WallTest {
    /// A test of `model` at `rate_hz` with wall stiffness `k_n_per_m` and defaults.
    pub fn new(model: &'static PhantomModel, rate_hz: u32, k_n_per_m: f64) -> Self {
        Self {
            model,
            loop_period: SimOptions::for_rate_hz(rate_hz).loop_period,
            substeps_per_period: 4,
            stiffness_n_per_m: k_n_per_m,
            virtual_damping_n_s_per_m: 0.0,
            grip: Grip::default(),
            push_force_n: 2.0,
            duration: Duration::from_secs(3),
        }
    }

    /// Physical damping b acting on the tip: arm + grip, N·s/m.
    pub fn physical_damping_n_s_per_m(&self) -> f64 {
        self.model.arm_damping_n_s_per_m + self.grip.damping_n_s_per_m
    }

    /// Colgate's passivity bound for this test, N/m.
    pub fn colgate_bound_n_per_m(&self) -> f64 {
        colgate_bound_n_per_m(
            self.physical_damping_n_s_per_m(),
            self.virtual_damping_n_s_per_m,
            self.loop_period,
        )
    }
}

/// K_max = 2(b − |B|)/T (zero when B ≥ b).
pub fn colgate_bound_n_per_m(
    physical_damping_n_s_per_m: f64,
    virtual_damping_n_s_per_m: f64,
    loop_period: Duration,
) -> f64 {
    (2.0 * (physical_damping_n_s_per_m - virtual_damping_n_s_per_m.abs())
        / loop_period.as_secs_f64())
    .max(0.0)
}

/// Result of one wall experiment.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EnergyReport {
    /// Energy above equilibrium at the start, joules.
    pub initial_excess_j: f64,
    /// Largest excess over the last fifth of the run, joules.
    pub late_excess_j: f64,
    /// Largest excess over the whole run, joules.
    pub peak_excess_j: f64,
    /// `late_excess_j / initial_excess_j`: > 1 means the energy grew.
    pub growth_ratio: f64,
    /// Peak-to-peak tip motion along the wall normal over the last fifth, metres.
    pub late_oscillation_m: f64,
}

impl EnergyReport {
    /// True when the energy grew (growth ratio > 1, or not a number: a NaN
    /// energy is reported as growth, never as stability).
    pub fn grows(&self) -> bool {
        self.growth_ratio > 1.0 || self.growth_ratio.is_nan()
    }
}

/// Runs one wall experiment.
pub fn run_wall(test: &WallTest) -> Result<EnergyReport, DeviceError> {
    let k = test.stiffness_n_per_m;
    let kh = test.grip.stiffness_n_per_m;
    let f = test.push_force_n;
    let depth = f / kh + f / k;
    let hand = Hand::new(Trajectory::Line {
        to_m: Vector3::new(0.0, -depth, 0.0),
        duration: Duration::ZERO,
    })
    .with_grip(test.grip);
    let options = SimOptions {
        loop_period: test.loop_period,
        substeps_per_period: test.substeps_per_period,
        thermal: false,
        motor_saturation: false,
        ..SimOptions::default()
    };
    let mut sim = SimPhantom::new(test.model, options, hand)?;
    let wall_y = sim.true_tip_m_device().y;
    let e_eq = 0.5 * f * f / k + 0.5 * f * f / kh;
    let energy = |s: &SimPhantom| {
        let pen = (wall_y - s.true_tip_m_device().y).max(0.0);
        s.kinetic_energy_j() + 0.5 * k * pen * pen + s.grip_energy_j() - s.hand_work_j() - e_eq
    };
    let ticks = (test.duration.as_nanos() / test.loop_period.as_nanos()) as u64;
    let late_from = ticks - ticks / 5;
    let period_s = test.loop_period.as_secs_f64();
    let (mut prev_y, mut initial, mut late, mut peak) = (wall_y, f64::NAN, 0.0f64, 0.0f64);
    let (mut y_min, mut y_max) = (f64::INFINITY, f64::NEG_INFINITY);
    for tick in 0..=ticks {
        let now = test.loop_period * tick as u32;
        let reading = sim.read(now).map_err(|e| DeviceError::InvalidConfig {
            what: "wall test read",
            value: e.to_string(),
            reason: "no faults are injected",
        })?;
        let e = energy(&sim);
        if tick == 0 {
            initial = e;
        }
        peak = peak.max(e);
        if tick >= late_from {
            late = late.max(e);
            y_min = y_min.min(sim.true_tip_m_device().y);
            y_max = y_max.max(sim.true_tip_m_device().y);
        }
        let y = reading.tip_m_device.y;
        let v_est = (y - prev_y) / period_s;
        prev_y = y;
        let pen = wall_y - y;
        let force = if pen > 0.0 {
            (k * pen - test.virtual_damping_n_s_per_m * v_est).max(0.0)
        } else {
            0.0
        };
        sim.write(Vector3::new(0.0, force, 0.0), now)
            .map_err(|e| DeviceError::InvalidConfig {
                what: "wall test write",
                value: e.to_string(),
                reason: "no faults are injected",
            })?;
    }
    Ok(EnergyReport {
        initial_excess_j: initial,
        late_excess_j: late,
        peak_excess_j: peak,
        growth_ratio: late / initial,
        late_oscillation_m: y_max - y_min,
    })
}

/// Result of a stiffness search.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StiffnessSearch {
    /// Largest stiffness found whose energy did not grow, N/m.
    pub k_max_n_per_m: f64,
    /// Smallest stiffness found whose energy grew, N/m.
    pub k_unstable_n_per_m: f64,
    /// Colgate's bound for the same test, N/m.
    pub colgate_bound_n_per_m: f64,
    /// Report at `k_max_n_per_m`.
    pub at_k_max: EnergyReport,
}

/// Searches the largest wall stiffness whose energy does not grow: bracket
/// from the Colgate bound (doubling / halving), then `iterations` geometric
/// bisections (relative resolution ≈ bracket ratio^(1/2^iterations)).
pub fn max_stable_stiffness(
    template: &WallTest,
    iterations: u32,
) -> Result<StiffnessSearch, DeviceError> {
    let bound = template.colgate_bound_n_per_m();
    let run = |k: f64| {
        run_wall(&WallTest {
            stiffness_n_per_m: k,
            ..*template
        })
    };
    let start = bound.max(1.0);
    let (mut lo, mut hi) = (start, start);
    let mut lo_report = run(lo)?;
    while lo_report.grows() && lo > 1e-3 {
        hi = lo;
        lo /= 2.0;
        lo_report = run(lo)?;
    }
    if hi == lo {
        loop {
            hi *= 2.0;
            let r = run(hi)?;
            if r.grows() || hi > 1e8 {
                break;
            }
            lo = hi;
            lo_report = r;
        }
    }
    for _ in 0..iterations {
        let mid = (lo * hi).sqrt();
        let r = run(mid)?;
        if r.grows() {
            hi = mid;
        } else {
            lo = mid;
            lo_report = r;
        }
    }
    Ok(StiffnessSearch {
        k_max_n_per_m: lo,
        k_unstable_n_per_m: hi,
        colgate_bound_n_per_m: bound,
        at_k_max: lo_report,
    })
}
