//! [`MountedDevice`]: one device of a session — the device behind its safety
//! layer plus its [`Mount`] in the scene. A session holds any number of them
//! (multi-finger grasps), each with its own origin, orientation and scale.
//!
//! ```no_run
//! use std::time::Duration;
//! use haptloop_devices::{Hand, MountedDevice, Mount, SafetyConfig, SimOptions, SimPhantom};
//! use nalgebra::Vector3;
//!
//! let sim = SimPhantom::by_name("phantom-omni", SimOptions::for_rate_hz(1000), Hand::still())?;
//! let mount = Mount::new(Vector3::zeros(), [1.0, 0.0, 0.0, 0.0], 2.0)?;
//! let mut right = MountedDevice::new("right", sim, SafetyConfig::default(), mount)?;
//! right.register(Duration::ZERO, &Vector3::new(0.3, 0.0, 0.1)); // clutch onto the finger
//! let now = Duration::from_millis(1);
//! let r = right.read_scene(now);                           // every tick:
//! let f_scene = (Vector3::new(0.3, 0.0, 0.1) - r.tip_m_scene) * 200.0;
//! right.write_scene(f_scene, now);
//! # Ok::<(), haptloop_devices::DeviceError>(())
//! ```

use std::time::Duration;

use nalgebra::{UnitQuaternion, Vector3};

use crate::device::{Device, DeviceReading};
use crate::error::DeviceError;
use crate::mount::Mount;
use crate::safety::{SafeDevice, SafetyConfig, WriteOutcome};

/// A boxed device, for sessions mixing device types.
pub type DynDevice = Box<dyn Device + Send>;

/// A reading with the tip and stylus in the scene frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SceneReading {
    /// The device-frame reading (possibly held; see its flags).
    pub reading: DeviceReading,
    /// Tip position, metres, scene frame.
    pub tip_m_scene: Vector3<f64>,
    /// Stylus orientation, scene frame.
    pub orientation_scene: UnitQuaternion<f64>,
}

/// A device behind its safety layer, placed in the scene.
#[derive(Debug)]
pub struct MountedDevice<D> {
    /// Scene name of the device.
    pub name: String,
    /// The device behind the safety layer.
    pub device: SafeDevice<D>,
    /// Placement in the scene.
    pub mount: Mount,
}

impl<D: Device> MountedDevice<D> {
    /// Wraps `device` in a safety layer with `safety` and places it with `mount`.
    pub fn new(
        name: impl Into<String>,
        device: D,
        safety: SafetyConfig,
        mount: Mount,
    ) -> Result<Self, DeviceError> {
        Ok(Self {
            name: name.into(),
            device: SafeDevice::new(device, safety)?,
            mount,
        })
    }

    /// Reads the device at `now` and sets the mount origin so the tip maps
    /// onto `finger_m_scene` (registration / clutch). Returns the reading used.
    pub fn register(&mut self, now: Duration, finger_m_scene: &Vector3<f64>) -> DeviceReading {
        let r = self.device.read(now);
        self.mount.register(&r.tip_m_device, finger_m_scene);
        r
    }

    /// Reads at `now`, mapped into the scene frame.
    ///
    /// # Real-time
    /// No allocation; the safety layer's read plus a rotation.
    pub fn read_scene(&mut self, now: Duration) -> SceneReading {
        let reading = self.device.read(now);
        SceneReading {
            reading,
            tip_m_scene: self.mount.point_to_scene(&reading.tip_m_device),
            orientation_scene: self.mount.orientation_to_scene(&reading.orientation_device),
        }
    }

    /// Writes a scene-frame force (newtons) through the mount and the safety layer.
    ///
    /// # Real-time
    /// No allocation; the safety layer's write plus a rotation.
    pub fn write_scene(&mut self, force_n_scene: Vector3<f64>, now: Duration) -> WriteOutcome {
        let f = self.mount.force_to_device(&force_n_scene);
        self.device.write(f, now)
    }
}
