//! The fast loop's force error against the converged reference: it tells an
//! under-iterated loop from a converged one, says "not measured" (never 0)
//! where it does not apply, and sampling it allocates nothing on the fast
//! thread.

use crate::mock_session::MockSession;
use haptloop::report::summary::Summary;
use haptloop::scenes::resolve;
use haptloop::session::{self, Plan, SessionOptions};
use haptloop_rt::alloc::count;
use haptloop_rt::schedule::StopFlag;
use haptloop_solver::UpdateRule;
use std::time::Duration;

fn summary(scene: &str, options: SessionOptions) -> Summary {
    let scene = resolve(scene).unwrap();
    let plan = Plan::new(&scene, &options).unwrap();
    let o = session::run(&scene, plan, &StopFlag::new(), &mut |_| {}).unwrap();
    Summary::of(&o)
}

fn every_10_ms(seconds: f64) -> SessionOptions {
    SessionOptions {
        seconds,
        deterministic: true,
        reference_every: Some(Duration::from_millis(10)),
        ..SessionOptions::default()
    }
}

/// One gradient iteration per tick (Nelson & Cohen Eq. 3 as written) lags
/// the hand by millimetres; the default (4 projected steps) by micrometres.
/// The force error says so: at least 10× apart, in max and in RMS, over
/// every sampled tick of the default scene.
#[test]
fn an_under_iterated_fast_loop_shows_at_least_ten_times_the_force_error() {
    let default = summary("four-bar", every_10_ms(2.0));
    let under = summary(
        "four-bar",
        SessionOptions {
            update: Some(UpdateRule::Gradient),
            iterations: Some(1),
            ..every_10_ms(2.0)
        },
    );
    for s in [&default, &under] {
        let r = &s.reference;
        assert_eq!(r.missing, None);
        assert_eq!((r.samples, r.compared), (200, 200), "{r:?}");
        assert!(r.not_compared.is_empty(), "{r:?}");
        assert!(r.force_error_n.max.is_finite() && r.force_n.max > 0.1);
    }
    let (d, u) = (&default.reference, &under.reference);
    assert!(d.force_error_n.max < 1e-2, "default: {:?}", d.force_error_n);
    assert!(
        u.force_error_n.max >= 10.0 * d.force_error_n.max
            && u.force_error_n.rms >= 10.0 * d.force_error_n.rms,
        "one gradient step {:?} vs default {:?}",
        u.force_error_n,
        d.force_error_n
    );
    assert!(u.configuration_error_m.max >= 10.0 * d.configuration_error_m.max);
    // Relative figures are the absolute ones over the reference force.
    let rel = d.force_error_n.max / d.force_n.max;
    assert!((d.force_error_relative.max - rel).abs() <= 1e-12 * rel);
}

/// A scene with contact rows is not measured, says why, and writes its
/// figures as "NaN" next to the reason (never 0); a scene of free bodies
/// held by fingers (no joint rows) is measured.
#[test]
fn the_force_error_is_measured_or_says_why_not() {
    let contact = summary("pinch-lift", every_10_ms(0.2));
    let r = &contact.reference;
    assert!(
        r.missing
            .as_deref()
            .unwrap()
            .starts_with("not measured: the scene has contact"),
        "{r:?}"
    );
    let json = serde_json::to_value(&contact).unwrap();
    assert_eq!(json["reference"]["force_error_n"]["max"], "NaN");
    assert_eq!(json["reference"]["compared"], 0);
    let text = haptloop::report::session::render(&contact, &[]);
    assert!(text.contains("force error against the converged reference: not measured"));

    let free = summary("grasp-3", every_10_ms(0.2));
    assert_eq!(free.reference.missing, None);
    assert_eq!(free.reference.compared, 20);
    assert!(free.reference.force_error_n.max < 1e-3);
}

/// Sampling every tick for the reference allocates nothing on the fast
/// thread (two state copies and a mailbox publish per tick).
#[test]
fn sampling_every_tick_allocates_nothing() {
    for name in ["four-bar", "four-bar-design"] {
        let scene = resolve(name).unwrap();
        let options = SessionOptions {
            reference_every: Some(Duration::ZERO),
            ..every_10_ms(30.0)
        };
        let mut m = MockSession::new(&scene, &options);
        assert_eq!(m.plan.reference_every_ticks, 1);
        m.run(100);
        let (_, stats) = count(|| m.run(1000));
        assert_eq!(stats.total(), 0, "{name}: {stats:?}");
        assert!(m.built.fast.sampled());
        while m.built.trace.pop().is_some() {}
        // The slow side sees the newest sample; the 1099 before it were
        // overwritten (counted, never silently lost).
        m.built.slow.check_reference();
        let r = m.built.slow.stats().reference;
        assert_eq!((r.captured, r.compared, r.overwritten), (1100, 1, 1099));
    }
}

/// The summary and the text report say which coordinates the fast loop ran
/// in (`Program::coordinates`) and how many joint ticks fell back to the
/// augmented tick: the default says augmented; `coordinates = joint` on the
/// four-bar says joint, none fallen back over 0.2 s of the hand's motion.
#[test]
fn the_summary_says_which_coordinates_ran() {
    let default = summary("four-bar", every_10_ms(0.2));
    assert!(
        default
            .coordinates
            .starts_with("augmented (asked: augmented"),
        "{}",
        default.coordinates
    );
    let joint = summary(
        "four-bar",
        SessionOptions {
            coordinates: Some(haptloop_solver::Coordinates::Joint),
            ..every_10_ms(0.2)
        },
    );
    assert!(
        joint.coordinates.starts_with("joint (asked: joint"),
        "{}",
        joint.coordinates
    );
    assert_eq!(joint.joint_fallbacks, 0);
    let text = haptloop::report::session::render(&joint, &[]);
    let line = format!(
        "fast-loop coordinates: {}; joint ticks run as augmented ticks: 0",
        joint.coordinates
    );
    assert!(text.contains(&line), "{text}");
}
