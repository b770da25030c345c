//! The matrix over the built-in mechanisms: masses, geometry, gains,
//! rates, a fast hand, a 1 m step of the hand and two fingers pulling a
//! body apart.

use haptloop::session::SessionOptions;
use toml::Value;

use super::edit::{builtin, edited, out_and_back, scale_geometry, set_masses, set_waypoints};
use super::harness::{MECHANISMS, assert_recovers, case, options};

#[test]
#[cfg_attr(debug_assertions, ignore = "minutes unoptimised: run with --release")]
fn masses_from_1e_4_to_1e3_kg() {
    for (m, seconds) in MECHANISMS {
        for kg in [1e-4, 1e3] {
            let scene = edited(m, |t| set_masses(t, kg));
            assert_recovers(&case(format!("{m}, {kg} kg"), scene, options(seconds)));
        }
    }
}

#[test]
#[cfg_attr(debug_assertions, ignore = "minutes unoptimised: run with --release")]
fn geometry_scaled_from_1e_3_to_10() {
    for (m, seconds) in MECHANISMS {
        for s in [1e-3, 10.0] {
            let scene = edited(m, |t| scale_geometry(t, s));
            assert_recovers(&case(
                format!("{m}, geometry × {s}"),
                scene,
                options(seconds),
            ));
        }
    }
}

#[test]
#[cfg_attr(debug_assertions, ignore = "minutes unoptimised: run with --release")]
fn gains_from_1e_3_to_1e3_times_the_default() {
    for (m, seconds) in MECHANISMS {
        for f in [1e-3, 1e3] {
            // K and k₂ together (k₂ = K, the method-of-multipliers choice).
            let scene = edited(m, |t| {
                let s = t.get_mut("solver").unwrap().as_table_mut().unwrap();
                s.insert("gain".into(), Value::Float(1000.0 * f));
                s.insert("multiplier_gain".into(), Value::Float(1000.0 * f));
            });
            assert_recovers(&case(format!("{m}, gains × {f}"), scene, options(seconds)));
        }
    }
}

#[test]
#[cfg_attr(debug_assertions, ignore = "minutes unoptimised: run with --release")]
fn rates_from_100_hz_to_20_khz() {
    for (m, seconds) in MECHANISMS {
        for (hz, s) in [(100, seconds), (20_000, seconds / 8.0)] {
            let o = SessionOptions {
                rate_hz: Some(hz),
                ..options(s)
            };
            let mut c = case(format!("{m} at {hz} Hz"), builtin(m), o);
            // The sphere toy promises 1 µm at its own 1 kHz; at a tenth of
            // that its hanging sphere lags 1.44 µm behind the rows, and the
            // report says the tolerance was exceeded.
            if m == "sphere-toy" && hz == 100 {
                c.holds_instead_m = Some(2e-6);
            }
            assert_recovers(&c);
        }
    }
}

/// The hand moves 5 cm at 5 m/s, holds, and comes back: back within
/// tolerance 0.1 s after it stops (the arm's tip is still catching up with
/// the hand until then). The sphere toy, hanging from its finger, comes
/// apart while it is jerked: ticks fail (counted by kind, force cut, the
/// slow loop re-places it) and it is back within 1 µm 1 s after.
#[test]
#[cfg_attr(debug_assertions, ignore = "minutes unoptimised: run with --release")]
fn a_hand_at_5_m_per_s() {
    for (m, _) in MECHANISMS {
        let (path, end) = out_and_back(0.2, [0.05, 0.0, 0.0], 0.01, 0.3);
        let scene = edited(m, |t| set_waypoints(t, 0, &path));
        let toy = m == "sphere-toy";
        let settle = if toy { 1.0 } else { 0.1 };
        let mut c = case(
            format!("{m}, hand at 5 m/s"),
            scene,
            options(end + settle + 0.3),
        );
        c.disturbance_end_s = end;
        c.settle_s = settle;
        c.expect_failures = toy;
        assert_recovers(&c);
    }
}

/// The hand target jumps 1 m in one tick, holds 0.3 s and jumps back; the
/// arm's tip swings after it for about half a second, so back within
/// tolerance 0.5 s after the jump back (the sphere toy: 1 s, with failed
/// ticks while it is yanked, as above).
#[test]
#[cfg_attr(debug_assertions, ignore = "minutes unoptimised: run with --release")]
fn a_1_m_step_of_the_hand_target() {
    for (m, _) in MECHANISMS {
        let (path, end) = out_and_back(0.2, [1.0, 0.0, 0.0], 0.001, 0.3);
        let scene = edited(m, |t| set_waypoints(t, 0, &path));
        let toy = m == "sphere-toy";
        let settle = if toy { 1.0 } else { 0.5 };
        let mut c = case(format!("{m}, 1 m step"), scene, options(end + settle + 0.3));
        c.disturbance_end_s = end;
        c.settle_s = settle;
        c.expect_failures = toy;
        assert_recovers(&c);
    }
}

/// Two hands pull the grasped box apart by 10 cm each and let go again: the
/// fingers cannot both be held, every figure stays finite and the forces
/// stay within the arms' peak.
#[test]
fn two_fingers_pulling_a_body_apart() {
    let scene = edited("grasp-2", |t| {
        let (left, _) = out_and_back(0.2, [-0.1, 0.0, 0.0], 0.1, 0.5);
        let (right, _) = out_and_back(0.2, [0.1, 0.0, 0.0], 0.1, 0.5);
        set_waypoints(t, 0, &left);
        set_waypoints(t, 1, &right);
    });
    let o = assert_recovers(&case("grasp-2 pulled apart".into(), scene, options(1.5)));
    assert_eq!(o.failed, 0);
}
