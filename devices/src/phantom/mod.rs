//! The simulated PHANToM family: model parameters, kinematics, encoders, motors
//! and the simulated arm that implements [`crate::Device`].
//!
//! | file | what it computes |
//! |---|---|
//! | [`kinematics`] | forward kinematics, Jacobian, closed-form inverse kinematics |
//! | [`encoder`] | joint angle ↔ encoder count quantisation |
//! | [`motors`] | Jᵀ torque mapping, torque saturation |
//! | [`thermal`] | motor heating and the continuous-force cut |
//! | [`drive`] | [`MotorDrive`]: thermal cut, Jᵀ mapping, saturation; shared by the simulated and the replayed arm |
//! | [`options`] | [`SimOptions`]: loop period, sub-steps, which limits are modelled |
//! | `stops` | end stops at the workspace box and the arm's reach |
//! | [`sim`] | [`SimPhantom`]: sub-stepped tip dynamics under hand + motor force |
//!
//! # Where the numbers come from
//!
//! | figure | Premium 1.5 | Omni / Touch | source |
//! |---|---|---|---|
//! | link lengths l1 = l2 | 0.2096 m | 0.135 m | Premium: Cavusoglu et al., "Kinematics and dynamics of PHANToM model 1.5 haptic interface" (value as quoted in the project brief, the paper itself was not available here); cross-check: the open replica `mahilab/Phantom` (`cpp/src/PhantomModel.hpp`) uses l1 = 0.20955 m. Omni: 0.135 m is the value used in the Omni kinematics literature (Jarillo-Silva et al., CERMA 2009) **from memory, not verified against the paper: estimate** |
//! | nominal position resolution | 0.03 mm | 0.055 mm | vendor datasheets **from memory** (research notes, table "Vendor datasheet figures": not found in the stored corpora) |
//! | encoder counts / joint rev | 43 900 | 15 400 | **derived**: 2π·l / resolution, rounded |
//! | peak force | 8.5 N | 3.3 N | datasheets (from memory) and CHAI3D `src/devices/CPhantomDevices.cpp` |
//! | continuous force | 1.4 N | 0.88 N | datasheets, **from memory** |
//! | workspace | 381×267×191 mm | 160×120×70 mm | datasheets, **from memory**; modelled as a box centred on the home pose |
//! | nominal stiffness | 3.5 N/mm | 1.02 N/mm (lowest axis of 1.26/2.31/1.02) | datasheets, **from memory** |
//! | stable stiffness at 1 kHz | 800 N/m | 700 N/m | CHAI3D `CPhantomDevices.cpp` (Premium 1.5 6DOF, PHANTOM Omni) |
//! | apparent tip mass | 75 g | 45 g | datasheets ("apparent mass at tip"), **from memory: estimate** |
//! | arm viscous damping at the tip | 0.0114 N·s/m | 0.0274 N·s/m | **estimate**: the joint damping 5e-4 N·m·s/rad of the `mahilab/Phantom` replica divided by l² |
//! | thermal time constant | 20 s | 10 s | **estimate** (typical small DC motor winding-to-ambient figure; no source found) |
//! | gimbal counts / rev | 4096 | 4096 | **estimate** (12-bit; the gimbal is sensed only) |
//!
//! CHAI3D's "damping" column (5 N·s/m for both) is the maximum *virtual*
//! damping it recommends rendering, not the arm's physical damping; it is not
//! used for the arm model.

pub mod drive;
pub mod encoder;
pub mod kinematics;
pub mod motors;
pub mod options;
pub mod sim;
mod stops;
pub mod thermal;

pub use drive::MotorDrive;
pub use kinematics::ArmGeometry;
pub use options::SimOptions;
pub use sim::SimPhantom;

use std::time::Duration;

use nalgebra::{UnitQuaternion, Vector3};

use crate::device::{ARM_JOINTS, DeviceInfo, DeviceLimits, DeviceReading, ReadingFlags};
use crate::error::DeviceError;

/// Parameters of one PHANToM model. Values and their sources: [module docs](self).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PhantomModel {
    /// Canonical scene-file name.
    pub name: &'static str,
    /// Arm link lengths.
    pub geometry: ArmGeometry,
    /// Encoder counts per joint revolution (all three joints).
    pub counts_per_rev: u32,
    /// Gimbal encoder counts per revolution (sensed only).
    pub gimbal_counts_per_rev: u32,
    /// Peak force, newtons.
    pub peak_force_n: f64,
    /// Continuous force rating, newtons.
    pub continuous_force_n: f64,
    /// Half extents of the workspace box around the home pose, metres.
    pub workspace_half_extent_m: [f64; 3],
    /// Apparent (effective) mass at the tip, kilograms.
    pub tip_mass_kg: f64,
    /// Viscous damping of the arm at the tip, N·s/m.
    pub arm_damping_n_s_per_m: f64,
    /// Datasheet structural stiffness, N/m.
    pub nominal_stiffness_n_per_m: f64,
    /// CHAI3D's stable closed-loop stiffness at 1 kHz, N/m.
    pub stable_stiffness_1khz_n_per_m: f64,
    /// Motor winding thermal time constant, seconds.
    pub thermal_time_constant_s: f64,
}

/// PHANToM Premium 1.5.
pub const PREMIUM_1_5: PhantomModel = PhantomModel {
    name: "phantom-premium-1.5",
    geometry: ArmGeometry {
        link1_m: 0.2096,
        link2_m: 0.2096,
    },
    counts_per_rev: 43_900,
    gimbal_counts_per_rev: 4096,
    peak_force_n: 8.5,
    continuous_force_n: 1.4,
    workspace_half_extent_m: [0.1905, 0.1335, 0.0955],
    tip_mass_kg: 0.075,
    arm_damping_n_s_per_m: 0.0114,
    nominal_stiffness_n_per_m: 3500.0,
    stable_stiffness_1khz_n_per_m: 800.0,
    thermal_time_constant_s: 20.0,
};

/// PHANToM Omni (also sold as Geomagic / 3D Systems Touch).
pub const OMNI: PhantomModel = PhantomModel {
    name: "phantom-omni",
    geometry: ArmGeometry {
        link1_m: 0.135,
        link2_m: 0.135,
    },
    counts_per_rev: 15_400,
    gimbal_counts_per_rev: 4096,
    peak_force_n: 3.3,
    continuous_force_n: 0.88,
    workspace_half_extent_m: [0.080, 0.060, 0.035],
    tip_mass_kg: 0.045,
    arm_damping_n_s_per_m: 0.0274,
    nominal_stiffness_n_per_m: 1020.0,
    stable_stiffness_1khz_n_per_m: 700.0,
    thermal_time_constant_s: 10.0,
};

/// Every model name a scene may use, aliases included.
pub const KNOWN_MODELS: &[&str] = &["phantom-premium-1.5", "phantom-omni", "phantom-touch"];

impl PhantomModel {
    /// Looks a model up by scene name (`phantom-touch` is an alias of
    /// `phantom-omni`). Unknown names are an error listing the known ones.
    pub fn by_name(name: &str) -> Result<&'static PhantomModel, DeviceError> {
        match name {
            "phantom-premium-1.5" => Ok(&PREMIUM_1_5),
            "phantom-omni" | "phantom-touch" => Ok(&OMNI),
            _ => Err(DeviceError::UnknownModel {
                name: name.to_owned(),
                known: KNOWN_MODELS.join(", "),
            }),
        }
    }

    /// Joint angle of one encoder count, radians.
    pub fn radians_per_count(&self) -> f64 {
        std::f64::consts::TAU / f64::from(self.counts_per_rev)
    }

    /// Tip displacement of one count at the nominal lever arm (link 1), metres:
    /// the "nominal position resolution" of the datasheet.
    pub fn nominal_resolution_m(&self) -> f64 {
        self.radians_per_count() * self.geometry.link1_m
    }

    /// The reading a driver builds from raw counts: angles = counts·Δ, tip =
    /// forward kinematics of those angles; orientation identity, no buttons,
    /// no flags (the caller fills those).
    ///
    /// # Real-time
    /// No allocation; constant time.
    pub fn reading_from_counts(&self, counts: &[i32; ARM_JOINTS], time: Duration) -> DeviceReading {
        let angles = encoder::Encoder::new(self.counts_per_rev).angles(counts);
        DeviceReading {
            time,
            joint_counts: *counts,
            joint_angles_rad: angles,
            tip_m_device: self.geometry.forward(&angles),
            orientation_device: UnitQuaternion::identity(),
            buttons: 0,
            flags: ReadingFlags::EMPTY,
        }
    }

    /// The [`DeviceInfo`] of this model.
    pub fn info(&self) -> DeviceInfo {
        let h = Vector3::from(self.workspace_half_extent_m);
        DeviceInfo {
            model: self.name,
            limits: DeviceLimits {
                peak_force_n: self.peak_force_n,
                continuous_force_n: self.continuous_force_n,
                workspace_min_m_device: -h,
                workspace_max_m_device: h,
                nominal_stiffness_n_per_m: self.nominal_stiffness_n_per_m,
                stable_stiffness_1khz_n_per_m: self.stable_stiffness_1khz_n_per_m,
            },
            counts_per_rev: [self.counts_per_rev; ARM_JOINTS],
            sensed_dof: 6,
            actuated_dof: 3,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn resolution_matches_published_figures() {
        // Datasheet: ~0.03 mm and ~0.055 mm; the counts were rounded to 100,
        // so 1 % is the rounding tolerance.
        assert!((PREMIUM_1_5.nominal_resolution_m() - 0.03e-3).abs() < 0.01 * 0.03e-3);
        assert!((OMNI.nominal_resolution_m() - 0.055e-3).abs() < 0.01 * 0.055e-3);
    }

    #[test]
    fn names_and_alias_resolve_and_unknown_lists_known() {
        assert_eq!(
            PhantomModel::by_name("phantom-touch").unwrap().name,
            "phantom-omni"
        );
        assert_eq!(
            PhantomModel::by_name("phantom-premium-1.5")
                .unwrap()
                .peak_force_n,
            8.5
        );
        let err = PhantomModel::by_name("phantom-desktop")
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("phantom-desktop")
                && err.contains("phantom-omni")
                && err.contains("phantom-touch"),
            "{err}"
        );
    }
}
