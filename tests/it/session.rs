//! End-to-end sessions: built-in scenes on simulated arms, deterministic runs,
//! record and replay, the fast loop's zero-allocation rule, a clean early stop.

use crate::mock_session::MockSession;
use haptloop::report::summary::Summary;
use haptloop::scenes::{BUILTIN, Scene, resolve};
use haptloop::session::{self, Plan, SessionOptions, SessionOutcome};
use haptloop_devices::PhantomModel;
use haptloop_rt::alloc::count;
use haptloop_rt::clock::{MockClock, Nanos};
use haptloop_rt::schedule::{Periodic, RunLimit, StopFlag};
use haptloop_rt::thread::ThreadConfig;
use std::path::Path;

fn deterministic(seconds: f64) -> SessionOptions {
    SessionOptions {
        seconds,
        deterministic: true,
        ..SessionOptions::default()
    }
}

fn run(scene: &Scene, options: &SessionOptions) -> SessionOutcome {
    let plan = Plan::new(scene, options).unwrap();
    session::run(scene, plan, &StopFlag::new(), &mut |_| {}).unwrap()
}

/// How long each built-in scene runs in the tolerance test: long enough to
/// cover the part of its hand path where the hard thing happens (2 s
/// otherwise: every circle in the built-ins turns at least once).
fn seconds_covering_the_hard_part(name: &str) -> f64 {
    match name {
        // The hand drags Q through the dead point (P = Q) at 2.58 s.
        "peaucellier" => 3.5,
        // The lift reaches the stroke limits at about 3.6 s and pulls on
        // them until 4 s.
        "stewart" | "stewart-feet" => 5.0,
        _ => 2.0,
    }
}

/// Every built-in scene runs deterministically through its hard part, keeps
/// its violation under the tolerance it states (a scene of free bodies has
/// no joint rows and reports "none", with no figure), keeps its penetration
/// under its tolerance if it has contact, and renders finite forces within
/// its devices' peak force.
#[test]
fn every_builtin_scene_runs_within_its_stated_tolerance() {
    for b in BUILTIN {
        let scene = resolve(b.name).unwrap();
        let seconds = seconds_covering_the_hard_part(b.name);
        let o = run(&scene, &deterministic(seconds));
        let s = Summary::of(&o);
        if s.violation.rows == 0 {
            assert!(
                s.violation.tolerance.is_none(),
                "{}: states a violation tolerance but has no joint rows",
                b.name
            );
            assert!(s.violation.max.is_nan(), "{}: {}", b.name, s.violation.max);
            assert!(s.violation.verdict.starts_with("none"), "{}", b.name);
        } else {
            let tol = s
                .violation
                .tolerance
                .unwrap_or_else(|| panic!("{} states no violation_tolerance", b.name));
            assert!(
                s.violation.max.is_finite() && s.violation.max <= tol,
                "{}: violation {:e} > {tol:e}",
                b.name,
                s.violation.max
            );
        }
        if let Some(c) = &s.contact {
            assert!(
                c.max_penetration_m <= c.tolerance_m,
                "{}: penetration {:e} > {:e}",
                b.name,
                c.max_penetration_m,
                c.tolerance_m
            );
            assert_eq!(c.verdict, "kept", "{}", b.name);
            assert_eq!(c.backups, 0, "{}", b.name);
        }
        // Every slot at the scene's own rate (sphere-toy-400: 500 Hz).
        assert_eq!(
            s.ticks,
            (seconds * f64::from(s.rate_hz)).round() as u64,
            "{}",
            b.name
        );
        assert!(s.rate_hz >= 500, "{}", b.name);
        let assembly = s.assembly.as_ref().expect("assembled");
        assert!(assembly.converged, "{}: assembly {assembly:?}", b.name);
        assert_eq!(s.safety.solver_failures, 0, "{}", b.name);
        for (i, (finger, f)) in s.force_n.iter().enumerate() {
            let peak = PhantomModel::by_name(&o.finger_devices[i])
                .unwrap()
                .peak_force_n;
            assert!(
                f.max.is_finite() && f.mean.is_finite(),
                "{}: {finger} force not finite",
                b.name
            );
            // The safety layer clamps the command to the peak; the motors'
            // force is their torque (mapped with the encoder-sensed
            // Jacobian) at the arm's true pose, so a clamped command may
            // come out above the peak by that Jacobian's error (counts of
            // 0.03 mm on ~0.2 m links: ~1e-4 relative; the stability matrix
            // bounds it the same way).
            assert!(
                f.max <= peak * (1.0 + 1e-3),
                "{}: {finger} rendered {} N > peak {peak} N",
                b.name,
                f.max
            );
        }
        assert!(s.tracking_m.max.is_finite());
    }
}

/// The summary without the figures read from the monotonic clock (wall
/// time, and compute time even on the mock clock).
fn without_wall_clock(s: &Summary) -> serde_json::Value {
    let mut v = serde_json::to_value(s).unwrap();
    let o = v.as_object_mut().unwrap();
    for key in ["wall_clock_s", "compute_ns", "stages_ns"] {
        assert!(o.remove(key).is_some(), "{key}");
    }
    let slow = o["slow_loop"].as_object_mut().unwrap();
    assert!(slow.remove("step_ns").is_some());
    v
}

#[test]
fn deterministic_runs_are_bit_identical() {
    let scene = resolve("four-bar").unwrap();
    let a = run(&scene, &deterministic(1.5));
    let b = run(&scene, &deterministic(1.5));
    assert_eq!(
        without_wall_clock(&Summary::of(&a)),
        without_wall_clock(&Summary::of(&b))
    );
    assert_eq!(
        a.recorder.force[0].points, b.recorder.force[0].points,
        "force traces differ"
    );
    assert_eq!(a.recorder.violation.points, b.recorder.violation.points);
    // And the run did something: the hand moved the coupler.
    let moving = a.recorder.force[0].points.iter().any(|p| p.1 > 1e-3);
    assert!(moving, "no force was ever rendered");
}

/// Record every built-in scene's devices, replay them (recording again): the
/// replay reproduces bit for bit the encoder counts and gimbal orientation
/// read, the force the session commanded and the force the safety layer sent
/// (every column of both device traces but the hand's), every column of
/// `trace.csv` — the motors' produced force too, since a replayed arm runs
/// the same motor model on the same commands — and the safety layer's
/// counts (clamps, thermal cuts), and it adds no fault; its own comparison
/// finds every force sent equal to the recorded one.
#[test]
fn replaying_a_recorded_session_reproduces_it_bit_for_bit() {
    for b in BUILTIN {
        let scene = resolve(b.name).unwrap();
        // Half a second shows force on every scene but board-wall, whose
        // fingertip is still, 2 mm from the cup, until its hold at 0.5 s
        // and its lift at 0.9 s.
        let seconds = if b.name == "board-wall" { 1.2 } else { 0.5 };
        let dir = tempfile::tempdir().unwrap();
        let (rec_out, rep_out) = (dir.path().join("recorded"), dir.path().join("replayed"));
        std::fs::create_dir_all(&rec_out).unwrap();
        std::fs::create_dir_all(&rep_out).unwrap();
        let (traces, again) = (dir.path().join("traces"), dir.path().join("traces-again"));
        let recorded = run(
            &scene,
            &SessionOptions {
                record: Some(traces.clone()),
                out_dir: Some(rec_out.clone()),
                ..deterministic(seconds)
            },
        );
        let replayed = run(
            &scene,
            &SessionOptions {
                replay: Some(traces.clone()),
                record: Some(again.clone()),
                out_dir: Some(rep_out.clone()),
                ..deterministic(seconds)
            },
        );
        let ticks = recorded.stats.ticks as usize;
        let rows = |p: &Path| -> Vec<String> {
            std::fs::read_to_string(p)
                .unwrap()
                .lines()
                .filter(|l| !l.starts_with('#') && !l.starts_with("t_ns"))
                .map(str::to_owned)
                .collect()
        };
        for d in &scene.compiled.devices {
            let name = format!("{}.trace", d.name);
            let (a, r) = (rows(&traces.join(&name)), rows(&again.join(&name)));
            assert_eq!(
                a.len(),
                1 + ticks,
                "{}: registration row + one per tick",
                b.name
            );
            assert!(
                a.iter().skip(1).any(|r| {
                    let c: Vec<f64> = r
                        .split(',')
                        .skip(4)
                        .take(3)
                        .map(|x| x.parse().unwrap())
                        .collect();
                    c.iter().any(|x| x.abs() > 1e-6)
                }),
                "{}/{}: no force was ever commanded",
                b.name,
                d.name
            );
            // Columns: t, counts, cmd, out, hand, q. The replay's hand column
            // is zero (there is no hand), every other column is identical.
            let strip_hand = |r: &String| {
                let c: Vec<&str> = r.split(',').collect();
                format!("{},{}", c[..10].join(","), c[13..].join(","))
            };
            let (a, r): (Vec<String>, Vec<String>) = (
                a.iter().map(strip_hand).collect(),
                r.iter().map(strip_hand).collect(),
            );
            assert!(a == r, "{}/{}: replayed trace differs", b.name, d.name);
        }
        let every_column = |p: &Path| -> Vec<String> {
            std::fs::read_to_string(p)
                .unwrap()
                .lines()
                .map(str::to_owned)
                .collect()
        };
        let (a, r) = (
            every_column(&rec_out.join("trace.csv")),
            every_column(&rep_out.join("trace.csv")),
        );
        assert_eq!(
            a.len(),
            1 + scene.compiled.fingers.len() * ticks,
            "{}",
            b.name
        );
        assert!(
            a == r,
            "{}: replayed targets/positions/forces/violations differ",
            b.name
        );
        assert_eq!(replayed.stats.faults, recorded.stats.faults, "{}", b.name);
        let limits = |o: &session::SessionOutcome| -> Vec<(u64, u64, u64)> {
            o.device_limits
                .iter()
                .map(|d| (d.peak_clamp, d.motor_saturation, d.thermal_cut))
                .collect()
        };
        assert_eq!(limits(&replayed), limits(&recorded), "{}", b.name);
        for d in &replayed.device_limits {
            let check = d.replay.expect("a replayed device");
            assert_eq!(
                (check.compared, check.diverged),
                (ticks as u64, 0),
                "{}/{}",
                b.name,
                d.device
            );
        }
        assert!(
            !replayed
                .device_events
                .iter()
                .any(|(_, e, _)| e.to_lowercase().contains("dropped")),
            "{}: the replay added {:?}",
            b.name,
            replayed.device_events
        );
        assert_eq!(recorded.recorder.device_trace_dropped, 0);
    }
}

/// A replay must come from the same scene, device model and rate, with times
/// in order, and must reach the end of the run: each mismatch is an error
/// that names the trace and what differs.
#[test]
fn replay_refuses_a_trace_that_belongs_to_another_session() {
    let dir = tempfile::tempdir().unwrap();
    let traces = dir.path().join("traces");
    let four_bar = resolve("four-bar").unwrap();
    run(
        &four_bar,
        &SessionOptions {
            record: Some(traces.clone()),
            ..deterministic(0.2)
        },
    );
    let text = std::fs::read_to_string(traces.join("right.trace")).unwrap();
    let attempt = |trace: &str, scene: &str, options: SessionOptions| -> String {
        let d = tempfile::tempdir().unwrap();
        std::fs::write(d.path().join("right.trace"), trace).unwrap();
        let scene = resolve(scene).unwrap();
        let options = SessionOptions {
            replay: Some(d.path().to_path_buf()),
            ..options
        };
        let r = Plan::new(&scene, &options)
            .and_then(|p| session::run(&scene, p, &StopFlag::new(), &mut |_| {}));
        format!("{:#}", r.err().expect("the replay must be refused"))
    };
    let other_scene = text.replace("# scene: four-bar", "# scene: stewart");
    let e = attempt(&other_scene, "four-bar", deterministic(0.2));
    assert!(
        e.contains("recorded in scene `stewart`, not `four-bar`"),
        "{e}"
    );
    let other_model = text.replace("# model: phantom-premium-1.5", "# model: phantom-omni");
    let e = attempt(&other_model, "four-bar", deterministic(0.2));
    assert!(e.contains("recorded on a `phantom-omni`"), "{e}");
    let e = attempt(
        &text,
        "four-bar",
        SessionOptions {
            rate_hz: Some(2000),
            ..deterministic(0.2)
        },
    );
    assert!(
        e.contains("recorded at 1000 Hz; this run is at 2000 Hz"),
        "{e}"
    );
    let e = attempt(&text, "four-bar", deterministic(0.5));
    assert!(
        e.contains("covers 0.2 s; this run needs 0.5 s (pass --seconds 0.2 or less)"),
        "{e}"
    );
    let mut lines: Vec<&str> = text.lines().collect();
    let first = lines
        .iter()
        .position(|l| l.starts_with("1000000,"))
        .unwrap();
    lines.swap(first, first + 1);
    let e = attempt(&(lines.join("\n") + "\n"), "four-bar", deterministic(0.2));
    assert!(e.contains("does not follow the previous row"), "{e}");
    // And the OS error is said once.
    let e = attempt("", "four-bar", deterministic(0.2));
    assert!(e.contains("empty file"), "{e}");
    let missing = Plan::new(
        &four_bar,
        &SessionOptions {
            replay: Some(dir.path().join("nowhere")),
            ..deterministic(0.2)
        },
    )
    .and_then(|p| session::run(&four_bar, p, &StopFlag::new(), &mut |_| {}));
    let e = format!("{:#}", missing.err().unwrap());
    assert_eq!(e.matches("No such file").count(), 1, "{e}");
}

/// After warm-up, the fast loop's tick (devices, solver, safety layer,
/// statistics, snapshot, trace queue, scheduler) allocates nothing; the
/// design scenes add objectives, free design variables, bounds and the
/// design trace queue.
#[test]
fn the_fast_loop_tick_allocates_nothing() {
    for name in [
        "four-bar",
        "stewart",
        "grasp-3",
        "stewart-feet",
        "dexterity-arm",
    ] {
        let scene = resolve(name).unwrap();
        let mut m = MockSession::new(&scene, &deterministic(30.0));
        m.run(200);
        let (_, stats) = count(|| m.run(2000));
        assert_eq!(
            stats.total(),
            0,
            "{name}: the fast loop allocated: {stats:?}"
        );
        assert_eq!(m.built.fast.stats().ticks, 2200);
        while m.built.trace.pop().is_some() {}
    }
}

/// A stop request mid-run ends the loop at a tick boundary and the outcome is
/// complete (this is what Ctrl-C does). Real scheduler: asserts structure only.
#[test]
fn a_stop_request_ends_a_real_session_cleanly() {
    let scene = resolve("four-bar").unwrap();
    let options = SessionOptions {
        seconds: 30.0,
        thread: ThreadConfig {
            fifo_priority: None,
            lock_memory: false,
            ..ThreadConfig::default()
        },
        ..SessionOptions::default()
    };
    let plan = Plan::new(&scene, &options).unwrap();
    let stop = StopFlag::new();
    let flag = stop.clone();
    let mut seen = 0;
    let o = session::run(&scene, plan, &stop, &mut |_line| {
        seen += 1;
        flag.request(); // after the first status line (about 1 s in)
    })
    .unwrap();
    assert!(o.stopped_early);
    assert!(seen >= 1);
    assert!(o.report.ticks > 0 && o.report.ticks < 30_000);
    assert_eq!(
        o.stats.ticks, o.report.ticks,
        "every tick was accounted for"
    );
    let s = Summary::of(&o);
    assert!(s.stopped_early && s.violation.max.is_finite());
}

#[test]
fn the_cli_runs_a_scene_and_writes_every_file() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    let status = std::process::Command::new(env!("CARGO_BIN_EXE_haptloop"))
        .args([
            "run",
            "peaucellier",
            "--deterministic",
            "--seconds",
            "0.5",
            "--quiet",
            "--out",
        ])
        .arg(&out)
        .output()
        .unwrap();
    assert!(
        status.status.success(),
        "{}",
        String::from_utf8_lossy(&status.stderr)
    );
    let stdout = String::from_utf8_lossy(&status.stdout);
    assert!(stdout.contains("constraint violation"), "{stdout}");
    for f in [
        "summary.json",
        "trace.csv",
        "compute.hgrm",
        "latency.svg",
        "force.svg",
        "violation.svg",
    ] {
        assert!(out.join(f).exists(), "missing {f}");
    }
    // The mock clock has no lateness and no device-to-motor time: a
    // deterministic run writes no histogram of them and says null.
    for f in ["lateness.hgrm", "read-to-write.hgrm"] {
        assert!(!out.join(f).exists(), "{f} written on the mock clock");
    }
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    for key in [
        "scene",
        "seconds",
        "rate_hz",
        "ticks",
        "missed",
        "lateness_ns",
        "compute_ns",
        "violation",
        "tracking_m",
        "force_n",
        "faults",
    ] {
        assert!(summary.get(key).is_some(), "summary.json lacks `{key}`");
    }
    assert_eq!(summary["ticks"], 500);
    assert!(summary["lateness_ns"].is_null() && summary["violation"]["rms"].is_f64());
    // compute.hgrm is the monotonic clock's tick, not the mock clock's zeros.
    assert!(summary["compute_ns"]["p50"].as_u64().unwrap() > 0);
    let hgrm = std::fs::read_to_string(out.join("compute.hgrm")).unwrap();
    let p50_us: f64 = hgrm
        .lines()
        .filter_map(|l| {
            let mut w = l.split_whitespace();
            let v: f64 = w.next()?.parse().ok()?;
            let q: f64 = w.next()?.parse().ok()?;
            (q >= 0.5).then_some(v)
        })
        .next()
        .unwrap();
    assert!(p50_us > 0.0, "compute.hgrm p50 {p50_us} µs");
    assert!(summary["force_n"]["index"]["max"].is_f64());
    let csv = std::fs::read_to_string(out.join("trace.csv")).unwrap();
    assert_eq!(csv.lines().count(), 501);
}

#[test]
fn the_cli_check_reports_a_bad_scene_with_its_location_and_exit_status_1() {
    let bad = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/bad-scenes/unknown-body-in-joint.toml");
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_haptloop"))
        .arg("check")
        .arg(&bad)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("unknown-body-in-joint.toml:20:21:"), "{err}");
    let ok = std::process::Command::new(env!("CARGO_BIN_EXE_haptloop"))
        .args(["check", "grasp-3"])
        .output()
        .unwrap();
    assert!(ok.status.success());
    assert!(String::from_utf8_lossy(&ok.stdout).contains("rigid grasp, 6 rows"));
}

/// The real-time flags are one set shared by `run` and `probe`: an
/// out-of-range priority is a usage error (exit status 2) naming the flag,
/// for both, before anything runs.
#[test]
fn an_out_of_range_priority_is_a_usage_error_for_run_and_probe() {
    for cmd in ["run", "probe"] {
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_haptloop"))
            .args([cmd, "--priority", "150"])
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(2), "{cmd}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            err.contains("--priority") && err.contains("150"),
            "{cmd}: {err}"
        );
    }
}

/// The zero-allocation rule on every path of the tick, not only the calm
/// one: a slow loop running on its own thread hands programs over (the
/// deliberately unstable gain fails every tick, so the slow loop keeps
/// re-projecting), the fault path and its force cut, injected safety events,
/// device traces recorded into their queues, and the force solve's
/// release-and-re-solve branch (Stewart's stroke limits), with its masked
/// second solve and its first solve taken back. Only the fast
/// thread is counted; the slow thread allocates freely, as it may.
#[test]
fn the_fast_loop_tick_allocates_nothing_on_every_path() {
    use haptloop::session::SessionFault;
    use haptloop_rt::schedule::{SafetyEvent, TickBody};
    use std::sync::Arc;
    use std::sync::atomic::{AtomicBool, Ordering};

    let cases = [("stewart", None, 6.0), ("four-bar", Some(1e20), 2.0)];
    let mut swapped = 0;
    let (mut releases, mut kept, mut low_rank) = (0, 0, 0);
    for (name, gain, seconds) in cases {
        let dir = tempfile::tempdir().unwrap();
        let scene = resolve(name).unwrap();
        let options = SessionOptions {
            gain,
            record: Some(dir.path().to_path_buf()),
            ..deterministic(seconds)
        };
        let plan = Plan::new(&scene, &options).unwrap();
        let clock = MockClock::new(Nanos(0));
        let built = session::build(&scene, &plan, clock.clone()).unwrap();
        let session::Built {
            mut fast,
            mut slow,
            trace,
            ..
        } = built;
        let done = Arc::new(AtomicBool::new(false));
        let flag = done.clone();
        let slow_thread = std::thread::spawn(move || {
            while !flag.load(Ordering::Acquire) {
                slow.step();
                std::thread::yield_now();
            }
            slow.stats()
        });
        let (mut periodic, _iv) = Periodic::new(&plan.schedule(), clock).unwrap();
        let stop = StopFlag::new();
        periodic.run(&mut fast, RunLimit::slots(100), &stop);
        let chunks = (plan.ticks() - 100) / 100;
        let (_, stats) = count(|| {
            for k in 0..chunks {
                periodic.run(&mut fast, RunLimit::slots(100), &stop);
                if k % 7 == 3 {
                    fast.on_safety(SafetyEvent::Fault(SessionFault::Solver));
                }
                if k % 11 == 5 {
                    fast.on_safety(SafetyEvent::MissStreak { misses: 5 });
                }
                while trace.pop().is_some() {}
            }
        });
        done.store(true, Ordering::Release);
        let slow_stats = slow_thread.join().unwrap();
        assert_eq!(
            stats.total(),
            0,
            "{name}: the fast loop allocated: {stats:?}"
        );
        assert!(
            fast.stats().force_cuts >= chunks / 7,
            "{name}: cut path not taken"
        );
        swapped += fast.stats().programs_swapped;
        releases += fast.program().force_releases();
        kept += fast.program().force_first_solves_kept();
        low_rank += fast.program().force_low_rank_releases();
        if gain.is_some() {
            assert_eq!(
                fast.stats().solver_failures,
                fast.stats().ticks,
                "{name}: the fault path must be the one taken"
            );
            assert!(slow_stats.reprojections > 0);
        }
    }
    assert!(
        swapped > 0,
        "no program was handed over during the counted ticks"
    );
    assert!(releases > 0, "the release-and-re-solve branch never ran");
    assert!(
        kept > 0,
        "the release branch never took its first solve back"
    );
    assert!(
        low_rank > 0,
        "no release was solved by the low-rank correction"
    );
}

/// Contact scenes on the fast thread allocate nothing either, with the slow
/// loop running beside it: witness tables copied in, whole contact programs
/// swapped in as pairs enter and leave the set, in-tick activations,
/// friction sticking and slipping, proxies on their couplings.
#[test]
fn the_fast_loop_tick_allocates_nothing_with_contacts_switching() {
    use std::sync::Arc;
    use std::sync::atomic::{AtomicBool, Ordering};
    let (mut tables, mut swapped, mut activations, mut sticking) = (0, 0, 0, 0);
    let mut prepared = 0;
    for (name, seconds) in [
        ("pinch-lift", 6.0),
        ("box-slide", 6.0),
        ("peg-in-hole", 3.0),
    ] {
        let scene = resolve(name).unwrap();
        let plan = Plan::new(&scene, &deterministic(seconds)).unwrap();
        let clock = MockClock::new(Nanos(0));
        let session::Built {
            mut fast,
            mut slow,
            trace,
            ..
        } = session::build(&scene, &plan, clock.clone()).unwrap();
        let done = Arc::new(AtomicBool::new(false));
        let flag = done.clone();
        let slow_thread = std::thread::spawn(move || {
            while !flag.load(Ordering::Acquire) {
                slow.step();
                std::thread::yield_now();
            }
        });
        let (mut periodic, _iv) = Periodic::new(&plan.schedule(), clock).unwrap();
        let stop = StopFlag::new();
        periodic.run(&mut fast, RunLimit::slots(50), &stop);
        let chunks = (plan.ticks() - 50) / 50;
        let (_, stats) = count(|| {
            for _ in 0..chunks {
                periodic.run(&mut fast, RunLimit::slots(50), &stop);
                while trace.pop().is_some() {}
                // Give the slow thread its turn, as a real 1 kHz period does.
                std::thread::yield_now();
            }
        });
        done.store(true, Ordering::Release);
        slow_thread.join().unwrap();
        assert_eq!(
            stats.total(),
            0,
            "{name}: the fast loop allocated: {stats:?}"
        );
        let c = fast.stats().contact;
        tables += c.updates;
        swapped += fast.stats().programs_swapped;
        prepared += c.prepared_programs;
        activations += c.activations;
        sticking = sticking.max(c.max_sticking);
    }
    assert!(tables > 0, "no witness update reached the fast loop");
    assert!(swapped > 0, "no contact program was handed over");
    // The slow loop factors every new set of pairs at its snapshot: those
    // hand-overs took the prepared factor (no refactorisation here). Only
    // quasi-static scenes (peg-in-hole): under inertial motion Eq. 7 needs
    // the running program's filtered contact forces, and adoption refactors.
    assert!(prepared > 0, "no prepared contact program was taken over");
    assert!(activations > 0, "no in-tick activation ran");
    assert!(sticking > 0, "no friction contact stuck");
}

/// The room's fast loop allocates nothing either while the slow loop beside
/// it grabs, snaps, breaks and hands over programs with semantic rows: the
/// ticks ramp snap offsets, carry bound bodies and run pinch (weld) rows.
#[test]
fn the_fast_loop_tick_allocates_nothing_with_semantic_rows() {
    use std::sync::Arc;
    use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
    let scene = resolve("room").unwrap();
    let plan = Plan::new(&scene, &deterministic(10.0)).unwrap();
    let clock = MockClock::new(Nanos(0));
    let session::Built {
        mut fast,
        mut slow,
        trace,
        ..
    } = session::build(&scene, &plan, clock.clone()).unwrap();
    let done = Arc::new(AtomicBool::new(false));
    let flag = done.clone();
    // The slow loop's steps, so the fast loop can wait for two after each
    // chunk: on a loaded machine a free-running slow thread may otherwise
    // fall behind and send fewer programs than the room's session makes.
    let steps = Arc::new(AtomicU64::new(0));
    let stepped = steps.clone();
    let slow_thread = std::thread::spawn(move || {
        while !flag.load(Ordering::Acquire) {
            slow.step();
            stepped.fetch_add(1, Ordering::Release);
            std::thread::yield_now();
        }
        slow
    });
    let (mut periodic, _iv) = Periodic::new(&plan.schedule(), clock).unwrap();
    let stop = StopFlag::new();
    periodic.run(&mut fast, RunLimit::slots(50), &stop);
    let chunks = (plan.ticks() - 50) / 50;
    let (_, stats) = count(|| {
        for _ in 0..chunks {
            periodic.run(&mut fast, RunLimit::slots(50), &stop);
            while trace.pop().is_some() {}
            let after = steps.load(Ordering::Acquire) + 2;
            while steps.load(Ordering::Acquire) < after {
                std::thread::yield_now();
            }
        }
    });
    done.store(true, Ordering::Release);
    let slow = slow_thread.join().unwrap();
    assert_eq!(stats.total(), 0, "the fast loop allocated: {stats:?}");
    let report = slow.semantic_report().expect("the room has semantics");
    let kinds: Vec<&str> = report.events.iter().map(|e| e.kind.as_str()).collect();
    assert!(
        kinds.contains(&"snap"),
        "no snap during the counted ticks: {kinds:?}"
    );
    assert!(kinds.contains(&"hold"), "no hold: {kinds:?}");
    assert!(
        report.programs >= 4,
        "{} semantic programs",
        report.programs
    );
    assert!(fast.stats().programs_swapped >= report.programs);
}
