//! A million ticks of the default scene.

use super::edit::builtin;
use super::harness::{case, check_recovered, drive_with, options};

/// A million ticks of the default scene (1000 s at 1 kHz, 500 turns of the
/// hand's circle), deterministic: nothing fails, nothing is non-finite, the
/// violation stays within 1 µm, and nothing drifts: the configuration at
/// the same phase of the circle after 10 s and after 1000 s agree within
/// the scene's tolerance, and the quaternion norms with them. It takes
/// 13–16 s in release (`cargo test --release`, what CI runs) and minutes
/// unoptimised, so a debug build skips it.
#[test]
#[cfg_attr(debug_assertions, ignore = "a million ticks: run with --release")]
fn a_million_ticks_of_the_default_scene() {
    let c = case(
        "four-bar, 1e6 ticks".into(),
        builtin("four-bar"),
        options(1000.0),
    );
    let (mut early, mut late) = (Vec::new(), Vec::new());
    let o = drive_with(&c, &mut |k, p| {
        if k == 9_999 {
            early = p.q().to_vec();
        } else if k == 999_999 {
            late = p.q().to_vec();
        }
    });
    let o = check_recovered(&c, o);
    assert_eq!(o.failed, 0);
    assert!(o.violation_max_m <= 1e-6, "{o:?}");
    let moved = early
        .iter()
        .zip(&late)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(moved < 1e-6, "the orbit drifted by {moved:e} in 990 s");
    assert!(o.norm_end <= 1e-9, "{o:?}");
}
