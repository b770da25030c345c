//! Every way a command ends: the exit status says how (failed ticks, a
//! signal, a usage error), and every exit after the output directory is
//! claimed gives it back or leaves it whole.

use haptloop::report::sweep as sweep_report;
use haptloop::scenes::resolve;
use haptloop::sweep::{self, Grid, Options};
use haptloop_rt::schedule::StopFlag;
use haptloop_solver::UpdateRule;
use std::path::Path;
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

fn haptloop() -> Command {
    Command::new(env!("CARGO_BIN_EXE_haptloop"))
}

fn text(o: &Output) -> String {
    format!(
        "status {:?}\nstdout:\n{}\nstderr:\n{}",
        o.status.code(),
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

/// The names in `dir`, sorted.
fn names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

/// A replay from a missing directory fails after the output directory is
/// claimed, and gives it back (a new one removed, an existing one left
/// empty, with no lock and no `trace.csv.partial`), so the next run can use
/// it. A `--record` path that is a file and a `--spin-us` as long as the
/// period are usage errors naming their flag, found before anything is
/// claimed.
#[test]
fn errors_after_the_claim_give_the_output_directory_back() {
    let dir = tempfile::tempdir().unwrap();
    let a_file = dir.path().join("a-file");
    std::fs::write(&a_file, "x").unwrap();
    let run = |extra: &[&str], out: &Path| {
        haptloop()
            .args(["run", "four-bar", "--deterministic", "--seconds", "0.05"])
            .args(["--quiet", "--out"])
            .arg(out)
            .args(extra)
            .output()
            .unwrap()
    };
    let missing = dir.path().join("no-traces");
    let record_at_file = ["--record", a_file.to_str().unwrap()];
    let replay_missing = ["--replay", missing.to_str().unwrap()];
    {
        let extra = &replay_missing[..];
        let new = dir.path().join("new");
        let o = run(extra, &new);
        assert_eq!(o.status.code(), Some(1), "{extra:?}: {}", text(&o));
        assert!(!new.exists(), "{extra:?}: left {:?}", names(&new));
        let existing = dir.path().join("existing");
        std::fs::create_dir_all(&existing).unwrap();
        let o = run(extra, &existing);
        assert_eq!(o.status.code(), Some(1), "{extra:?}: {}", text(&o));
        assert!(
            names(&existing).is_empty(),
            "{extra:?}: left {:?}",
            names(&existing)
        );
    }
    let spin = dir.path().join("spin");
    let o = run(&["--spin-us", "1000"], &spin);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(
        String::from_utf8_lossy(&o.stderr).contains(
            "--spin-us 1000: the spin window must be shorter than the period, 1000 µs at 1000 Hz"
        ),
        "{}",
        text(&o)
    );
    assert!(!spin.exists());
    let o = run(&record_at_file, &spin);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(
        String::from_utf8_lossy(&o.stderr).contains("that is a file; --record takes a directory"),
        "{}",
        text(&o)
    );
    assert!(!spin.exists());
    // The directory the failed runs gave back takes the next run.
    let existing = dir.path().join("existing");
    let o = run(&[], &existing);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    assert!(names(&existing).contains(&"summary.json".to_string()));
}

/// A run whose ticks failed finishes, writes its files and exits 3 (not 0),
/// saying how many failed.
#[test]
fn a_run_with_failed_ticks_exits_3() {
    let o = haptloop()
        .args(["run", "four-bar", "--deterministic", "--seconds", "0.1"])
        .args(["--gain", "1e20", "--no-files", "--quiet"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(3), "{}", text(&o));
    assert!(
        String::from_utf8_lossy(&o.stderr).contains("100 ticks failed (exit status 3)"),
        "{}",
        text(&o)
    );
    let ok = haptloop()
        .args(["run", "four-bar", "--deterministic", "--seconds", "0.1"])
        .args(["--no-files", "--quiet"])
        .output()
        .unwrap();
    assert_eq!(ok.status.code(), Some(0), "{}", text(&ok));
}

/// Waits (bounded) until `path` holds more than `bytes` bytes.
fn wait_for(path: &Path, bytes: u64) -> bool {
    let start = Instant::now();
    while start.elapsed() < Duration::from_secs(30) {
        if std::fs::metadata(path).is_ok_and(|m| m.len() > bytes) {
            return true;
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    false
}

/// Two Ctrl-C in a row: the run aborts with status 130, but first writes
/// `summary.json` of the ticks that ran (it used to exit at once, leaving
/// its lock and an empty `trace.csv.partial`, and the next run refused the
/// directory).
#[test]
fn a_double_ctrl_c_writes_summary_json_of_what_ran() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    let child = haptloop()
        .args(["run", "four-bar", "--seconds", "60", "--quiet"])
        .args(["--priority", "0", "--no-mlock", "--out"])
        .arg(&out)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let started = wait_for(&out.join("trace.csv.partial"), 20_000);
    for _ in 0..2 {
        Command::new("kill")
            .args(["-INT", &child.id().to_string()])
            .status()
            .unwrap();
    }
    let o = child.wait_with_output().unwrap();
    assert!(started, "the run never started: {}", text(&o));
    assert_eq!(o.status.code(), Some(130), "{}", text(&o));
    let left = names(&out);
    assert!(
        left.iter()
            .all(|n| !n.ends_with(".partial") && !n.ends_with(".lock")),
        "left behind {left:?}"
    );
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["stopped_early"], true);
    let ticks = summary["ticks"].as_u64().unwrap();
    assert!(ticks > 10, "{ticks} ticks");
    // The trace holds exactly those ticks (one finger).
    let rows = std::fs::read_to_string(out.join("trace.csv"))
        .unwrap()
        .lines()
        .count()
        - 1;
    assert_eq!(rows as u64, ticks);
}

/// A sweep stopped by a signal exits 130, says so in `sweep.json`, and does
/// not call the points it measured "not run".
#[test]
fn an_interrupted_sweep_exits_130_and_labels_what_ran() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("sweep");
    let child = haptloop()
        .args(["sweep", "four-bar", "--iterations", "1,2,3,4,5,6"])
        .args(["--update", "projected,gradient", "--rate", "1000,2000"])
        .args(["--seconds", "10", "--threads", "1", "--quiet", "--out"])
        .arg(&out)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // 24 points of 10 s: 480 s of session time (accuracy, then timing), at
    // least ~13 s of work even on CI's faster cores (3 s points finished
    // there inside the 4 s wait), while the first point is measured in
    // about a second.
    std::thread::sleep(Duration::from_secs(4));
    Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    let o = child.wait_with_output().unwrap();
    assert_eq!(o.status.code(), Some(130), "{}", text(&o));
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("sweep.json")).unwrap()).unwrap();
    assert_eq!(json["stopped_early"], true, "{json}");
    let points = json["points"].as_array().unwrap();
    let measured: Vec<&serde_json::Value> = points
        .iter()
        .filter(|p| p["failed_ticks"].is_u64())
        .collect();
    assert!(
        !measured.is_empty(),
        "nothing was measured before the signal"
    );
    assert!(
        measured.iter().all(|p| p["verdict"] != "not run"),
        "{measured:?}"
    );
    assert!(
        points.iter().any(|p| p["verdict"] != "ok"),
        "every point measured and timed: the signal came too late"
    );
}

/// "recommended: none" names, per point, the criterion it missed (it used
/// to say "no point has no failed tick, …" when no tick had failed).
#[test]
fn no_recommendation_says_why_for_each_point() {
    let scene = resolve("four-bar").unwrap();
    let grid = Grid {
        iterations: vec![1, 2],
        update: vec![UpdateRule::Gradient],
        force_solver: vec![haptloop_solver::ForceSolver::Cholesky],
        gain: vec![1000.0],
        rate_hz: vec![1000],
        velocity_filter_ms: vec![10.0],
    };
    let options = Options {
        seconds: 0.3,
        reference_every: Duration::from_millis(10),
        threads: 1,
        force_tolerance: 0.01,
    };
    let s = sweep::run(&scene, &grid, &options, &StopFlag::new(), &|_| {}).unwrap();
    let table = sweep_report::table(&s);
    let json: serde_json::Value = serde_json::from_str(&sweep_report::json(&s).unwrap()).unwrap();
    assert_eq!(json["recommended"], serde_json::Value::Null, "{table}");
    // Both points ran without a failed tick; gradient steps leave the
    // four-bar's 1 µm tolerance behind.
    for p in json["points"].as_array().unwrap() {
        assert_eq!(p["failed_ticks"], 0, "{table}");
        assert_eq!(p["verdict"], "violation > tolerance", "{table}");
    }
    assert!(
        table.contains("each point misses one:\n  violation > tolerance: #0, #1"),
        "{table}"
    );
    assert!(!table.contains("no point has"), "{table}");
    assert_eq!(json["stopped_early"], false);
}

/// Ctrl-C during `check`'s trial stops the trial at its next tick and exits
/// 130 saying so (the trial used to ignore the signal: `timeout` could not
/// stop a check of a 64-sphere pile for ten minutes).
#[test]
fn ctrl_c_stops_checks_trial() {
    let mut child = haptloop()
        .args(["check", "four-bar", "--seconds", "3600"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // The build takes well under a second; the hour-long trial (minutes of
    // work) is then running.
    std::thread::sleep(Duration::from_secs(3));
    Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    let mut waited = 0;
    while child.try_wait().unwrap().is_none() && waited < 600 {
        std::thread::sleep(Duration::from_millis(100));
        waited += 1;
    }
    if waited == 600 {
        child.kill().unwrap();
    }
    let o = child.wait_with_output().unwrap();
    assert!(waited < 600, "check ran on for 60 s after Ctrl-C");
    assert_eq!(o.status.code(), Some(130), "{}", text(&o));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("interrupted during the 3600 s trial"),
        "{}",
        text(&o)
    );
}

/// `haptloop bench … | head` closes stdout before the table is printed: the
/// bench still writes its `--json` file and exits 0, and never panics on the
/// broken pipe (it used `println!`, which panics on EPIPE).
#[test]
fn a_bench_into_a_closed_pipe_does_not_panic() {
    let dir = tempfile::tempdir().unwrap();
    let json = dir.path().join("bench.json");
    let mut child = haptloop()
        .args(["bench", "four-bar", "--ticks", "300", "--json"])
        .arg(&json)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let o = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!err.contains("panicked"), "{err}");
    assert_eq!(o.status.code(), Some(0), "{err}");
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(v["ticks"].as_u64(), Some(300), "{v}");
}
