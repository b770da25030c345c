//! The session's devices: one mounted, safety-wrapped device per
//! `[[device]]`, registered ("clutched") so its tip maps onto its finger's
//! initial world position, plus the grasp offset a rigid finger needs.

use crate::scenes::Scene;
use anyhow::{Context, Result, bail};
use haptloop_devices::{
    Device, DeviceFault, DeviceInfo, DeviceReading, Grip, Hand, MotorReport, Mount, MountedDevice,
    Pointer, ReplayDevice, SafetyConfig, SimOptions, SimPhantom, Trace, Trajectory, VIRTUAL_MODEL,
    VirtualDevice, VirtualParams,
};
use haptloop_solver::scene::HandPath;
use haptloop_solver::{FingerId, FingerTarget, Grasp};
use nalgebra::{UnitQuaternion, Vector3};
use std::path::Path;
use std::time::Duration;

/// A simulated arm, or a recorded one played back. An enum, not a trait
/// object, so the fast loop dispatches statically and can still ask the
/// simulator for its hand target.
#[derive(Debug)]
pub enum SessionDevice {
    /// A simulated PHANToM held by a simulated hand.
    Sim(Box<SimPhantom>),
    /// A trace recorded by `--record`, played back tick by tick.
    Replay(Box<ReplayDevice>),
    /// A virtual device, moved by a person through the live viewer.
    Virtual(Box<VirtualDevice>),
}

impl SessionDevice {
    /// The simulated hand's target offset at `now`, device frame (zero when
    /// replaying).
    pub fn hand_offset_m_device(&self, now: Duration) -> Vector3<f64> {
        match self {
            SessionDevice::Sim(s) => s.hand().trajectory.sample(now).offset_m,
            SessionDevice::Replay(_) => Vector3::zeros(),
            // The pointer's target: the virtual device starts at its origin.
            SessionDevice::Virtual(v) => v.target_m_device(),
        }
    }
}

impl Device for SessionDevice {
    fn info(&self) -> &DeviceInfo {
        match self {
            SessionDevice::Sim(d) => d.info(),
            SessionDevice::Replay(d) => d.info(),
            SessionDevice::Virtual(d) => d.info(),
        }
    }
    fn read(&mut self, now: Duration) -> Result<DeviceReading, DeviceFault> {
        match self {
            SessionDevice::Sim(d) => d.read(now),
            SessionDevice::Replay(d) => d.read(now),
            SessionDevice::Virtual(d) => d.read(now),
        }
    }
    fn write(
        &mut self,
        force_n_device: Vector3<f64>,
        now: Duration,
    ) -> Result<MotorReport, DeviceFault> {
        match self {
            SessionDevice::Sim(d) => d.write(force_n_device, now),
            SessionDevice::Replay(d) => d.write(force_n_device, now),
            SessionDevice::Virtual(d) => d.write(force_n_device, now),
        }
    }
    fn motors_off(&mut self, now: Duration) {
        match self {
            SessionDevice::Sim(d) => d.motors_off(now),
            SessionDevice::Replay(d) => d.motors_off(now),
            SessionDevice::Virtual(d) => d.motors_off(now),
        }
    }
    fn set_hardware_watchdog(&mut self, timeout: Option<Duration>) -> bool {
        match self {
            SessionDevice::Sim(d) => d.set_hardware_watchdog(timeout),
            SessionDevice::Replay(d) => d.set_hardware_watchdog(timeout),
            SessionDevice::Virtual(d) => d.set_hardware_watchdog(timeout),
        }
    }
    fn applied_torque_nm(&self) -> Option<Vector3<f64>> {
        match self {
            SessionDevice::Sim(d) => d.applied_torque_nm(),
            SessionDevice::Replay(d) => d.applied_torque_nm(),
            SessionDevice::Virtual(d) => d.applied_torque_nm(),
        }
    }
}

/// All devices of a session and how fingers map onto them.
pub struct Rig {
    /// One per `[[device]]`, scene order.
    pub devices: Vec<MountedDevice<SessionDevice>>,
    /// For each model finger: the index of its device.
    pub finger_device: Vec<usize>,
    /// For each model finger: the body orientation relative to the device's
    /// sensed orientation at registration (rigid grasps hold it).
    pub grasp_offset: Vec<UnitQuaternion<f64>>,
    /// For each device: the reading it was registered with at t = 0 (what a
    /// recording stores as its first row).
    pub registered: Vec<Option<DeviceReading>>,
    /// For each model finger: point or rigid.
    pub grasp: Vec<Grasp>,
    /// For each device: the pointer that moves it, if it is virtual (the
    /// live viewer sets it; nothing else does).
    pub pointers: Vec<Option<Pointer>>,
}

/// The hand's trajectory in the device frame (offsets from the home pose),
/// as the simulated hand follows it: the scene's path through the mount.
pub fn device_trajectory(
    path: &HandPath,
    trace: Option<&haptloop_devices::HandTrace>,
    mount: &Mount,
) -> Trajectory {
    let v = |a: [f64; 3]| Vector3::new(a[0], a[1], a[2]);
    let scene = match path {
        HandPath::Still => Trajectory::Still,
        HandPath::Circle {
            radius_m,
            hz,
            u,
            v: w,
        } => Trajectory::Circle {
            radius_m: *radius_m,
            frequency_hz: *hz,
            u: v(*u).normalize(),
            v: v(*w).normalize(),
        },
        HandPath::Line { to_m, seconds } => Trajectory::Line {
            to_m: v(*to_m),
            duration: Duration::from_secs_f64(*seconds),
        },
        HandPath::Waypoints { points } => {
            let pts: Vec<(Duration, Vector3<f64>)> = points
                .iter()
                .map(|p| (Duration::from_secs_f64(p[0]), v([p[1], p[2], p[3]])))
                .collect();
            Trajectory::Trace(
                haptloop_devices::HandTrace::from_points(&pts)
                    .expect("waypoints are checked when the scene loads"),
            )
        }
        HandPath::Trace { .. } => {
            Trajectory::Trace(trace.cloned().expect("traces are loaded with the scene"))
        }
    };
    // Offsets are written in the scene frame; the hand acts in the device frame.
    mount.trajectory_to_device(&scene)
}

/// A replayed trace must come from this scene, this device model and this
/// rate, and reach the end of the run: anything else would replay motion
/// that belongs to another session, silently.
fn check_replay(
    trace: &Trace,
    path: &Path,
    scene: &str,
    model: &str,
    rate_hz: u32,
    duration: Duration,
) -> Result<()> {
    let h = &trace.header;
    let at = path.display();
    if h.scene != scene {
        bail!("{at}: recorded in scene `{}`, not `{scene}`", h.scene);
    }
    if h.model != model {
        bail!(
            "{at}: recorded on a `{}`, but this scene's device is a `{model}`",
            h.model
        );
    }
    if h.rate_hz != rate_hz {
        bail!(
            "{at}: recorded at {} Hz; this run is at {rate_hz} Hz (pass --rate {})",
            h.rate_hz,
            h.rate_hz
        );
    }
    let end = trace.rows.last().map_or(Duration::ZERO, |r| r.time);
    if end < duration {
        let fix = if end.is_zero() {
            "it holds no tick after the registration row".to_string()
        } else {
            format!("pass --seconds {} or less", exact_seconds(end))
        };
        bail!(
            "{at}: the trace covers {} s; this run needs {} s ({fix})",
            exact_seconds(end),
            exact_seconds(duration)
        );
    }
    Ok(())
}

/// A duration in seconds, exactly, without trailing zeros: `0.0005`, `2`,
/// `0.2` (never a rounded `0.000`).
pub fn exact_seconds(d: Duration) -> String {
    let frac = format!("{:09}", d.subsec_nanos());
    let frac = frac.trim_end_matches('0');
    if frac.is_empty() {
        format!("{}", d.as_secs())
    } else {
        format!("{}.{frac}", d.as_secs())
    }
}

impl Rig {
    /// Builds every device of `scene` for a loop at `rate_hz`, replaying the
    /// traces in `replay` (one `<device>.trace` each) instead of simulating when
    /// given, and registers each on its finger's initial world position.
    pub fn build(
        scene: &Scene,
        rate_hz: u32,
        replay: Option<&Path>,
        duration: Duration,
    ) -> Result<Rig> {
        let c = &scene.compiled;
        let model = &c.model;
        let q0 = model.q0();
        let mut devices = Vec::with_capacity(c.devices.len());
        let mut pointers = Vec::with_capacity(c.devices.len());
        let mut finger_device = vec![0; model.fingers().len()];
        for f in &c.fingers {
            finger_device[f.finger.index()] = f.device;
        }
        for (k, d) in c.devices.iter().enumerate() {
            let mount = Mount::new(Vector3::zeros(), d.orientation_wxyz, d.scale)
                .with_context(|| format!("device `{}`", d.name))?;
            let device = match replay {
                Some(dir) => {
                    let path = dir.join(format!("{}.trace", d.name));
                    let trace = Trace::load(&path)
                        .with_context(|| format!("replaying device `{}`", d.name))?;
                    check_replay(&trace, &path, &c.name, &d.model, rate_hz, duration)?;
                    SessionDevice::Replay(Box::new(ReplayDevice::new(trace)?))
                }
                None if d.model == VIRTUAL_MODEL => {
                    let pointer = Pointer::new();
                    pointers.push(Some(pointer.clone()));
                    let params = VirtualParams::for_rate_hz(rate_hz);
                    let device = VirtualDevice::new(params, pointer)
                        .with_context(|| format!("device `{}`", d.name))?;
                    SessionDevice::Virtual(Box::new(device))
                }
                None => {
                    // The grip is the user's hand on the physical stylus: its
                    // stiffness and damping are device-frame figures, unscaled.
                    let mut grip = Grip::default();
                    if let Some(k) = d.hand.stiffness_n_per_m {
                        grip.stiffness_n_per_m = k;
                    }
                    if let Some(b) = d.hand.damping_n_s_per_m {
                        grip.damping_n_s_per_m = b;
                    }
                    let trajectory =
                        device_trajectory(&d.hand.path, scene.traces[k].as_ref(), &mount);
                    let hand = Hand::new(trajectory).with_grip(grip);
                    let sim = SimPhantom::by_name(&d.model, SimOptions::for_rate_hz(rate_hz), hand)
                        .with_context(|| format!("device `{}`", d.name))?;
                    SessionDevice::Sim(Box::new(sim))
                }
            };
            let safety = SafetyConfig {
                loop_period: Duration::from_nanos(1_000_000_000 / u64::from(rate_hz)),
                ..SafetyConfig::default()
            };
            pointers.resize(devices.len() + 1, None);
            devices.push(MountedDevice::new(d.name.clone(), device, safety, mount)?);
        }
        let mut rig = Rig {
            registered: vec![None; devices.len()],
            devices,
            finger_device,
            grasp_offset: vec![UnitQuaternion::identity(); model.fingers().len()],
            grasp: model.fingers().iter().map(|f| f.grasp).collect(),
            pointers,
        };
        // Register (clutch): each tip maps onto its finger's initial position,
        // and a rigid grasp remembers the body's orientation relative to the
        // sensed orientation, so the initial target is the initial pose.
        for (i, f) in model.fingers().iter().enumerate() {
            let id = FingerId(i as u32);
            let at = model
                .finger_point(q0, id)
                .expect("every finger has a point");
            let dev = &mut rig.devices[rig.finger_device[i]];
            let reading = dev.register(Duration::ZERO, &at);
            rig.registered[rig.finger_device[i]] = Some(reading);
            let sensed = dev.mount.orientation_to_scene(&reading.orientation_device);
            let body = model
                .body_rotation(q0, f.body)
                .map(|r| UnitQuaternion::from_matrix(&r))
                .unwrap_or_else(UnitQuaternion::identity);
            rig.grasp_offset[i] = sensed.inverse() * body;
        }
        Ok(rig)
    }

    /// The finger target of model finger `i` from its device's scene reading.
    #[inline]
    pub fn target(
        &self,
        i: usize,
        tip_m_scene: Vector3<f64>,
        sensed_scene: UnitQuaternion<f64>,
    ) -> FingerTarget {
        FingerTarget {
            position_m: tip_m_scene,
            orientation: sensed_scene * self.grasp_offset[i],
        }
    }
}

/// What a virtual device did over a run, scene frame (`summary.json` →
/// `virtual_devices`).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct VirtualOutcome {
    /// Device name.
    pub device: String,
    /// Where its tip started (registered on its finger), m.
    pub tip_start_m: [f64; 3],
    /// Its tip as sensed at the last tick, m.
    pub tip_end_m: [f64; 3],
    /// Where the mouse last put its target, m (the start if never moved).
    pub pointer_end_m: [f64; 3],
    /// The pointer was moved at least once.
    pub pointer_moved: bool,
    /// The force rendered on it at the last tick, N.
    pub force_end_n: [f64; 3],
    /// The largest force rendered on it, N.
    pub force_max_n: f64,
    /// The pointer spring in the scene frame, N/m (k_p / scale²): at rest,
    /// tip = pointer + force / this.
    pub pointer_stiffness_n_per_m: f64,
}

impl Rig {
    /// Each virtual device's outcome, from its state now and its first
    /// finger's last trace sample (`last[i]` for model finger i) and
    /// largest force.
    pub fn virtual_outcomes(
        &self,
        last: &[super::TraceSample],
        force_max_n: &[f64],
    ) -> Vec<VirtualOutcome> {
        let mut out = Vec::new();
        for (d, dev) in self.devices.iter().enumerate() {
            let SessionDevice::Virtual(v) = dev.device.device() else {
                continue;
            };
            let Some(i) = self.finger_device.iter().position(|&k| k == d) else {
                continue;
            };
            let m = &dev.mount;
            let s = last.get(i).copied().unwrap_or_default();
            out.push(VirtualOutcome {
                device: dev.name.clone(),
                tip_start_m: m.point_to_scene(&Vector3::zeros()).into(),
                tip_end_m: s.target_m,
                pointer_end_m: m.point_to_scene(&v.target_m_device()).into(),
                pointer_moved: v.pointer().get().is_some(),
                force_end_n: s.force_n,
                force_max_n: force_max_n.get(i).copied().unwrap_or(f64::NAN),
                pointer_stiffness_n_per_m: v.params().pointer_stiffness_n_per_m
                    / (m.scale * m.scale),
            });
        }
        out
    }
}
