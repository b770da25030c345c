//! Numerical stability at the extremes: a matrix over the built-in
//! mechanisms (masses 1e-4 and 1e3 kg, geometry × 1e-3 and × 10, gains
//! × 1e-3 and × 1e3, 100 Hz and 20 kHz, a hand at 5 m/s, a 1 m step of the
//! hand), singular poses, two fingers pulling a body apart, and a long
//! deterministic run. Every case runs a whole session (devices, safety
//! layer, slow loop) on the mock clock and asserts, tick by tick:
//!
//! - no NaN or infinity anywhere in the outputs (q, multipliers, every
//!   finger output, every tick report figure);
//! - the force the motors rendered within each device's peak force;
//! - every quaternion's |e|² within 1e-9 of 1 at every tick (no drift);
//! - the violation back within the scene's tolerance (scaled with the
//!   geometry) within the case's stated number of ticks after its
//!   disturbance ends, and no failed tick from then on; a case that cannot
//!   recover must fail as counted, named failures (`failure_kinds`), and
//!   its report must not say "kept".
//!
//! No timing: every figure is deterministic. The matrix's sweeps (masses,
//! geometry, gains, rates, the fast hand and the 1 m step) and the million
//! ticks take minutes each unoptimised (the whole file about 14 minutes), so
//! a debug build skips them: `cargo test --release` runs them all.

use haptloop::report::summary::Summary;
use haptloop::scenes::{BUILTIN, Scene, check_loaded};
use haptloop::session::{self, Plan, SessionOptions};
use haptloop_devices::PhantomModel;
use haptloop_rt::clock::{MockClock, Nanos};
use haptloop_rt::schedule::{SafetyEvent, StopFlag, Tick, TickBody, TickStatus};
use haptloop_solver::TickOutcome;
use nalgebra::{Matrix6, Vector3};
use std::path::Path;
use toml::{Table, Value};

/// A built-in scene with its TOML edited by `f`.
fn edited(name: &str, f: impl FnOnce(&mut Table)) -> Scene {
    let text = BUILTIN.iter().find(|b| b.name == name).unwrap().text;
    let mut t: Table = text.parse().unwrap();
    f(&mut t);
    let text = toml::to_string(&t).unwrap();
    let loaded = haptloop_solver::scene::parse(
        &format!("stability/{name}.toml"),
        &text,
        Some(Path::new("scenes")),
    )
    .unwrap();
    check_loaded(loaded).unwrap_or_else(|e| panic!("{name}: {e}"))
}

fn tables<'a>(t: &'a mut Table, key: &str) -> impl Iterator<Item = &'a mut Table> {
    t.get_mut(key)
        .and_then(Value::as_array_mut)
        .into_iter()
        .flatten()
        .filter_map(Value::as_table_mut)
}

fn scale_numbers(v: &mut Value, s: f64) {
    match v {
        Value::Float(x) => *x *= s,
        Value::Integer(i) => *v = Value::Float(*i as f64 * s),
        Value::Array(a) => a.iter_mut().for_each(|x| scale_numbers(x, s)),
        _ => {}
    }
}

/// Every moving body weighs `kg` (its inertia scaled with it).
fn set_masses(t: &mut Table, kg: f64) {
    for b in tables(t, "body") {
        let Some(m) = b.get("mass").and_then(Value::as_float) else {
            continue;
        };
        if let Some(i) = b.get_mut("inertia") {
            scale_numbers(i, kg / m);
        }
        b.insert("mass".into(), Value::Float(kg));
    }
}

/// Every length × `s`: positions, anchors, lengths, prismatic limits,
/// finger points, the hand's path, shapes; inertias × s²; the scene's
/// violation tolerance × s (a relative accuracy).
fn scale_geometry(t: &mut Table, s: f64) {
    for b in tables(t, "body") {
        for k in ["position", "shape"] {
            if let Some(v) = b.get_mut(k) {
                scale_numbers(v, s);
            }
        }
        if let Some(i) = b.get_mut("inertia") {
            scale_numbers(i, s * s);
        }
    }
    for j in tables(t, "joint") {
        let prismatic = j.get("kind").and_then(Value::as_str) == Some("prismatic");
        for k in ["anchors", "length"] {
            if let Some(v) = j.get_mut(k) {
                scale_numbers(v, s);
            }
        }
        if prismatic && let Some(v) = j.get_mut("limits") {
            scale_numbers(v, s);
        }
    }
    for f in tables(t, "finger") {
        if let Some(v) = f.get_mut("point") {
            scale_numbers(v, s);
        }
    }
    for d in tables(t, "device") {
        // The device's workspace scales too: the hand moves the arm as
        // before, and an encoder count is `s` times as long in the scene.
        let scale = d.get("scale").and_then(Value::as_float).unwrap_or(1.0);
        d.insert("scale".into(), Value::Float(scale * s));
        let Some(h) = d.get_mut("hand").and_then(Value::as_table_mut) else {
            continue;
        };
        if let Some(c) = h.get_mut("circle").and_then(Value::as_table_mut)
            && let Some(r) = c.get_mut("radius")
        {
            scale_numbers(r, s);
        }
        if let Some(l) = h.get_mut("line").and_then(Value::as_table_mut)
            && let Some(to) = l.get_mut("to")
        {
            scale_numbers(to, s);
        }
    }
    if let Some(tol) = t
        .get_mut("solver")
        .and_then(Value::as_table_mut)
        .and_then(|s| s.get_mut("violation_tolerance"))
    {
        scale_numbers(tol, s);
    }
}

/// Device `k`'s hand follows `points` (`[t, dx, dy, dz]`, scene frame).
fn set_waypoints(t: &mut Table, k: usize, points: &[[f64; 4]]) {
    let d = tables(t, "device").nth(k).unwrap();
    let mut hand = Table::new();
    hand.insert(
        "waypoints".into(),
        Value::Array(
            points
                .iter()
                .map(|p| Value::Array(p.iter().map(|&x| Value::Float(x)).collect()))
                .collect(),
        ),
    );
    d.insert("hand".into(), Value::Table(hand));
}

/// A hand path out by `offset` over `ramp_s` at `t0`, held `hold_s`, and
/// back over `ramp_s`: (waypoints, time the disturbance ends).
fn out_and_back(t0: f64, offset: [f64; 3], ramp_s: f64, hold_s: f64) -> (Vec<[f64; 4]>, f64) {
    let [x, y, z] = offset;
    let back = t0 + 2.0 * ramp_s + hold_s;
    (
        vec![
            [0.0, 0.0, 0.0, 0.0],
            [t0, 0.0, 0.0, 0.0],
            [t0 + ramp_s, x, y, z],
            [t0 + ramp_s + hold_s, x, y, z],
            [back, 0.0, 0.0, 0.0],
        ],
        back,
    )
}

fn builtin(name: &str) -> Scene {
    edited(name, |_| {})
}

/// One case of the matrix.
struct Case {
    name: String,
    scene: Scene,
    options: SessionOptions,
    /// Session time at which the disturbance is over, s (0: the extreme
    /// holds for the whole run and every tick must be within tolerance).
    disturbance_end_s: f64,
    /// Time allowed after it to be back within tolerance, s.
    settle_s: f64,
    /// The disturbance is expected to make ticks fail (counted by kind,
    /// reported, force cut, the slow loop recovering the configuration);
    /// none may fail once it is over and the settle window has passed.
    expect_failures: bool,
    /// The disturbance may make ticks fail, or may not (a chaotic passage
    /// through a singular pose, where the last bits decide it). Any that
    /// fail are held to what `expect_failures` asks of them.
    may_fail: bool,
    /// Where the extreme makes the scene's own tolerance unreachable: the
    /// bound the case holds instead, m. The run's report must then say
    /// `EXCEEDED`, never `kept`.
    holds_instead_m: Option<f64>,
}

/// What a case's run showed.
#[derive(Debug)]
struct Outcome {
    /// The first non-finite output, if any.
    non_finite: Option<String>,
    /// Largest force the motors rendered over the device's peak (both in
    /// the device's frame and units).
    force_over_peak: f64,
    /// Largest force the solver asked for (before the safety layer) over
    /// the device's peak, in the same units.
    commanded_over_peak: f64,
    /// Largest | |e|² − 1 | of any body at any tick (a transient: the
    /// rational rotation R(e) = A_h/|e|² is exact for any e).
    norm_max: f64,
    /// Largest | |e|² − 1 | after the settle window.
    norm_drift: f64,
    /// Largest | |e|² − 1 | after the last tick.
    norm_end: f64,
    /// Largest violation of a successful tick after the settle window, m.
    violation_after_m: f64,
    /// Largest violation of any successful tick, m.
    violation_max_m: f64,
    /// Failed ticks after the settle window.
    failed_after: u64,
    /// The session's failure counts by kind.
    failure_kinds: Vec<(&'static str, u64)>,
    /// Failed ticks in all.
    failed: u64,
    /// The summary's verdict.
    verdict: String,
    tolerance_m: Option<f64>,
}

fn drive(case: &Case) -> Outcome {
    drive_with(case, &mut |_, _| {})
}

/// Runs `case` tick by tick, calling `on_tick(k, program)` after each.
fn drive_with(case: &Case, on_tick: &mut dyn FnMut(u64, &haptloop_solver::Program)) -> Outcome {
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
fn assert_recovers(case: &Case) -> Outcome {
    check_recovered(case, drive(case))
}

fn check_recovered(case: &Case, o: Outcome) -> Outcome {
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
const MECHANISMS: [(&str, f64); 4] = [
    ("four-bar", 2.0),
    ("stewart", 2.0),
    ("peaucellier", 2.0),
    ("sphere-toy", 1.0),
];

fn options(seconds: f64) -> SessionOptions {
    SessionOptions {
        seconds,
        deterministic: true,
        ..SessionOptions::default()
    }
}

fn case(name: String, scene: Scene, options: SessionOptions) -> Case {
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

/// The smallest over the largest singular value of C_q at `q` over the
/// joint rows that hold there: every equality (quaternion norms included)
/// and every limit at its bound (within 1 µm): 0 at a singular pose of
/// the mechanism as it is held.
fn joint_conditioning(scene: &Scene, q: &[f64]) -> f64 {
    use haptloop_solver::Sense;
    let model = &scene.compiled.joints_only;
    let mut ev = haptloop_solver::Evaluation::new(model);
    ev.evaluate(model, q, &[]).unwrap();
    let j = ev.jacobian().to_dense();
    let held: Vec<usize> = model
        .rows()
        .iter()
        .enumerate()
        .filter(|(i, r)| match r.sense {
            Sense::Equality => true,
            Sense::Inequality => ev.values()[*i] <= 1e-6,
            Sense::Friction => false,
        })
        .map(|(i, _)| i)
        .collect();
    let sv = j.select_rows(held.iter()).singular_values();
    sv.min() / sv.max()
}

/// The four-bar's transmission at `q`: how fast the crank and the rocker
/// move (their centres) against the coupler's centre along the linkage's
/// one freedom (the null vector of the joint rows' C_q). At a toggle one of
/// the two stands still while the coupler moves: this goes to 0.
fn four_bar_transmission(scene: &Scene, q: &[f64]) -> f64 {
    let model = &scene.compiled.joints_only;
    let mut ev = haptloop_solver::Evaluation::new(model);
    ev.evaluate(model, q, &[]).unwrap();
    let j = ev.jacobian().to_dense();
    let e = (j.transpose() * &j).symmetric_eigen();
    let k = e.eigenvalues.imin();
    let n = e.eigenvectors.column(k);
    let speed = |name: &str| {
        let (_, off) = model
            .layout()
            .moving_bodies()
            .find(|(id, _)| model.bodies()[id.index()].name == name)
            .unwrap();
        (n[off].powi(2) + n[off + 1].powi(2) + n[off + 2].powi(2)).sqrt()
    };
    speed("crank").min(speed("rocker")) / speed("coupler")
}

/// The four-bar driven into its toggle: the hand pulls the coupler 0.2 m
/// out along each direction of its circle's plane in turn (far beyond the
/// linkage's reach), so the linkage runs to the ends of its range, where it
/// locks (this spatial linkage is not Grashof: its range ends at toggle
/// poses, where the joint rows lose rank). The conditioning of the joint
/// rows' C_q falls by the factor asserted below, and the loop is back
/// within 1 µm 0.5 s after the hand returns.
#[test]
fn the_four_bar_toggle() {
    let u = [0.045194, -0.997943, -0.045474];
    let v = [0.556809, 0.062958, -0.828251];
    let at = |d: [f64; 3], s: f64| [d[0] * s, d[1] * s, d[2] * s];
    let mut path = vec![[0.0, 0.0, 0.0, 0.0]];
    let mut t = 0.2;
    for d in [at(u, 0.2), at(u, -0.2), at(v, 0.2), at(v, -0.2)] {
        path.push([t, 0.0, 0.0, 0.0]);
        path.push([t + 0.3, d[0], d[1], d[2]]);
        path.push([t + 0.6, d[0], d[1], d[2]]);
        path.push([t + 0.9, 0.0, 0.0, 0.0]);
        t += 1.0;
    }
    let end = t - 0.1;
    let scene = edited("four-bar", |s| set_waypoints(s, 0, &path));
    let mut c = case("four-bar toggle".into(), scene, options(end + 1.0));
    c.disturbance_end_s = end;
    c.settle_s = 0.5;
    c.expect_failures = true;
    let (mut first, mut least) = (f64::NAN, f64::INFINITY);
    let o = drive_with(&c, &mut |k, p| {
        // Only configurations a tick held (a failed tick's q is not one).
        let r = p.last_report();
        if k % 10 == 0 && r.status == TickOutcome::Ok && r.max_violation_m <= 1e-4 {
            let r = four_bar_transmission(&c.scene, p.q());
            if k == 0 {
                first = r;
            }
            least = least.min(r);
        }
    });
    let o = check_recovered(&c, o);
    eprintln!("four-bar toggle: transmission {least:e} (start {first:e}); {o:?}");
    assert!(
        least < 0.05 * first,
        "the toggle was not reached: transmission {least:e} against {first:e} at the start"
    );
    // The fast loop cannot hold the linkage while the hand yanks it into
    // the toggle: those ticks fail as counted, named failures (force cut,
    // the slow loop re-places it), none after the settle window.
    let kinds: Vec<&str> = o.failure_kinds.iter().map(|(k, _)| *k).collect();
    assert!(
        kinds
            .iter()
            .all(|k| ["diverged_violation", "violation_beyond_broken"].contains(k)),
        "{o:?}"
    );
    assert_eq!(
        o.failure_kinds.iter().map(|(_, n)| n).sum::<u64>(),
        o.failed
    );
}

/// The Stewart platform's legs as lines, from the scene file's own numbers
/// (not the solver's): the base attachment points (joints `base{i}`, on
/// the fixed base at the origin) and the platform's (joints `top{i}`, in
/// the platform's frame), placed by the platform's pose in q.
struct StewartLegs {
    base: [Vector3<f64>; 6],
    top: [Vector3<f64>; 6],
    /// The platform's offset in q.
    platform: usize,
    /// Moments are divided by this (the platform's radius), m, so that the
    /// wrench matrix holds numbers of one kind.
    radius_m: f64,
}

impl StewartLegs {
    fn of(scene: &Scene) -> Self {
        let text = BUILTIN.iter().find(|b| b.name == "stewart").unwrap().text;
        let mut t: Table = text.parse().unwrap();
        let base = tables(&mut t, "body").next().unwrap();
        // The base is fixed at the origin, unrotated: its anchors are
        // scene coordinates.
        assert_eq!(base.get("fixed").and_then(Value::as_bool), Some(true));
        let numbers = |k: &str| -> Vec<f64> {
            base[k]
                .as_array()
                .unwrap()
                .iter()
                .map(|x| x.as_float().unwrap())
                .collect()
        };
        assert_eq!(numbers("position"), [0.0; 3]);
        assert_eq!(numbers("orientation"), [1.0, 0.0, 0.0, 0.0]);
        let mut anchor = |joint: String, k: usize| {
            let j = tables(&mut t, "joint")
                .find(|j| j.get("name").and_then(Value::as_str) == Some(&joint))
                .unwrap();
            let a = j["anchors"].as_array().unwrap()[k].as_array().unwrap();
            Vector3::from_iterator(a.iter().map(|x| x.as_float().unwrap()))
        };
        let base = std::array::from_fn(|i| anchor(format!("base{i}"), 0));
        let top: [Vector3<f64>; 6] = std::array::from_fn(|i| anchor(format!("top{i}"), 1));
        let model = &scene.compiled.model;
        let (_, platform) = model
            .layout()
            .moving_bodies()
            .find(|(id, _)| model.bodies()[id.index()].name == "platform")
            .unwrap();
        let radius_m = top.iter().map(|a| a.norm()).sum::<f64>() / 6.0;
        StewartLegs {
            base,
            top,
            platform,
            radius_m,
        }
    }

    /// Leg i at `q`: (base point, platform point relative to the
    /// platform's centre, platform point), m.
    fn leg(&self, q: &[f64], i: usize) -> (Vector3<f64>, Vector3<f64>, Vector3<f64>) {
        let o = self.platform;
        let x = Vector3::new(q[o], q[o + 1], q[o + 2]);
        let r = haptloop_solver::rotation::rotation_wxyz([q[o + 3], q[o + 4], q[o + 5], q[o + 6]])
            .unwrap();
        let arm = r * self.top[i];
        (self.base[i], arm, x + arm)
    }

    /// Leg i's length (base attachment to platform attachment) at `q`, m.
    fn length(&self, q: &[f64], i: usize) -> f64 {
        let (b, _, p) = self.leg(q, i);
        (p - b).norm()
    }

    /// σ_min/σ_max of the platform's wrench Jacobian at `q`: row i the
    /// Plücker coordinates of leg i's line, its unit direction u_i and its
    /// moment about the platform's centre (r_i × u_i)/radius. A leg,
    /// spherical at the platform, can only push or pull along its line, so
    /// this is 0 exactly where some wrench on the platform is one no leg
    /// force can balance: a Gough–Stewart singular pose.
    fn conditioning(&self, q: &[f64]) -> f64 {
        let mut w = Matrix6::zeros();
        for i in 0..6 {
            let (b, arm, p) = self.leg(q, i);
            let u = (p - b).normalize();
            let m = arm.cross(&u) / self.radius_m;
            w.fixed_view_mut::<1, 3>(i, 0).copy_from(&u.transpose());
            w.fixed_view_mut::<1, 3>(i, 3).copy_from(&m.transpose());
        }
        let sv = w.singular_values();
        sv.min() / sv.max()
    }
}

/// What a run through the Stewart platform's singular pose showed.
#[derive(Debug)]
struct SingularRun {
    /// σ_min/σ_max of the legs' wrench matrix at the first tick, at the
    /// tick closest to singular, and that tick and the platform's height
    /// there (m; the base attachment points are at 0).
    wrench_first: f64,
    wrench_least: f64,
    least_tick: u64,
    least_z_m: f64,
    /// σ_min/σ_max of the rows the solver held (equalities, limits at their
    /// bounds): at the first tick and the least over the run.
    rows_first: f64,
    rows_least: f64,
    /// The last tick whose violation exceeded the scene's tolerance or
    /// that failed (None: none did).
    last_bad_tick: Option<u64>,
}

/// The hand's path through the Stewart platform's singular pose: the
/// platform down 12 cm into the plane of the base attachment points over
/// 1 s, held there 0.3 s, 1 cm further (below it) and back, held 0.3 s, and
/// up again over 1 s; the hand leaves the singular pose at 2 s. The arm's
/// workspace box reaches 9.55 cm below its home pose, so every device
/// metre is two scene metres (the hand moves 6.5 cm). Each slider's stroke
/// limits become `[lower[i], 0.04]`.
fn stewart_through_its_base_plane(t: &mut Table, lower: [f64; 6]) {
    for j in tables(t, "joint") {
        let Some(i) = j
            .get("name")
            .and_then(Value::as_str)
            .and_then(|n| n.strip_prefix("slider"))
        else {
            continue;
        };
        let i: usize = i.parse().unwrap();
        j.insert(
            "limits".into(),
            Value::Array(vec![Value::Float(lower[i]), Value::Float(0.04)]),
        );
    }
    tables(t, "device")
        .next()
        .unwrap()
        .insert("scale".into(), Value::Float(2.0));
    set_waypoints(
        t,
        0,
        &[
            [0.0, 0.0, 0.0, 0.0],
            [0.2, 0.0, 0.0, 0.0],
            [1.2, 0.0, 0.0, -0.12],
            [1.5, 0.0, 0.0, -0.12],
            [1.6, 0.0, 0.0, -0.13],
            [1.7, 0.0, 0.0, -0.12],
            [2.0, 0.0, 0.0, -0.12],
            [3.0, 0.0, 0.0, 0.0],
        ],
    );
}

/// Runs the Stewart platform through its base plane with the sliders'
/// lower stroke limits at `lower`, measuring the singularity as it goes,
/// and asserts what every case of the matrix asserts (`check_recovered`),
/// back within tolerance `settle_s` after the hand leaves the singular
/// pose (at 2 s, tick 2000), and that it went through a singular pose.
fn drive_stewart_singular(
    name: &str,
    lower: [f64; 6],
    settle_s: f64,
    may_fail: bool,
) -> (Outcome, SingularRun) {
    let scene = edited("stewart", |t| stewart_through_its_base_plane(t, lower));
    let legs = StewartLegs::of(&scene);
    let mut c = case(name.into(), scene, options(4.0));
    c.disturbance_end_s = 2.0;
    c.settle_s = settle_s;
    c.may_fail = may_fail;
    let tol = c.scene.compiled.settings.violation_tolerance.unwrap();
    let mut s = SingularRun {
        wrench_first: f64::NAN,
        wrench_least: f64::INFINITY,
        least_tick: 0,
        least_z_m: f64::NAN,
        rows_first: f64::NAN,
        rows_least: f64::INFINITY,
        last_bad_tick: None,
    };
    let o = drive_with(&c, &mut |k, p| {
        let w = legs.conditioning(p.q());
        if k == 0 {
            s.wrench_first = w;
        }
        if w < s.wrench_least {
            (s.wrench_least, s.least_tick) = (w, k);
            s.least_z_m = p.q()[legs.platform + 2];
        }
        // (A failed tick is one of these too; `check_recovered` counts
        // them after the settle window.)
        let r = p.last_report();
        if r.status != TickOutcome::Ok || r.max_violation_m > tol {
            s.last_bad_tick = Some(k);
        }
        // Only configurations a tick held; every tick near the pose.
        if (k % 10 == 0 || w < 1e-2) && r.status == TickOutcome::Ok && r.max_violation_m <= 1e-4 {
            let j = joint_conditioning(&c.scene, p.q());
            if k == 0 {
                s.rows_first = j;
            }
            s.rows_least = s.rows_least.min(j);
        }
    });
    eprintln!("{name}: {s:?}; {o:?}");
    let o = check_recovered(&c, o);
    assert_eq!(
        o.failure_kinds.iter().map(|(_, n)| n).sum::<u64>(),
        o.failed,
        "{name}: {o:?}"
    );
    // Over the tolerance at any tick: the report says so, never "kept".
    if o.violation_max_m > tol {
        assert!(
            o.verdict.contains("EXCEEDED") && !o.verdict.contains("kept"),
            "{name}: {}",
            o.verdict
        );
    }
    // Measured independently of the solver: the run went through a
    // singular pose, from a well-conditioned start.
    assert!(s.wrench_first > 0.1, "{name}: {s:?}");
    assert!(
        s.wrench_least < 1e-3 && s.least_z_m.abs() < 1e-4,
        "{name}: the singular pose was not reached: {s:?}"
    );
    (o, s)
}

/// The Stewart platform lowered into the plane of its base attachment
/// points, through it and back (`stewart_through_its_base_plane`). There
/// all six leg lines lie in one plane, so their Plücker coordinates span
/// rank 3 and no leg force can hold a vertical force or a tilt: the classic
/// Gough–Stewart singularity. The legs must shorten from 13.3 cm to 5.7 cm
/// for it, beyond the scene's −4 cm stroke, so the lower stroke limits are
/// widened to −10 cm. The legs are unactuated: the rows the solver holds
/// (each leg a U-P-S chain with six freedoms of its own) keep their rank,
/// conditioning 3.3e-2 at the start and 1.4e-2 at the least, and the
/// singularity is the one the legs have as struts: measured from q and the
/// scene file's anchors (`StewartLegs`), independently of the solver, the
/// legs' wrench matrix falls from σ_min/σ_max 0.286 at the start to 1.8e-4
/// at the closest tick (tick 1197, the platform 14 µm below the plane).
/// The loop holds the mechanism within its 0.1 mm tolerance at every tick
/// (6.9e-7 m at most), no tick fails, the motors' force reaches 0.513 of
/// the arm's peak, and |e|² stays within 9e-6 of 1.
#[test]
fn the_stewart_singular_pose() {
    let (o, s) = drive_stewart_singular("stewart singular pose", [-0.10; 6], 0.5, false);
    assert_eq!(o.failed, 0, "{o:?}");
    assert!(o.violation_max_m <= 1e-4, "{o:?}");
    assert_eq!(s.last_bad_tick, None, "{s:?}");
}

/// The stroke limits of `the_stewart_singular_pose` with each leg's lower
/// limit `by` off its length in the base plane: `by` = 0, the six legs
/// reach their stops together at the singular pose and act there as
/// locked struts, so the rows the solver holds lose rank as well.
fn stewart_legs_bottoming_out(by: f64) -> [f64; 6] {
    let stewart = builtin("stewart");
    let legs = StewartLegs::of(&stewart);
    let q0 = stewart.compiled.model.q0();
    let mut flat = q0.to_vec();
    flat[legs.platform + 2] = 0.0;
    std::array::from_fn(|i| legs.length(&flat, i) - legs.length(q0, i) + by)
}

/// The same, with the legs bottoming out in the base plane: there the six
/// limits become active together at a pose where the legs' lines are
/// coplanar, and the held rows lose rank (conditioning 3.3e-2 → 2.6e-9).
/// The passage is chaotic: the solver asks for up to 17× the arm's peak
/// force (the safety layer clamps it), and whether ticks fail or the
/// violation merely exceeds the tolerance depends on the limits' last bits.
/// With the limits exactly at the in-plane lengths two ticks fail
/// (`force_solve`, counted, the report says FAILED TICKS, not "kept"), the
/// violation reaches 0.107 mm, and the last tick over the tolerance is
/// tick 1759, before the hand leaves the pose at 2 s.
#[test]
fn the_stewart_legs_bottoming_out_in_the_singular_pose() {
    let (o, s) = drive_stewart_singular(
        "stewart legs bottoming out",
        stewart_legs_bottoming_out(0.0),
        1.0,
        true,
    );
    assert!(
        s.rows_least < 1e-6,
        "the held rows did not lose rank: {s:?}"
    );
    assert!(o.violation_max_m <= 5e-3, "{o:?}");
    assert!(s.last_bad_tick.is_none_or(|k| k < 3000), "{s:?}");
}

/// Each lower limit 1 nm below the in-plane length: beside the singular
/// pose (1.8 s) the fast loop falls into a period-5 cycle — each Gauss–Newton
/// step halves the platform's height (4.8 → 2.4 → 1.2 → 0.6 mm, Newton at a
/// singular root) and the active limits throw it back — with violations
/// 3.6e-4, 7.6e-5, 1.9e-5, 4.7e-6, 6.6e-5 m and no failed tick. The slow loop
/// looks every 5 ticks, the cycle's own period; it used to land on the
/// 6.6e-5 m tick each time, under its 1e-4 m threshold, and never
/// re-projected, so the platform stayed jammed to the end of the run. Now
/// each snapshot carries the largest violation since the slow loop's last
/// look (`Snapshot::peak_violation_m`), the re-projection fires, and the
/// platform is back within tolerance before the hand leaves the pose (tick
/// 2121 of 4000); the run's verdict is `EXCEEDED`, never `kept`.
#[test]
fn the_stewart_legs_bottoming_out_1_nm_short() {
    let (o, s) = drive_stewart_singular(
        "stewart legs bottoming out, 1 nm short",
        stewart_legs_bottoming_out(-1e-9),
        1.0,
        true,
    );
    assert!(s.wrench_least < 1e-4 * s.wrench_first, "{s:?}");
    assert!(o.violation_max_m > 1e-4, "the cycle was not reached: {o:?}");
    assert_eq!(o.verdict, "EXCEEDED", "{o:?}");
    assert!(
        s.last_bad_tick.is_some_and(|k| k < 2500),
        "still jammed after the hand left the pose: {s:?}"
    );
    assert!(o.violation_after_m <= 1e-6, "{o:?}");
}

/// KNOWN BUG (issue 11), reproduced: with the limits 10 nm short the same
/// period-5 cycle does not clear even with the slow loop re-projecting on
/// the largest violation since its last look (0.65 mm to the end of the
/// run), and 1 pm short every tick fails (`force_solve`, counted) from
/// 2.2 s on. The fast loop's step at a rank-deficient set of active limits
/// is what needs fixing.
#[test]
#[ignore = "known bug: a period-5 jam at the Stewart singular pose when six active limits lose rank"]
fn the_stewart_legs_bottoming_out_10_nm_short() {
    let (o, s) = drive_stewart_singular(
        "stewart legs bottoming out, 10 nm short",
        stewart_legs_bottoming_out(-1e-8),
        1.0,
        true,
    );
    assert!(
        s.last_bad_tick.is_some_and(|k| k < 2500) && o.violation_after_m <= 1e-6,
        "jammed: {s:?} {o:?}"
    );
}

/// The Peaucellier linkage's dead point (P = Q, the rhombus flat) at about
/// 2.58 s of its own hand path. A dead point is a bifurcation: two assembly
/// branches cross there, and which one the linkage leaves on is decided by
/// the last bits of the state (the summation order of a kernel, or 1e-12 m
/// at the start, changes it). It snaps into its other branch there, or
/// passes on its own and snaps where the hand brings Q back at about
/// 3.42 s, or keeps its branch through both crossings (violation under
/// 1e-7 m the whole run). Whichever, for any round-off: the run reaches the
/// dead point (P and Q within 0.1 mm on the bodies' poses), each snap is a
/// transient of a tick or two (0.05–0.86 mm at the first crossing,
/// `haptloop sweep peaucellier`, BENCHMARKS.md; 5–33 µm at the second),
/// within the 1 mm the scene states; every excursion above 1 µm is over
/// within 0.1 s, the run ends under 1 µm, and the quaternions' |e|² are back
/// within 1e-4 from 3.5 s on.
/// Checked on the scene as shipped and on eight starts moved by
/// k · 1e-12 m: changes of round-off size that can flip the branch (with
/// another factor kernel's round-off, one of sixteen such starts passed
/// the first crossing and snapped at the second; with the norm rows out of
/// the force factor one of nine kept its branch throughout; BENCHMARKS.md,
/// issue 23).
#[test]
fn the_peaucellier_dead_point() {
    let (mut snapped_early, mut snapped_late) = (0, 0);
    for k in 0..9 {
        let scene = edited("peaucellier", |t| nudge_body(t, "crank", k as f64 * 1e-12));
        let mut c = case(
            format!("peaucellier dead point, start +{k} pm"),
            scene,
            options(3.6),
        );
        // The second crossing is at 3.42 s: the norms are checked from 3.5 s.
        c.disturbance_end_s = 3.4;
        c.settle_s = 0.1;
        let mut x = Excursions::default();
        let model = c.scene.compiled.model.clone();
        let mut flat = DeadPoint::default();
        let o = drive_with(&c, &mut |tick, p| {
            x.record(tick, p.last_report());
            flat.record(&model, p);
        });
        let o = check_recovered(&c, o);
        let n = &c.name;
        eprintln!(
            "{n}: violation max {:e} m, |e|² max off {:e}, excursions {:?}, longest {}, {flat:?}",
            o.violation_max_m, o.norm_max, x.starts, x.longest
        );
        assert!(o.violation_max_m <= 1e-3, "{n}: {o:?}");
        assert!(
            x.longest <= 100,
            "{n}: {} ticks above 1 µm: {x:?}",
            x.longest
        );
        assert!(x.last <= 1e-6, "{n}: ended {:e} m off: {x:?}", x.last);
        // The run went through the dead point, measured on the bodies' poses
        // (not on the solver's violation figure, which a run that keeps its
        // branch through both crossings leaves under 1e-7 m: round-off picks
        // that too, BENCHMARKS.md issue 23): P and Q, 10.4 mm apart at the
        // start, came within 0.1 mm (snapping runs reach 1e-14 m, one that
        // kept its branch 5.9e-6 m); and the poses are assembled: the crank's
        // P and the side's P apart by at most √3 × the run's worst violation
        // (a row's figure is one coordinate of the gap).
        assert!(
            flat.min_pq_m < 1e-4,
            "{n}: never reached the dead point: {flat:?}"
        );
        assert!(
            flat.max_p_gap_m <= 3f64.sqrt() * o.violation_max_m + 1e-12,
            "{n}: the poses disagree with the violation figure: {flat:?} {o:?}"
        );
        snapped_early += usize::from(x.starts.iter().any(|&s| s < 2700));
        snapped_late += usize::from(x.starts.iter().any(|&s| s >= 2700));
    }
    eprintln!(
        "peaucellier dead point: {snapped_early} of 9 starts snapped at the first crossing, {snapped_late} at the second"
    );
}

/// Moves the body `name`'s position by `dx` along x.
fn nudge_body(t: &mut Table, name: &str, dx: f64) {
    for b in tables(t, "body") {
        if b.get("name").and_then(Value::as_str) == Some(name) {
            let pos = b.get_mut("position").and_then(Value::as_array_mut).unwrap();
            let x = pos[0].as_float().unwrap();
            pos[0] = Value::Float(x + dx);
        }
    }
}

/// The Peaucellier linkage's dead point measured on the bodies' poses: the
/// least distance between P (the crank's end) and Q (`side-bq`'s end), and
/// the largest gap between the crank's P and `side-ap`'s P (a joint, read
/// off the poses).
#[derive(Debug)]
struct DeadPoint {
    min_pq_m: f64,
    max_p_gap_m: f64,
}

impl Default for DeadPoint {
    fn default() -> Self {
        Self {
            min_pq_m: f64::INFINITY,
            max_p_gap_m: 0.0,
        }
    }
}

impl DeadPoint {
    fn record(&mut self, model: &haptloop_solver::Model, p: &haptloop_solver::Program) {
        let at = |name: &str, z: f64| -> Vector3<f64> {
            let id = model.body_id(name).unwrap();
            let (_, off) = model.layout().moving_bodies().find(|b| b.0 == id).unwrap();
            let q = &p.q()[off..off + 7];
            let e = nalgebra::Quaternion::new(q[3], q[4], q[5], q[6]);
            let r = nalgebra::UnitQuaternion::from_quaternion(e);
            Vector3::new(q[0], q[1], q[2]) + r * Vector3::new(0.0, 0.0, z)
        };
        let p_crank = at("crank", 0.025);
        self.min_pq_m = self.min_pq_m.min((p_crank - at("side-bq", 0.02)).norm());
        self.max_p_gap_m = self.max_p_gap_m.max((p_crank - at("side-ap", 0.02)).norm());
    }
}

/// The runs of consecutive successful ticks whose violation exceeds 1 µm.
#[derive(Debug, Default)]
struct Excursions {
    /// The tick each run started at.
    starts: Vec<u64>,
    /// Length of the current run and of the longest, ticks.
    current: u64,
    longest: u64,
    /// The last successful tick's violation, m.
    last: f64,
}

impl Excursions {
    fn record(&mut self, tick: u64, r: &haptloop_solver::TickReport) {
        if r.status != TickOutcome::Ok {
            return;
        }
        self.last = r.max_violation_m;
        if r.max_violation_m > 1e-6 {
            if self.current == 0 {
                self.starts.push(tick);
            }
            self.current += 1;
            self.longest = self.longest.max(self.current);
        } else {
            self.current = 0;
        }
    }
}

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

/// The Stewart platform lifted into all six stroke limits at once (6 s of
/// its own path): more active rows than the platform has freedoms.
#[test]
fn the_stewart_platform_at_its_stroke_limits() {
    assert_recovers(&case(
        "stewart limits".into(),
        builtin("stewart"),
        options(6.0),
    ));
}
