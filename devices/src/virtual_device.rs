//! [`VirtualDevice`] (`model = "virtual"`): a force-feedback device with no
//! hardware, whose tip a person moves with the mouse through the live viewer
//! (CHAI3D's virtual device for people without one).
//!
//! # Dynamics
//! The tip is a point of mass `m` pulled toward the mouse's target `x_p` (a
//! [`Pointer`], held between moves) by a spring `k_p`, slowed by a viscous
//! damper `b` to the ground, and pushed by the force the session renders:
//!
//! ```text
//! m v̇ = k_p (x_p − x) − b v + F
//! ```
//!
//! integrated up to each `now` in sub-steps of at most a quarter period with
//! the same velocity-Verlet scheme as [`crate::SimPhantom`] (damping
//! implicit; the force held between writes, a zero-order hold). It is the
//! simulated hand on a simulated arm, with the mouse as the hand: the
//! spring is the grip, the damper the hand's and the device's friction.
//!
//! # Why it stays passive
//! With the pointer still, E = ½ m |v|² + ½ k_p |x_p − x|² can only fall
//! (b > 0) unless the rendered force feeds energy in. A sampled spring K with
//! a zero-order hold at period T feeds in at most what a damper of K·T/2
//! takes out (Colgate & Schenkel), so any stiffness below 2b/T, the bound the
//! PHANToMs' passivity test uses ([`crate::passivity`]), cannot make it grow:
//! with the defaults (b = 5 N·s/m) that is 10 000 N/m at 1 kHz, 25× the
//! scenes' 400 N/m couplings. The tests check both sides of the bound.
//!
//! # Sensing, recording, limits
//! The tip is sensed to 1 µm: the reading's `joint_counts` are the tip's
//! x, y, z in micrometres (no joints), so a recorded trace replays it bit
//! for bit ([`crate::ReplayDevice`]). The rendered force is clamped to the
//! peak force (direction kept); there are no motors to overheat.
//! [`Device::applied_torque_nm`] reports the force it applies to the tip
//! (newtons: a virtual device has no joints), zero after a stop.
//!
//! # Real-time
//! No allocation, no locks: `read` loads the pointer (one atomic load) and
//! integrates at most [`VirtualDevice::MAX_SUBSTEPS_PER_CALL`] sub-steps.

use std::time::Duration;

use nalgebra::{UnitQuaternion, Vector3};

use crate::device::{
    ARM_JOINTS, Device, DeviceFault, DeviceInfo, DeviceLimits, DeviceReading, MotorReport,
    ReadingFlags,
};
use crate::error::DeviceError;
use crate::pointer::{POINTER_RESOLUTION_M, Pointer};

/// The scene-file model name of the virtual device.
pub const VIRTUAL_MODEL: &str = "virtual";

/// Parameters of a [`VirtualDevice`] (see the [module docs](self)).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VirtualParams {
    /// Tip mass m, kg (default 0.1 kg: a stylus and a hand's share of it).
    pub mass_kg: f64,
    /// Pointer spring k_p, N/m, device frame (default 300 N/m: the
    /// simulated hand's grip, [`crate::Grip`]).
    pub pointer_stiffness_n_per_m: f64,
    /// Damping b to the ground, N·s/m (default 5 N·s/m: damping ratio
    /// b / 2√(k_p m) ≈ 0.46, so the tip follows the mouse without ringing,
    /// and Colgate's bound 2b/T is 10 000 N/m at 1 kHz).
    pub damping_n_s_per_m: f64,
    /// Peak force, N (default 10 N).
    pub peak_force_n: f64,
    /// Half extent of the workspace box around the start, m (default 0.3 m).
    pub workspace_half_extent_m: f64,
    /// Loop period the sub-steps divide (default 1 ms).
    pub loop_period: Duration,
}

impl Default for VirtualParams {
    fn default() -> Self {
        Self {
            mass_kg: 0.1,
            pointer_stiffness_n_per_m: 300.0,
            damping_n_s_per_m: 5.0,
            peak_force_n: 10.0,
            workspace_half_extent_m: 0.3,
            loop_period: Duration::from_millis(1),
        }
    }
}

impl VirtualParams {
    /// Defaults for a loop at `rate_hz`.
    pub fn for_rate_hz(rate_hz: u32) -> Self {
        Self {
            loop_period: Duration::from_nanos(1_000_000_000 / u64::from(rate_hz.max(1))),
            ..Self::default()
        }
    }

    /// The static description every virtual device shares.
    pub fn info(&self) -> DeviceInfo {
        let h = Vector3::repeat(self.workspace_half_extent_m);
        DeviceInfo {
            model: VIRTUAL_MODEL,
            limits: DeviceLimits {
                peak_force_n: self.peak_force_n,
                continuous_force_n: self.peak_force_n,
                workspace_min_m_device: -h,
                workspace_max_m_device: h,
                nominal_stiffness_n_per_m: self.pointer_stiffness_n_per_m,
                stable_stiffness_1khz_n_per_m: 2.0 * self.damping_n_s_per_m / 1e-3,
            },
            // A notional joint whose count is 1 µm at a 1 m lever: the safety
            // layer's jump check (25 rad/s) then allows 25 m/s of tip speed,
            // far above anything the damped tip reaches.
            counts_per_rev: [(std::f64::consts::TAU / POINTER_RESOLUTION_M) as u32; ARM_JOINTS],
            sensed_dof: 3,
            actuated_dof: 3,
        }
    }

    /// The reading built from recorded counts (micrometres per axis): what a
    /// live read returns for the same counts.
    ///
    /// # Real-time
    /// No allocation; constant time.
    pub fn reading_from_counts(counts: &[i32; ARM_JOINTS], time: Duration) -> DeviceReading {
        let tip = Vector3::new(
            f64::from(counts[0]),
            f64::from(counts[1]),
            f64::from(counts[2]),
        ) * POINTER_RESOLUTION_M;
        DeviceReading {
            time,
            joint_counts: *counts,
            joint_angles_rad: Vector3::zeros(),
            tip_m_device: tip,
            orientation_device: UnitQuaternion::identity(),
            buttons: 0,
            flags: ReadingFlags::EMPTY,
        }
    }

    /// What the device applies for a commanded force: the force clamped to
    /// the peak (direction kept), nothing for a non-finite one. A replay of
    /// a virtual device's trace applies the same.
    pub fn applied(&self, force_n_device: Vector3<f64>) -> MotorReport {
        if !force_n_device.iter().all(|v| v.is_finite()) {
            return MotorReport::off();
        }
        let norm = force_n_device.norm();
        let saturated = norm > self.peak_force_n;
        MotorReport {
            force_n_device: if saturated {
                force_n_device * (self.peak_force_n / norm)
            } else {
                force_n_device
            },
            torque_nm: Vector3::zeros(),
            thermal_limited: false,
            saturated,
        }
    }

    fn validate(&self) -> Result<(), DeviceError> {
        let positive = [
            ("mass_kg", self.mass_kg),
            ("pointer_stiffness_n_per_m", self.pointer_stiffness_n_per_m),
            ("damping_n_s_per_m", self.damping_n_s_per_m),
            ("peak_force_n", self.peak_force_n),
            ("workspace_half_extent_m", self.workspace_half_extent_m),
        ];
        for (what, v) in positive {
            if !(v.is_finite() && v > 0.0) {
                return Err(DeviceError::InvalidConfig {
                    what,
                    value: v.to_string(),
                    reason: "must be finite and > 0",
                });
            }
        }
        if self.loop_period.is_zero() {
            return Err(DeviceError::InvalidConfig {
                what: "loop_period",
                value: "0".into(),
                reason: "must be > 0",
            });
        }
        Ok(())
    }
}

/// A device moved by a [`Pointer`] (see the [module docs](self)).
#[derive(Debug, Clone)]
pub struct VirtualDevice {
    params: VirtualParams,
    info: DeviceInfo,
    pointer: Pointer,
    p: Vector3<f64>,
    v: Vector3<f64>,
    t: Duration,
    force: Vector3<f64>,
    target: Vector3<f64>,
    pointer_work_j: f64,
    force_work_j: f64,
}

impl VirtualDevice {
    /// Longest run of sub-steps one call performs (a longer gap is covered
    /// with longer sub-steps).
    pub const MAX_SUBSTEPS_PER_CALL: u64 = 4096;

    /// A device at rest at the origin of its frame, moved by `pointer`.
    pub fn new(params: VirtualParams, pointer: Pointer) -> Result<Self, DeviceError> {
        params.validate()?;
        Ok(Self {
            info: params.info(),
            params,
            pointer,
            p: Vector3::zeros(),
            v: Vector3::zeros(),
            t: Duration::ZERO,
            force: Vector3::zeros(),
            target: Vector3::zeros(),
            pointer_work_j: 0.0,
            force_work_j: 0.0,
        })
    }

    /// The parameters.
    pub fn params(&self) -> &VirtualParams {
        &self.params
    }

    /// The pointer that moves it (clones share it).
    pub fn pointer(&self) -> &Pointer {
        &self.pointer
    }

    /// The target the tip is pulled toward now, m, device frame (the origin
    /// until the pointer is first set).
    pub fn target_m_device(&self) -> Vector3<f64> {
        self.target
    }

    /// True (unquantised) tip position, m, device frame.
    pub fn true_tip_m_device(&self) -> Vector3<f64> {
        self.p
    }

    /// ½ m |v|² + ½ k_p |x_p − x|², J.
    pub fn energy_j(&self) -> f64 {
        let d = self.target - self.p;
        0.5 * self.params.mass_kg * self.v.norm_squared()
            + 0.5 * self.params.pointer_stiffness_n_per_m * d.norm_squared()
    }

    /// Work the pointer's moves did on the spring, J (a move changes the
    /// spring's energy at once).
    pub fn pointer_work_j(&self) -> f64 {
        self.pointer_work_j
    }

    /// Work the rendered force did on the tip, J.
    pub fn force_work_j(&self) -> f64 {
        self.force_work_j
    }

    /// Takes the pointer's newest target (a move does work on the spring).
    fn follow_pointer(&mut self) {
        if let Some(x) = self.pointer.get() {
            let h = self.params.workspace_half_extent_m;
            let x = x.map(|c| c.clamp(-h, h));
            if x != self.target {
                let before = self.energy_j();
                self.target = x;
                self.pointer_work_j += self.energy_j() - before;
            }
        }
    }

    /// Integrates up to `now` (no-op if `now` is not later).
    ///
    /// # Real-time
    /// No allocation; at most [`Self::MAX_SUBSTEPS_PER_CALL`] sub-steps.
    pub fn advance_to(&mut self, now: Duration) {
        if now <= self.t {
            return;
        }
        let max_step = (self.params.loop_period.as_nanos() as u64 / 4).max(1);
        let gap = (now - self.t).as_nanos() as u64;
        let n = gap.div_ceil(max_step).clamp(1, Self::MAX_SUBSTEPS_PER_CALL);
        let h = gap as f64 * 1e-9 / n as f64;
        for _ in 0..n {
            self.substep(h);
        }
        self.t = now;
    }

    /// One velocity-Verlet step with the damping implicit in each half step.
    fn substep(&mut self, h: f64) {
        let m = self.params.mass_kg;
        let c = self.params.damping_n_s_per_m / m;
        let k = self.params.pointer_stiffness_n_per_m;
        let spring = |p: &Vector3<f64>| (self.target - p) * k;
        let v_half =
            (self.v + (spring(&self.p) + self.force) * (0.5 * h / m)) / (1.0 + 0.5 * h * c);
        let dp = v_half * h;
        let p_new = self.p + dp;
        let v_new = (v_half + (spring(&p_new) + self.force) * (0.5 * h / m)) / (1.0 + 0.5 * h * c);
        self.force_work_j += self.force.dot(&dp);
        self.p = p_new;
        self.v = v_new;
    }

    fn counts(&self) -> [i32; ARM_JOINTS] {
        let h = self.params.workspace_half_extent_m;
        let c = |x: f64| (x.clamp(-h, h) / POINTER_RESOLUTION_M).round() as i32;
        [c(self.p.x), c(self.p.y), c(self.p.z)]
    }
}

impl Device for VirtualDevice {
    fn info(&self) -> &DeviceInfo {
        &self.info
    }

    fn read(&mut self, now: Duration) -> Result<DeviceReading, DeviceFault> {
        self.advance_to(now);
        self.follow_pointer();
        Ok(VirtualParams::reading_from_counts(&self.counts(), now))
    }

    fn write(
        &mut self,
        force_n_device: Vector3<f64>,
        now: Duration,
    ) -> Result<MotorReport, DeviceFault> {
        self.advance_to(now);
        let r = self.params.applied(force_n_device);
        self.force = r.force_n_device;
        Ok(r)
    }

    fn motors_off(&mut self, now: Duration) {
        self.advance_to(now);
        self.force = Vector3::zeros();
    }

    fn applied_torque_nm(&self) -> Option<Vector3<f64>> {
        Some(self.force)
    }
}

#[cfg(test)]
mod tests;
