//! What the user and the hardware must be able to trust: motors at zero after
//! every kind of exit (read at the motor), signals handled like Ctrl-C, output
//! directories that one run owns, files that are whole or absent.

use haptloop::report::summary::Summary;
use haptloop::scenes::resolve;
use haptloop::session::{self, Plan, SessionOptions};
use haptloop_rt::schedule::StopFlag;
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

fn deterministic(seconds: f64) -> SessionOptions {
    SessionOptions {
        seconds,
        deterministic: true,
        ..SessionOptions::default()
    }
}

/// After a run ends, every device's motors apply exactly zero torque, read at
/// the motor (the old stop wrote zero through the rate limiter, which let it
/// fall by only 2 N on that write and left the last force on the motors).
#[test]
fn motors_apply_zero_torque_after_every_run() {
    for name in ["four-bar", "grasp-2", "grasp-3"] {
        let scene = resolve(name).unwrap();
        let plan = Plan::new(&scene, &deterministic(0.8)).unwrap();
        let o = session::run(&scene, plan, &StopFlag::new(), &mut |_| {}).unwrap();
        assert_eq!(
            o.torque_at_exit_nm.len(),
            scene.compiled.devices.len(),
            "{name}"
        );
        let max_force = o
            .stats
            .fingers
            .iter()
            .map(|f| f.force_max)
            .fold(0.0, f64::max);
        assert!(max_force > 0.05, "{name}: the run rendered no force");
        for (device, torque) in &o.torque_at_exit_nm {
            assert_eq!(*torque, Some([0.0; 3]), "{name}: {device} left torque on");
        }
    }
}

fn haptloop() -> Command {
    Command::new(env!("CARGO_BIN_EXE_haptloop"))
}

/// Waits (bounded) until `path` exists and holds more than `bytes` bytes.
fn wait_for(path: &Path, bytes: u64, limit: Duration) -> bool {
    let start = Instant::now();
    while start.elapsed() < limit {
        if std::fs::metadata(path).is_ok_and(|m| m.len() > bytes) {
            return true;
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    false
}

/// SIGTERM and SIGHUP stop a real-time run like Ctrl-C: exit status 130
/// (a stopped run is not a success, README "Exit status"), the report and
/// every file written, `trace.csv` complete to its last row, no temporary or
/// lock file left behind.
#[test]
fn sigterm_and_sighup_stop_a_run_cleanly() {
    for signal in ["TERM", "HUP"] {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("run");
        let child = haptloop()
            .args([
                "run",
                "four-bar",
                "--seconds",
                "60",
                "--quiet",
                "--priority",
                "0",
            ])
            .args(["--no-mlock", "--out"])
            .arg(&out)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        // The run is under way once its trace has rows.
        let started = wait_for(
            &out.join("trace.csv.partial"),
            20_000,
            Duration::from_secs(30),
        );
        let kill = Command::new("kill")
            .args([format!("-{signal}"), child.id().to_string()])
            .status()
            .unwrap();
        let result = child.wait_with_output().unwrap();
        assert!(started, "SIG{signal}: the run never started");
        assert!(kill.success());
        let stdout = String::from_utf8_lossy(&result.stdout);
        assert_eq!(
            result.status.code(),
            Some(130),
            "SIG{signal}: exit {:?}\n{}",
            result.status,
            String::from_utf8_lossy(&result.stderr)
        );
        assert!(
            stdout.contains("ticks:"),
            "SIG{signal}: no report\n{stdout}"
        );
        for f in ["summary.json", "trace.csv", "force.svg", "lateness.hgrm"] {
            assert!(out.join(f).is_file(), "SIG{signal}: {f} missing");
        }
        let mut names: Vec<_> = std::fs::read_dir(&out)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        assert!(
            names
                .iter()
                .all(|n| !n.ends_with(".partial") && !n.ends_with(".lock")),
            "SIG{signal}: left behind {names:?}"
        );
        let trace = std::fs::read_to_string(out.join("trace.csv")).unwrap();
        assert!(trace.ends_with('\n'));
        let header_fields = trace.lines().next().unwrap().split(',').count();
        let rows = trace.lines().skip(1).count();
        assert!(rows > 10, "SIG{signal}: {rows} rows");
        for (i, line) in trace.lines().enumerate() {
            assert_eq!(line.split(',').count(), header_fields, "row {i}: {line}");
        }
        let summary: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap())
                .unwrap();
        assert_eq!(summary["stopped_early"], true, "SIG{signal}");
    }
}

/// A second run into a directory that holds files is refused before it runs,
/// so two runs can never interleave rows into one `trace.csv`.
#[test]
fn a_non_empty_output_directory_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("trace.csv"), "t_s\n").unwrap();
    let r = haptloop()
        .args(["run", "--deterministic", "--seconds", "0.1", "--out"])
        .arg(dir.path())
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&r.stderr);
    assert_eq!(r.status.code(), Some(1), "{err}");
    assert!(
        err.contains("not empty") && err.contains("trace.csv"),
        "{err}"
    );
    assert_eq!(
        std::fs::read_to_string(dir.path().join("trace.csv")).unwrap(),
        "t_s\n"
    );
}

/// Out-of-range numbers are usage errors (exit 2) naming the flag, caught
/// before anything runs; so is a core this process cannot use.
#[test]
fn out_of_range_flags_are_usage_errors() {
    let cases: [&[&str]; 7] = [
        &["run", "--rate", "5"],
        &["run", "--seconds", "0"],
        &["run", "--seconds", "nan"],
        &["run", "--iterations", "0"],
        &["run", "--gain=-1"],
        &["run", "--core", "4096"],
        &["probe", "--rate", "30000"],
    ];
    for args in cases {
        let r = haptloop().args(args).output().unwrap();
        let err = String::from_utf8_lossy(&r.stderr);
        assert_eq!(r.status.code(), Some(2), "{args:?}: {err}");
        assert!(
            err.contains(args[1].trim_start_matches("--").split('=').next().unwrap()),
            "{args:?}: {err}"
        );
    }
}

/// `probe --json` to a path that cannot be written fails at once, not after
/// the probe has run.
#[test]
fn probe_fails_before_running_when_its_output_cannot_be_written() {
    let r = haptloop()
        .args([
            "probe",
            "--seconds",
            "30",
            "--json",
            "/nonexistent-dir/x.json",
        ])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&r.stderr);
    assert_eq!(r.status.code(), Some(1), "{err}");
    assert!(err.contains("/nonexistent-dir/x.json"), "{err}");
    assert!(!err.contains("haptloop probe:"), "the probe ran: {err}");
}

fn summary_of(scene: &haptloop::scenes::Scene, options: &SessionOptions) -> Summary {
    let plan = Plan::new(scene, options).unwrap();
    Summary::of(&session::run(scene, plan, &StopFlag::new(), &mut |_| {}).unwrap())
}

/// A scene file derived from the default scene by one textual replacement.
fn four_bar_with(dir: &Path, from: &str, to: &str) -> haptloop::scenes::Scene {
    let text = haptloop::scenes::BUILTIN
        .iter()
        .find(|b| b.name == "four-bar")
        .unwrap()
        .text;
    assert!(text.contains(from), "{from}");
    let path = dir.join("variant.toml");
    std::fs::write(&path, text.replace(from, to)).unwrap();
    resolve(path.to_str().unwrap()).unwrap()
}

/// (A body at 1e308 m, the fourth case, is now refused when the
/// scene loads: `tests/data/bad-scenes/huge-position.toml`.)
/// Runs where every tick fails, or none runs, never report a violation of 0
/// "kept": they say nothing was measured and why, the figures are NaN, and
/// summary.json writes them as "NaN" (not a silent null).
#[test]
fn reports_never_claim_a_tolerance_over_ticks_that_failed_or_never_ran() {
    let dir = tempfile::tempdir().unwrap();
    let default = resolve("four-bar").unwrap();
    let unassemblable = four_bar_with(dir.path(), "-0.049749371855331]", "-0.5]");
    let cases = [
        (
            "gain 1e20",
            summary_of(
                &default,
                &SessionOptions {
                    gain: Some(1e20),
                    ..deterministic(0.3)
                },
            ),
            "not measured: all 300 ticks failed",
        ),
        (
            "no tick",
            summary_of(&default, &deterministic(0.0001)),
            "not measured: no tick ran",
        ),
        (
            "unassemblable",
            summary_of(&unassemblable, &deterministic(0.3)),
            "not measured: all 300 ticks failed",
        ),
    ];
    for (what, s, verdict) in &cases {
        assert_eq!(s.violation.verdict, *verdict, "{what}");
        assert_eq!(s.violation.ticks_measured, 0, "{what}");
        assert_eq!(s.violation.ticks_failed, s.ticks, "{what}");
        assert!(
            s.violation.max.is_nan() && s.tracking_m.max.is_nan(),
            "{what}"
        );
        let json = serde_json::to_value(s).unwrap();
        assert_eq!(json["violation"]["max"], "NaN", "{what}");
        assert_eq!(json["tracking_m"]["rms"], "NaN", "{what}");
        assert!(
            s.reference.missing.is_some() && s.reference.force_error_n.max.is_nan(),
            "{what}: claims reference samples"
        );
        let text = haptloop::report::session::render(s, &[]);
        assert!(!text.contains("kept"), "{what}: {text}");
        assert!(text.contains(verdict), "{what}: {text}");
    }
    assert_eq!(cases[2].1.assembly.as_ref().unwrap().status, "LeastSquares");
    // A healthy run: measured over every tick, kept, a real figure.
    let ok = summary_of(&default, &deterministic(0.3));
    assert_eq!(
        (ok.violation.ticks_measured, ok.violation.ticks_failed),
        (300, 0)
    );
    assert_eq!(ok.violation.verdict, "kept");
    assert!(ok.violation.max.is_finite() && ok.violation.max < 1e-6);
}

/// `check` builds what `run` builds: a scene that loads but whose program
/// cannot be built is refused by `check` too, at a file position.
#[test]
fn check_refuses_what_run_refuses() {
    let dir = tempfile::tempdir().unwrap();
    let text = haptloop::scenes::BUILTIN[0]
        .text
        .replace("step = 1.0", "step = 1e9");
    assert!(
        text.contains("step = 1e9"),
        "the default scene sets its step"
    );
    let path = dir.path().join("step.toml");
    std::fs::write(&path, &text).unwrap();
    let line = text.lines().position(|l| l == "[solver]").unwrap() + 1;
    let check = haptloop().arg("check").arg(&path).output().unwrap();
    let err = String::from_utf8_lossy(&check.stderr);
    assert_eq!(check.status.code(), Some(1), "{err}");
    assert!(
        err.starts_with(&format!(
            "{}:{line}:1: the scene loads but cannot run",
            path.display()
        )) && err.contains("step"),
        "{err}"
    );
    let run = haptloop()
        .args(["run", "--deterministic", "--seconds", "0.1", "--no-files"])
        .arg(&path)
        .output()
        .unwrap();
    assert_eq!(run.status.code(), Some(1));
    // And every built-in scene passes check.
    // (A short preflight trial keeps this cheap; its length is the
    // preflight's only knob.)
    for b in haptloop::scenes::BUILTIN {
        let r = haptloop()
            .args(["check", "--seconds", "0.5", b.name])
            .output()
            .unwrap();
        assert!(
            r.status.success(),
            "{}: {}",
            b.name,
            String::from_utf8_lossy(&r.stderr)
        );
    }
}

/// Ctrl-C while a session is still being built (the build stretched to 20 s
/// with the testing aid `HAPTLOOP_TEST_SLOW_BUILD_MS`; a big mechanism's
/// factorisations are the real case) ends the process at once with status
/// 130 and gives back the output directory.
#[test]
fn ctrl_c_during_building_exits_at_once() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    let child = haptloop()
        .args(["run", "--seconds", "1", "--quiet", "--out"])
        .arg(&out)
        .env(haptloop::session::SLOW_BUILD_ENV, "20000")
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let lock = out.join(".haptloop-run.lock");
    let start = Instant::now();
    while !lock.exists() && start.elapsed() < Duration::from_secs(30) {
        std::thread::sleep(Duration::from_millis(5));
    }
    let claimed = lock.exists();
    Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    let r = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&r.stderr);
    assert!(claimed, "the run never claimed its directory: {err}");
    assert_eq!(r.status.code(), Some(130), "{err}");
    assert!(
        err.contains("interrupted before the session started"),
        "{err}"
    );
    assert!(!out.exists(), "the claimed directory was left behind");
}

/// A closed stdout (`haptloop run … | head -1`) does not stop a run from
/// writing its files, and nothing panics: the report's print used to panic
/// on the broken pipe before the files were written. `scenes` too.
#[test]
fn a_closed_stdout_still_writes_the_run_and_does_not_panic() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    let mut child = haptloop()
        .args([
            "run",
            "pinch-lift",
            "--deterministic",
            "--seconds",
            "0.5",
            "--quiet",
            "--out",
        ])
        .arg(&out)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let result = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&result.stderr);
    assert!(result.status.success(), "{:?}: {stderr}", result.status);
    assert!(!stderr.contains("panicked"), "{stderr}");
    let summary = std::fs::read_to_string(out.join("summary.json")).unwrap();
    let summary: Summary = serde_json::from_str(&summary).unwrap();
    assert!(summary.ticks >= 499, "{} ticks", summary.ticks);
    for name in ["trace.csv", "bodies.csv", "contact.svg"] {
        assert!(out.join(name).exists(), "{name} missing");
    }

    let mut child = haptloop()
        .arg("scenes")
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let result = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&result.stderr);
    assert!(result.status.success(), "{:?}: {stderr}", result.status);
    assert!(!stderr.contains("panicked"), "{stderr}");
}
