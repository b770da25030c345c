//! haptloop-devices: force-feedback devices for the fast loop — the [`Device`]
//! trait, simulated PHANToM arms ([`SimPhantom`]: `phantom-premium-1.5`,
//! `phantom-omni` / `phantom-touch`), the simulated [`Hand`] that holds them,
//! the [`SafeDevice`] safety layer every device sits behind, injected faults,
//! [`Mount`]s that place several devices in one scene, and trace
//! record ([`TraceRecorder`]) / replay ([`ReplayDevice`]), and the
//! [`VirtualDevice`] a person moves with the mouse through a [`Pointer`].
//!
//! Data flow, once per tick and per device (all `Copy` values, no allocation):
//!
//! ```text
//!  Hand (grip spring–damper → trajectory target)
//!    │ force on the tip                 ┌──────────── fast loop (session) ─────────────┐
//!    ▼                                  │                                              │
//!  SimPhantom: tip mass + damping, ─read(now)─► SafeDevice ─DeviceReading─► Mount ─► p_scene ─► solver
//!  sub-stepped to `now`; encoders          │  holds bad readings, counts faults          │
//!  quantise joint angles                   │                                              │
//!    ▲                                     │                                              ▼
//!    └── motors: τ = Jᵀ F, saturation, ◄─write(F, now)─ SafeDevice ◄── F_device ◄── Mount ◄── F_scene
//!        thermal cut, ZOH until next write    NaN guard, clamp, ramp, rate limit,
//!                                             velocity limit, watchdog → CutRecord
//! ```
//!
//! Time is a [`std::time::Duration`] since session start, given by the caller
//! (real or mock clock): a simulated device integrates its physics up to the
//! time it is given, so the same calls give bit-identical results. Vectors
//! named `*_device` are in the device frame (metres, newtons; y up, z toward the
//! user), `*_scene` in the scene frame. Set-up errors are [`DeviceError`] /
//! [`TraceError`]; fast-path problems are `Copy` values ([`DeviceFault`],
//! [`FaultKind`], [`CutReason`]). The [`passivity`] module measures the largest
//! stable wall stiffness against Colgate's bound.

pub mod device;
pub mod error;
pub mod fault;
pub mod hand;
pub mod hand_trace;
pub mod mount;
pub mod passivity;
pub mod phantom;
pub mod pointer;
pub mod replay;
pub mod rig;
pub mod safety;
pub mod trace;
mod trace_read;
pub mod virtual_device;

pub use device::{
    ARM_JOINTS, Device, DeviceFault, DeviceInfo, DeviceLimits, DeviceReading, MotorReport,
    ReadingFlags,
};
pub use error::{DeviceError, TraceError};
pub use fault::{FaultKind, FaultSchedule, InjectedFault};
pub use hand::{Grip, Hand, TargetSample, Trajectory};
pub use hand_trace::{HandTrace, MAX_HAND_SAMPLES, MAX_HAND_TRACE_BYTES};
pub use mount::Mount;
pub use phantom::{
    KNOWN_MODELS, MotorDrive, OMNI, PREMIUM_1_5, PhantomModel, SimOptions, SimPhantom,
};
pub use pointer::{POINTER_RANGE_M, POINTER_RESOLUTION_M, Pointer};
pub use replay::{ReplayCheck, ReplayDevice};
pub use rig::{DynDevice, MountedDevice, SceneReading};
pub use safety::{
    CutReason, CutRecord, FaultRecord, Health, SafeDevice, SafetyConfig, SafetyCounters,
    SafetyEvent, WriteOutcome,
};
pub use trace::{
    MAX_COMMAND_N, MAX_TRACE_BYTES, MAX_TRACE_ROWS, Trace, TraceHeader, TraceRecorder, TraceRow,
    TraceStream,
};
pub use virtual_device::{VIRTUAL_MODEL, VirtualDevice, VirtualParams};
