//! The simulated hand: a spring–damper grip pulling the tip toward a target
//! that follows a trajectory.
//!
//! Trajectories are **offsets** (metres, device frame) from the tip's position
//! when the session starts (the anchor), matching `hand` in `docs/scene-format.md`:
//! `still`, `line {to, seconds}` then hold, `circle {radius, hz, u, v}` =
//! r((cos ωt − 1)u + sin ωt v), and a recorded `trace` ([`HandTrace`]). The
//! session converts scene-frame offsets with
//! [`crate::Mount::trajectory_to_device`].
//!
//! The grip force on the tip is `k (target − p) + b (v_target − v)`: the tip
//! moves under this force **plus** the motor force, so what the loop renders
//! changes the motion. The grip is massless (the hand's own mass is lumped into
//! nothing); its orientation is held constant and only sensed by the gimbal —
//! the modelled arms actuate 3 DOF, so no torque is rendered on it.
//!
//! # Real-time
//! [`Hand::target`] and [`Trajectory::sample`] do not allocate; a trace is
//! searched by bisection (O(log n)).

use std::time::Duration;

use nalgebra::{UnitQuaternion, Vector3};

use crate::hand_trace::HandTrace;

/// Grip impedance of the simulated hand.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Grip {
    /// Spring between target and tip, N/m.
    pub stiffness_n_per_m: f64,
    /// Damper between target and tip velocity, N·s/m.
    pub damping_n_s_per_m: f64,
}

impl Default for Grip {
    /// A light-to-moderate pen-hold grip: 300 N/m and 1.0 N·s/m. Fingertip and
    /// pen-hold impedance studies (Hajian & Howe 1997; Israr, Choi & Tan 2006)
    /// report stiffness of a few hundred N/m and damping of the order of
    /// 1 N·s/m, both rising with grip force. These defaults are **estimates**
    /// of that order, recalled rather than quoted; a relaxed grip (lower
    /// damping) is the worse case for stability — see [`Grip::light`].
    fn default() -> Self {
        Self {
            stiffness_n_per_m: 300.0,
            damping_n_s_per_m: 1.0,
        }
    }
}

impl Grip {
    /// A relaxed grip (100 N/m, 0.3 N·s/m, estimate): little damping from the
    /// hand, the hard case for wall stability.
    pub fn light() -> Self {
        Self {
            stiffness_n_per_m: 100.0,
            damping_n_s_per_m: 0.3,
        }
    }
}

/// Where the hand target goes, as an offset from the anchor (device frame).
#[derive(Debug, Clone, PartialEq)]
pub enum Trajectory {
    /// Stay at the anchor.
    Still,
    /// Move at constant speed to `to_m`, reaching it after `duration`, then hold.
    Line {
        /// Final offset, metres.
        to_m: Vector3<f64>,
        /// Travel time (zero = jump).
        duration: Duration,
    },
    /// r((cos ωt − 1)u + sin ωt v), ω = 2π·`frequency_hz`; starts at zero offset.
    Circle {
        /// Radius, metres.
        radius_m: f64,
        /// Revolutions per second.
        frequency_hz: f64,
        /// First in-plane direction (unit).
        u: Vector3<f64>,
        /// Second in-plane direction (unit).
        v: Vector3<f64>,
    },
    /// A recorded path, linearly interpolated.
    Trace(HandTrace),
}

/// Target offset and its velocity at one instant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TargetSample {
    /// Offset from the anchor, metres, device frame.
    pub offset_m: Vector3<f64>,
    /// Velocity of the target, m/s, device frame.
    pub velocity_m_per_s: Vector3<f64>,
}

impl Trajectory {
    /// The target offset at session time `t`.
    pub fn sample(&self, t: Duration) -> TargetSample {
        self.sample_s(t.as_secs_f64())
    }

    pub(crate) fn sample_s(&self, t: f64) -> TargetSample {
        match self {
            Trajectory::Still => TargetSample {
                offset_m: Vector3::zeros(),
                velocity_m_per_s: Vector3::zeros(),
            },
            Trajectory::Line { to_m, duration } => {
                let d = duration.as_secs_f64();
                if d <= 0.0 || t >= d {
                    TargetSample {
                        offset_m: *to_m,
                        velocity_m_per_s: Vector3::zeros(),
                    }
                } else {
                    let s = (t / d).max(0.0);
                    TargetSample {
                        offset_m: to_m * s,
                        velocity_m_per_s: to_m / d,
                    }
                }
            }
            Trajectory::Circle {
                radius_m,
                frequency_hz,
                u,
                v,
            } => {
                let w = std::f64::consts::TAU * frequency_hz;
                let (s, c) = (w * t).sin_cos();
                TargetSample {
                    offset_m: (u * (c - 1.0) + v * s) * *radius_m,
                    velocity_m_per_s: (u * -s + v * c) * (radius_m * w),
                }
            }
            Trajectory::Trace(trace) => trace.sample_s(t),
        }
    }

    /// The smallest and largest offset, per axis, the target reaches over
    /// the first `duration` of a session: exact at the samples of a trace and
    /// the ends of a line, within 1e-5 of the radius for a circle (sampled
    /// every half degree). Not for the real-time thread.
    pub fn extent(&self, duration: Duration) -> (Vector3<f64>, Vector3<f64>) {
        let t_end = duration.as_secs_f64();
        let mut lo = Vector3::zeros();
        let mut hi = Vector3::zeros();
        let mut take = |o: Vector3<f64>| {
            lo = lo.inf(&o);
            hi = hi.sup(&o);
        };
        match self {
            Trajectory::Still => {}
            Trajectory::Line { .. } => take(self.sample_s(t_end).offset_m),
            Trajectory::Circle { frequency_hz, .. } => {
                let span = if *frequency_hz > 0.0 {
                    t_end.min(1.0 / frequency_hz)
                } else {
                    0.0
                };
                for k in 0..=720 {
                    take(self.sample_s(span * f64::from(k) / 720.0).offset_m);
                }
            }
            Trajectory::Trace(trace) => {
                for (t, o) in trace.points() {
                    if t > t_end {
                        break;
                    }
                    take(o);
                }
                take(trace.sample_s(t_end).offset_m);
            }
        }
        (lo, hi)
    }

    /// The same path with every offset mapped by the linear map `f` (used to
    /// change frame and scale).
    pub fn map_offsets(&self, f: impl Fn(Vector3<f64>) -> Vector3<f64>) -> Trajectory {
        match self {
            Trajectory::Still => Trajectory::Still,
            Trajectory::Line { to_m, duration } => Trajectory::Line {
                to_m: f(*to_m),
                duration: *duration,
            },
            Trajectory::Circle {
                radius_m,
                frequency_hz,
                u,
                v,
            } => {
                // Map r·u and r·v; keep unit directions and put the length in r.
                let (ru, rv) = (f(u * *radius_m), f(v * *radius_m));
                let r = ru.norm();
                let (u2, v2) = if r > 0.0 { (ru / r, rv / r) } else { (*u, *v) };
                Trajectory::Circle {
                    radius_m: r,
                    frequency_hz: *frequency_hz,
                    u: u2,
                    v: v2,
                }
            }
            Trajectory::Trace(trace) => Trajectory::Trace(trace.map_offsets(f)),
        }
    }
}

/// The simulated hand: grip, trajectory, held orientation and buttons.
#[derive(Debug, Clone, PartialEq)]
pub struct Hand {
    /// Grip impedance.
    pub grip: Grip,
    /// Path of the target (offsets from the anchor).
    pub trajectory: Trajectory,
    /// Orientation in which the stylus is held, device frame (sensed by the
    /// gimbal, not actuated).
    pub orientation_device: UnitQuaternion<f64>,
    /// Buttons held down (bit mask).
    pub buttons: u8,
}

impl Hand {
    /// A hand with the default grip following `trajectory`.
    pub fn new(trajectory: Trajectory) -> Self {
        Self {
            grip: Grip::default(),
            trajectory,
            orientation_device: UnitQuaternion::identity(),
            buttons: 0,
        }
    }

    /// A hand that holds still with the default grip.
    pub fn still() -> Self {
        Self::new(Trajectory::Still)
    }

    /// Replaces the grip.
    #[must_use]
    pub fn with_grip(mut self, grip: Grip) -> Self {
        self.grip = grip;
        self
    }

    /// The target position (anchor + offset) and velocity at `t`.
    pub fn target(&self, anchor_m_device: &Vector3<f64>, t: Duration) -> TargetSample {
        let s = self.trajectory.sample(t);
        TargetSample {
            offset_m: anchor_m_device + s.offset_m,
            velocity_m_per_s: s.velocity_m_per_s,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn circle_starts_at_zero_and_velocity_is_its_derivative() {
        let c = Trajectory::Circle {
            radius_m: 0.02,
            frequency_hz: 0.5,
            u: Vector3::x(),
            v: Vector3::y(),
        };
        assert!(c.sample(Duration::ZERO).offset_m.norm() < 1e-15);
        for t in [0.1, 0.37, 1.2] {
            let h = 1e-6;
            let fd = (c.sample_s(t + h).offset_m - c.sample_s(t - h).offset_m) / (2.0 * h);
            assert!((fd - c.sample_s(t).velocity_m_per_s).norm() < 1e-9);
        }
        // Diametrically opposite point after half a period: offset −2r·u.
        let half = c.sample(Duration::from_secs(1)).offset_m;
        assert!(
            (half - Vector3::new(-0.04, 0.0, 0.0)).norm() < 1e-12,
            "{half}"
        );
    }

    #[test]
    fn line_reaches_and_holds() {
        let l = Trajectory::Line {
            to_m: Vector3::new(0.01, 0.0, -0.02),
            duration: Duration::from_secs(2),
        };
        assert_eq!(
            l.sample(Duration::from_secs(1)).offset_m,
            Vector3::new(0.005, 0.0, -0.01)
        );
        let end = l.sample(Duration::from_secs(5));
        assert_eq!(end.offset_m, Vector3::new(0.01, 0.0, -0.02));
        assert_eq!(end.velocity_m_per_s, Vector3::zeros());
    }

    #[test]
    fn map_offsets_scales_circle_radius() {
        let c = Trajectory::Circle {
            radius_m: 0.02,
            frequency_hz: 1.0,
            u: Vector3::x(),
            v: Vector3::y(),
        };
        let Trajectory::Circle { radius_m, u, .. } = c.map_offsets(|o| o * 0.5) else {
            panic!()
        };
        assert!((radius_m - 0.01).abs() < 1e-15 && (u - Vector3::x()).norm() < 1e-15);
    }
}
