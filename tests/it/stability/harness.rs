//! A case of the matrix run as a whole session on the mock clock, tick by
//! tick, and what it must show (see the module docs of `stability`).

use haptloop::report::summary::Summary;
use haptloop::scenes::Scene;
use haptloop::session::{self, Plan, SessionOptions};
use haptloop_devices::PhantomModel;
use haptloop_rt::clock::{MockClock, Nanos};
use haptloop_rt::schedule::{SafetyEvent, StopFlag, Tick, TickBody, TickStatus};
use haptloop_solver::TickOutcome;

/// One case of the matrix.
pub(super) struct Case {
    pub(super) name: String,
    pub(super) scene: Scene,
    pub(super) options: SessionOptions,
    /// Session time at which the disturbance is over, s (0: the extreme
    /// holds for the whole run and every tick must be within tolerance).
    pub(super) disturbance_end_s: f64,
    /// Time allowed after it to be back within tolerance, s.
    pub(super) settle_s: f64,
    /// The disturbance is expected to make ticks fail (counted by kind,
    /// reported, force cut, the slow loop recovering the configuration);
    /// none may fail once it is over and the settle window has passed.
    pub(super) expect_failures: bool,
    /// The disturbance may make ticks fail, or may not (a chaotic passage
    /// through a singular pose, where the last bits decide it). Any that
    /// fail are held to what `expect_failures` asks of them.
    pub(super) may_fail: bool,
    /// Where the extreme makes the scene's own tolerance unreachable: the
    /// bound the case holds instead, m. The run's report must then say
    /// `EXCEEDED`, never `kept`.
    pub(super) holds_instead_m: Option<f64>,
}

/// What a case's run showed.
#[derive(Debug)]
pub(super) struct Outcome {
    /// The first non-finite output, if any.
    pub(super) non_finite: Option<String>,
    /// Largest force the motors rendered over the device's peak (both in
    /// the device's frame and units).
    pub(super) force_over_peak: f64,
    /// Largest force the solver asked for (before the safety layer) over
    /// the device's peak, in the same units.
    pub(super) commanded_over_peak: f64,
    /// Largest | |e|² − 1 | of any body at any tick (a transient: the
    /// rational rotation R(e) = A_h/|e|² is exact for any e).
    pub(super) norm_max: f64,
    /// Largest | |e|² − 1 | after the settle window.
    pub(super) norm_drift: f64,
    /// Largest | |e|² − 1 | after the last tick.
    pub(super) norm_end: f64,
    /// Largest violation of a successful tick after the settle window, m.
    pub(super) violation_after_m: f64,
    /// Largest violation of any successful tick, m.
    pub(super) violation_max_m: f64,
    /// Failed ticks after the settle window.
    pub(super) failed_after: u64,
    /// The session's failure counts by kind.
    pub(super) failure_kinds: Vec<(&'static str, u64)>,
    /// Failed ticks in all.
    pub(super) failed: u64,
    /// The summary's verdict.
    pub(super) verdict: String,
    pub(super) tolerance_m: Option<f64>,
}

fn drive(case: &Case) -> Outcome {
    drive_with(case, &mut |_, _| {})
}

/// Runs `case` tick by tick, calling `on_tick(k, program)` after each.
pub(super) fn drive_with(
    case: &Case,
    on_tick: &mut dyn FnMut(u64, &haptloop_solver::Program),
) -> Outcome {
    let plan = Plan::new(&case.scene, &case.options).unwrap();
    let scene = &case.scene;
    let mut b = session::build(scene, &plan, MockClock::new(Nanos(0)))
        .unwrap_or_else(|e| panic!("{}: {e:#}", case.name));
    let period = plan.period().as_nanos() as u64;
    let slow_every = ((0.005 * f64::from(plan.rate_hz)).round() as u64).max(1);
    let settle_from =
        ((case.disturbance_end_s + case.settle_s) * f64::from(plan.rate_hz)).round() as u64;
    let model = scene.compiled.model.clone();
    let mut o = Outcome {
        non_finite: None,
        force_over_peak: 0.0,
        commanded_over_peak: 0.0,
        norm_max: 0.0,
        norm_drift: 0.0,
        norm_end: 0.0,
        violation_after_m: 0.0,
        violation_max_m: 0.0,
        failed_after: 0,
        failure_kinds: Vec::new(),
        failed: 0,
        verdict: String::new(),
        tolerance_m: plan.violation_tolerance_m,
    };
    for k in 0..plan.ticks() {
        let failed_before = b.fast.stats().solver_failures;
        let t = Nanos((k + 1) * period);
        // As the scheduler does: a faulted tick calls the safety hook (a
        // force cut), so the run is the very one `session::run` makes.
        if let TickStatus::Fault(f) = b.fast.tick(&Tick {
            index: k,
            deadline: t,
            start: t,
        }) {
            b.fast.on_safety(SafetyEvent::Fault(f));
        }
        if k % slow_every == slow_every - 1 {
            b.slow.step();
        }
        while b.trace.pop().is_some() {}
        let p = b.fast.program();
        let r = p.last_report();
        let figures = [
            r.max_violation_m,
            r.max_violation_rad,
            r.max_norm_violation,
            r.rms_violation_m,
            r.max_tracking_error_m,
        ];
        let outputs_finite = p.finger_outputs().iter().all(|f| f.is_finite());
        if o.non_finite.is_none()
            && !(p.q().iter().all(|x| x.is_finite())
                && p.lambda().iter().all(|x| x.is_finite())
                && outputs_finite
                && figures.iter().all(|x| x.is_finite()))
        {
            o.non_finite = Some(format!("tick {k}: {r:?}"));
        }
        let mut norm: f64 = 0.0;
        for (_, off) in model.layout().moving_bodies() {
            let e2: f64 = p.q()[off + 3..off + 7].iter().map(|x| x * x).sum();
            norm = norm.max((e2 - 1.0).abs());
        }
        o.norm_max = o.norm_max.max(norm);
        o.norm_end = norm;
        // A tick the session counted as failed (solve failed, or the
        // mechanism came apart) has no violation to measure.
        let failed_now = b.fast.stats().solver_failures > failed_before;
        if !failed_now && r.status == TickOutcome::Ok {
            o.violation_max_m = o.violation_max_m.max(r.max_violation_m);
        }
        on_tick(k, p);
        if k >= settle_from {
            o.norm_drift = o.norm_drift.max(norm);
            if failed_now {
                o.failed_after += 1;
            } else if r.status == TickOutcome::Ok {
                o.violation_after_m = o.violation_after_m.max(r.max_violation_m);
            }
        }
    }
    b.fast.on_stop();
    let stats = b.fast.stats();
    for (i, f) in stats.fingers.iter().enumerate() {
        let d = &scene.compiled.devices[scene.compiled.fingers[i].device];
        let peak = PhantomModel::by_name(&d.model).unwrap().peak_force_n;
        // The session's figures are scene forces, F/s for a workspace
        // scale s: the motors produced s times them.
        o.force_over_peak = o.force_over_peak.max(f.force_max * d.scale / peak);
        o.commanded_over_peak = o.commanded_over_peak.max(f.commanded_max * d.scale / peak);
        assert!(f.force_max.is_finite(), "{}: rendered force", case.name);
    }
    o.failed = stats.solver_failures;
    o.failure_kinds = session::FailureKind::ALL
        .iter()
        .zip(&stats.failure_kinds)
        .filter(|(_, n)| **n > 0)
        .map(|(k, n)| (k.as_str(), *n))
        .collect();
    // Where ticks failed or the tolerance was exceeded, the report of the
    // same run must say so and never "kept".
    let exceeded = o.tolerance_m.is_some_and(|t| o.violation_max_m > t);
    if o.failed > 0 || exceeded {
        let run = session::run(scene, plan, &StopFlag::new(), &mut |_| {}).unwrap();
        let summary = Summary::of(&run);
        o.verdict = summary.violation.verdict.clone();
        assert_eq!(summary.safety.solver_failures, o.failed, "{}", case.name);
    }
    o
}

/// Asserts a case recovered: finite, within the peak force, norms that do
/// not drift, within tolerance with no failed tick from `settle_s` after
/// the disturbance on; and no failed tick at all unless the case
/// expects some, in which case they are counted by kind and the report
/// says so instead of "kept".
pub(super) fn assert_recovers(case: &Case) -> Outcome {
    check_recovered(case, drive(case))
}

pub(super) fn check_recovered(case: &Case, o: Outcome) -> Outcome {
    let n = &case.name;
    assert_eq!(o.non_finite, None, "{n}");
    // The safety layer clamps the command to the peak; the motors' output
    // is computed at the arm's true pose from torques mapped with the
    // encoder-sensed Jacobian, which may exceed it by that Jacobian's error.
    assert!(o.force_over_peak <= 1.0 + 1e-3, "{n}: {o:?}");
    // |e|² is held by the norm rows like any joint row: a transient during
    // a fast motion (the rotation R(e) = A_h/|e|² is exact for any e), then
    // back, never a drift.
    assert!(
        o.norm_drift <= 1e-4 && o.norm_end <= 1e-5,
        "{n}: quaternion norms drift {o:?}"
    );
    assert_eq!(o.failed_after, 0, "{n}: {o:?}");
    if let Some(bound) = case.holds_instead_m {
        let tol = o.tolerance_m.expect("a scene with joints");
        assert!(
            o.violation_after_m <= bound && o.violation_after_m > tol,
            "{n}: violation {:e} against the bound {bound:e} it states: {o:?}",
            o.violation_after_m
        );
        assert!(
            o.verdict.contains("EXCEEDED") && !o.verdict.contains("kept"),
            "{n}: {}",
            o.verdict
        );
    } else if let Some(tol) = o.tolerance_m {
        assert!(
            o.violation_after_m <= tol,
            "{n}: violation {:e} > {tol:e} {} s after the disturbance: {o:?}",
            o.violation_after_m,
            case.settle_s
        );
    }
    if case.expect_failures || (case.may_fail && o.failed > 0) {
        assert!(o.failed > 0 && !o.failure_kinds.is_empty(), "{n}: {o:?}");
        assert!(
            o.verdict.starts_with("FAILED TICKS") && !o.verdict.contains("kept"),
            "{n}: {}",
            o.verdict
        );
    } else if !case.may_fail {
        assert_eq!(o.failed, 0, "{n}: {o:?}");
    }
    o
}

/// The mechanisms of the matrix and how long each runs its own hand path.
pub(super) const MECHANISMS: [(&str, f64); 4] = [
    ("four-bar", 2.0),
    ("stewart", 2.0),
    ("peaucellier", 2.0),
    ("sphere-toy", 1.0),
];

pub(super) fn options(seconds: f64) -> SessionOptions {
    SessionOptions {
        seconds,
        deterministic: true,
        ..SessionOptions::default()
    }
}

pub(super) fn case(name: String, scene: Scene, options: SessionOptions) -> Case {
    Case {
        name,
        scene,
        options,
        disturbance_end_s: 0.0,
        settle_s: 0.0,
        expect_failures: false,
        may_fail: false,
        holds_instead_m: None,
    }
}
