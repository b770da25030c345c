//! [`SceneSettings`]: the `[solver]` keys a scene file set, and the one way
//! they become the solver's and the contact layer's settings
//! ([`SceneSettings::apply_to`], [`SceneSettings::contact_settings`]).
//! Whoever runs a scene (the session, tests, probes) starts from these and
//! overrides what it must afterwards (the session: its command-line flags).

use super::spec::SolverSection;
use crate::geometry::ContactSettings;
use crate::{Coordinates, SolverSettings};
use std::time::Duration;
use toml::Spanned;

/// The `[solver]` values the file set (unset keys are `None`; the session
/// fills them from command-line flags or the solver's defaults).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct SceneSettings {
    /// Fast-loop rate, Hz.
    pub rate_hz: Option<u32>,
    /// AL iterations per tick.
    pub iterations: Option<u32>,
    /// h.
    pub step: Option<f64>,
    /// K.
    pub gain: Option<f64>,
    /// k₂.
    pub multiplier_gain: Option<f64>,
    /// Newton-KKT stopping tolerance.
    pub placement_tolerance: Option<f64>,
    /// μ.
    pub damping: Option<f64>,
    /// Witness activation distance, m.
    pub contact_distance: Option<f64>,
    /// Witness removal distance, m.
    pub release_distance: Option<f64>,
    /// Violation the scene promises to stay under, m.
    pub violation_tolerance: Option<f64>,
    /// Virtual-coupling stiffness, N/m.
    pub coupling_stiffness: Option<f64>,
    /// Virtual-coupling damping, N·s/m.
    pub coupling_damping: Option<f64>,
    /// Velocity low-pass time constant, s.
    pub velocity_filter: Option<f64>,
    /// Inertial motion (`dynamics`).
    pub dynamics: Option<bool>,
    /// Contact penetration beyond which the slow loop backs up, m.
    pub penetration_tolerance: Option<f64>,
    /// Pre-emptive witness guards (`contact_guards`).
    pub contact_guards: Option<bool>,
    /// The fast loop's coordinates (validated).
    pub coordinates: Option<Coordinates>,
}

impl SceneSettings {
    /// The values of a validated `[solver]` table.
    pub(super) fn from_section(s: &SolverSection) -> SceneSettings {
        let f = |v: &Option<Spanned<f64>>| v.as_ref().map(|x| *x.get_ref());
        SceneSettings {
            rate_hz: s.rate_hz.as_ref().map(|x| *x.get_ref()),
            iterations: s.iterations.as_ref().map(|x| *x.get_ref()),
            step: f(&s.step),
            gain: f(&s.gain),
            multiplier_gain: f(&s.multiplier_gain),
            placement_tolerance: f(&s.placement_tolerance),
            damping: f(&s.damping),
            contact_distance: f(&s.contact_distance),
            release_distance: f(&s.release_distance),
            violation_tolerance: f(&s.violation_tolerance),
            coupling_stiffness: f(&s.coupling_stiffness),
            coupling_damping: f(&s.coupling_damping),
            velocity_filter: f(&s.velocity_filter),
            dynamics: s.dynamics.as_ref().map(|x| *x.get_ref()),
            penetration_tolerance: f(&s.penetration_tolerance),
            contact_guards: s.contact_guards.as_ref().map(|x| *x.get_ref()),
            coordinates: (s.coordinates.as_ref()).and_then(|c| Coordinates::parse(c.get_ref())),
        }
    }

    /// Sets every solver setting the scene stated over `solver`: iterations,
    /// step, gain, multiplier gain, coupling stiffness and damping, velocity
    /// filter, inertial motion and coordinates. Keys the scene left unset
    /// keep `solver`'s value (a session puts its own defaults there first,
    /// e.g. inertial motion by [`crate::dynamics::inertial_by_default`]).
    /// The other keys are not solver settings: the rate and the tolerances
    /// are the session's, the contact keys [`Self::contact_settings`]'.
    pub fn apply_to(&self, solver: &mut SolverSettings) {
        let Self {
            iterations,
            step,
            gain,
            multiplier_gain,
            coupling_stiffness,
            coupling_damping,
            velocity_filter,
            dynamics,
            coordinates,
            rate_hz: _,
            placement_tolerance: _,
            damping: _,
            contact_distance: _,
            release_distance: _,
            violation_tolerance: _,
            penetration_tolerance: _,
            contact_guards: _,
        } = *self;
        let set = |to: &mut f64, v: Option<f64>| *to = v.unwrap_or(*to);
        solver.iterations = iterations.unwrap_or(solver.iterations);
        set(&mut solver.step, step);
        set(&mut solver.gain, gain);
        set(&mut solver.multiplier_gain, multiplier_gain);
        set(&mut solver.coupling_stiffness_n_per_m, coupling_stiffness);
        set(&mut solver.coupling_damping_n_s_per_m, coupling_damping);
        if let Some(tau) = velocity_filter {
            solver.velocity_filter = Duration::from_secs_f64(tau);
        }
        solver.dynamics = dynamics.unwrap_or(solver.dynamics);
        solver.coordinates = coordinates.unwrap_or(solver.coordinates);
    }

    /// [`SolverSettings::default`] with the scene's solver keys applied
    /// ([`Self::apply_to`]).
    pub fn solver_settings(&self) -> SolverSettings {
        let mut solver = SolverSettings::default();
        self.apply_to(&mut solver);
        solver
    }

    /// The contact layer's settings: the scene's contact and release
    /// distances, penetration tolerance and guards over the defaults.
    pub fn contact_settings(&self) -> ContactSettings {
        let d = ContactSettings::default();
        ContactSettings {
            contact_distance_m: self.contact_distance.unwrap_or(d.contact_distance_m),
            release_distance_m: self.release_distance.unwrap_or(d.release_distance_m),
            penetration_tolerance_m: (self.penetration_tolerance)
                .unwrap_or(d.penetration_tolerance_m),
            guards: self.contact_guards.unwrap_or(d.guards),
            ..d
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{ForceSolver, RedundancyCheck, UpdateRule};

    /// Every key set, each to a value no default has.
    fn every_key() -> SceneSettings {
        SceneSettings {
            rate_hz: Some(777),
            iterations: Some(7),
            step: Some(0.7),
            gain: Some(123.0),
            multiplier_gain: Some(45.0),
            placement_tolerance: Some(3e-7),
            damping: Some(2e-3),
            contact_distance: Some(7e-3),
            release_distance: Some(9e-3),
            violation_tolerance: Some(4e-5),
            coupling_stiffness: Some(321.0),
            coupling_damping: Some(0.07),
            velocity_filter: Some(0.004),
            dynamics: Some(true),
            penetration_tolerance: Some(6e-4),
            contact_guards: Some(false),
            coordinates: Some(Coordinates::Joint),
        }
    }

    /// Every field of the result, written out (no `..`: a new solver
    /// setting breaks this test until it is decided whether scenes set it).
    #[test]
    fn a_scene_with_every_key_sets_every_solver_setting_it_states() {
        let expected = SolverSettings {
            update: UpdateRule::Projected,
            iterations: 7,
            step: 0.7,
            gain: 123.0,
            multiplier_gain: 45.0,
            finger_pull_limit_m: 1e-2,
            contact_step_m: f64::INFINITY,
            finger_weight: 1.0,
            length_scale_m: None,
            coupling_stiffness_n_per_m: 321.0,
            coupling_damping_n_s_per_m: 0.07,
            coupling_angular_stiffness_nm_per_rad: 0.0,
            velocity_filter: Duration::from_micros(4000),
            force_solver: ForceSolver::Cholesky,
            force_regularization: 0.0,
            dynamics: true,
            redundancy: RedundancyCheck::Auto,
            norm_rows_out: false,
            coordinates: Coordinates::Joint,
        };
        assert_eq!(every_key().solver_settings(), expected);
        let d = ContactSettings::default();
        let contact = every_key().contact_settings();
        assert_eq!(
            (
                contact.contact_distance_m,
                contact.release_distance_m,
                contact.penetration_tolerance_m,
                contact.guards
            ),
            (7e-3, 9e-3, 6e-4, false)
        );
        assert_eq!(
            (
                contact.slots_per_pair,
                contact.finger_slots,
                contact.max_pairs_per_body
            ),
            (d.slots_per_pair, d.finger_slots, d.max_pairs_per_body)
        );
        assert!(d.guards, "the test's guards value is the default");
    }

    /// Unset keys leave what was there: an empty scene changes nothing,
    /// over the defaults or over a non-default base.
    #[test]
    fn unset_keys_keep_the_base() {
        let empty = SceneSettings::default();
        assert_eq!(empty.solver_settings(), SolverSettings::default());
        let mut base = every_key().solver_settings();
        base.update = UpdateRule::Gradient;
        let before = base;
        empty.apply_to(&mut base);
        assert_eq!(base, before);
        let c = empty.contact_settings();
        let d = ContactSettings::default();
        assert_eq!(
            (c.contact_distance_m, c.release_distance_m),
            (d.contact_distance_m, d.release_distance_m)
        );
        assert_eq!(
            (c.penetration_tolerance_m, c.guards),
            (d.penetration_tolerance_m, d.guards)
        );
    }
}
