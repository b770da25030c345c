//! The fourth pass's cuts of the small linkages' tick against the old
//! path, bit for bit: the last projected step's masked prediction
//! (`al::prediction`) and the value-only evaluation at an unchanged q
//! (`evaluate::same_q`). Two programs of each mechanism tick the same
//! targets, one with both switched off; q, the multipliers and every finger
//! output must agree to the last bit on every tick, and each cut must have
//! been taken.

use std::sync::Arc;
use std::time::Duration;

use nalgebra::Vector3;

use crate::mechanisms::{bennett, four_bar, stewart};
use crate::program::TickOutcome;
use crate::{FingerTarget, Model, Program, SolverSettings};

fn peaucellier() -> Model {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/peaucellier.toml");
    crate::scene::load(&path).unwrap().compile().unwrap().model
}

fn bits(x: &[f64]) -> Vec<u64> {
    x.iter().map(|v| v.to_bits()).collect()
}

/// `ticks` ticks of both programs toward the targets `path(k)` gives;
/// panics at the first bit that differs. Returns (last steps masked,
/// evaluations at an unchanged q) of the new program.
fn run_both(
    name: &str,
    model: Model,
    ticks: usize,
    path: impl Fn(usize, &[FingerTarget]) -> Vec<FingerTarget>,
) -> (u64, u64) {
    let model = Arc::new(model);
    let mut new = Program::new(model.clone(), SolverSettings::default()).unwrap();
    let mut old = Program::new(model.clone(), SolverSettings::default()).unwrap();
    old.projected.test_whole = true;
    old.ev.same_q.disable();
    let t0 = model.initial_targets();
    for k in 0..ticks {
        let targets = path(k, &t0);
        let (a, b) = (
            new.tick(&targets, Duration::from_millis(1)),
            old.tick(&targets, Duration::from_millis(1)),
        );
        assert_eq!(a.status, TickOutcome::Ok, "{name} tick {k}");
        assert_eq!(a.status, b.status, "{name} tick {k}");
        assert_eq!(bits(&new.q), bits(&old.q), "{name} tick {k}: q");
        assert_eq!(bits(&new.lambda), bits(&old.lambda), "{name} tick {k}: λ");
        for (f, g) in new.outputs.iter().zip(&old.outputs) {
            assert_eq!(
                format!("{f:?}"),
                format!("{g:?}"),
                "{name} tick {k}: output"
            );
        }
    }
    assert_eq!(
        old.projected.test_lasts, 0,
        "{name}: the old path masks nothing"
    );
    (new.projected.test_lasts, new.ev.same_q.test_taken)
}

/// A small circle of the hand, as the scenes' paths.
fn circle(k: usize, t0: &[FingerTarget]) -> Vec<FingerTarget> {
    let a = 0.004 * (k as f64 * 0.05).sin();
    let b = 0.004 * (k as f64 * 0.05).cos() - 0.004;
    t0.iter()
        .map(|t| FingerTarget {
            position_m: t.position_m + Vector3::new(a, b, 0.5 * a),
            ..*t
        })
        .collect()
}

#[test]
fn the_linkage_ticks_equal_the_old_path_bit_for_bit() {
    for (name, model) in [
        ("four-bar", four_bar()),
        ("bennett", bennett()),
        ("peaucellier", peaucellier()),
    ] {
        let (lasts, same_q) = run_both(name, model, 150, circle);
        assert!(lasts >= 140, "{name}: {lasts} last steps masked");
        assert!(
            same_q >= 140,
            "{name}: {same_q} first steps at an unchanged q"
        );
    }
}

/// Stewart's platform pushed up against its stroke limits and back: the
/// cuts on ticks that activate and release limits (and take the release
/// spare's first solve back, `force::feedback::spare`).
#[test]
fn stewart_against_its_stroke_limits_equals_the_old_path_bit_for_bit() {
    let push = |k: usize, t0: &[FingerTarget]| -> Vec<FingerTarget> {
        let z = 0.12 * (k as f64 / 150.0).min(1.0) - 0.12 * ((k as f64 - 250.0) / 150.0).max(0.0);
        t0.iter()
            .map(|t| FingerTarget {
                position_m: t.position_m + Vector3::new(0.0, 0.0, z),
                ..*t
            })
            .collect()
    };
    let (lasts, same_q) = run_both("stewart", stewart(), 400, push);
    assert!(lasts >= 360, "stewart: {lasts} last steps masked");
    assert!(same_q > 0, "stewart: {same_q}");
}
