//! Replays that cannot lie: every value read back is checked, a recording
//! cannot be overwritten by the replay that reads it, and a replay whose
//! forces differ from its recording's says so.

use haptloop::scenes::resolve;
use haptloop::session::{self, Plan, SessionOptions};
use haptloop_rt::schedule::StopFlag;
use std::path::Path;
use std::process::{Command, Output};

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

fn deterministic(seconds: f64) -> SessionOptions {
    SessionOptions {
        seconds,
        deterministic: true,
        ..SessionOptions::default()
    }
}

/// Records `scene`'s devices for `seconds` into `dir`.
fn record(scene: &str, seconds: f64, dir: &Path) {
    let o = haptloop()
        .args(["run", scene, "--deterministic", "--seconds"])
        .arg(seconds.to_string())
        .args(["--no-files", "--quiet", "--record"])
        .arg(dir)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", text(&o));
}

/// Every value a trace holds is checked when it is read back: a NaN, an
/// infinity or 1e308 in a command or output column, an output above the
/// device's peak force, a NaN hand offset, an orientation that is not a
/// rotation. Each refusal names the file, the line and the column (they
/// used to be accepted, and one replay faulted every tick while its report
/// said "kept").
#[test]
fn every_value_a_replay_reads_is_checked() {
    let dir = tempfile::tempdir().unwrap();
    let traces = dir.path().join("traces");
    record("four-bar", 0.2, &traces);
    let text = std::fs::read_to_string(traces.join("right.trace")).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    let row = lines
        .iter()
        .position(|l| l.starts_with("50000000,"))
        .unwrap();
    let scene = resolve("four-bar").unwrap();
    // (column, value, what the refusal says)
    let cases = [
        (4, "NaN", "column 5 (`cmd_x`) is NaN"),
        (5, "inf", "column 6 (`cmd_y`) is inf"),
        (6, "1e308", "above 1e6 N"),
        (7, "9.0", "above the phantom-premium-1.5's peak of 8.5 N"),
        (8, "1e308", "above the phantom-premium-1.5's peak"),
        (9, "-inf", "column 10 (`out_z`) is -inf"),
        (11, "NaN", "column 12 (`hand_y`) is NaN"),
        (13, "NaN", "column 14 (`qw`) is NaN"),
        (14, "5.0", "not a rotation"),
    ];
    for (column, value, want) in cases {
        let mut fields: Vec<&str> = lines[row].split(',').collect();
        fields[column] = value;
        let edited = fields.join(",");
        let mut all = lines.clone();
        all[row] = &edited;
        let d = tempfile::tempdir().unwrap();
        std::fs::write(d.path().join("right.trace"), all.join("\n") + "\n").unwrap();
        let options = SessionOptions {
            replay: Some(d.path().to_path_buf()),
            ..deterministic(0.2)
        };
        let r = Plan::new(&scene, &options)
            .and_then(|p| session::run(&scene, p, &StopFlag::new(), &mut |_| {}));
        let e = format!("{:#}", r.err().expect("the edited trace must be refused"));
        let at = format!("right.trace:{}: ", row + 1);
        assert!(
            e.contains(&at) && e.contains(want),
            "{column} = {value}: {e}"
        );
    }
}

/// `--record` into the `--replay` directory would overwrite the recording
/// being replayed: a usage error, before anything runs; the recording is
/// untouched.
#[test]
fn recording_into_the_replay_directory_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let traces = dir.path().join("traces");
    record("grasp-2", 0.1, &traces);
    let before = std::fs::read(traces.join("left.trace")).unwrap();
    let same_dir = format!("{}/./", traces.display());
    let o = haptloop()
        .args(["run", "grasp-2", "--deterministic", "--seconds", "0.1"])
        .args(["--no-files", "--quiet", "--replay"])
        .arg(&traces)
        .args(["--record", &same_dir])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(
        String::from_utf8_lossy(&o.stderr).contains("that is the --replay directory"),
        "{}",
        text(&o)
    );
    assert_eq!(std::fs::read(traces.join("left.trace")).unwrap(), before);
}

/// `--record` naming a file: a usage error that names the flag, before
/// anything runs (it was "creating …: File exists" once the run had
/// started); the file is untouched.
#[test]
fn recording_into_a_file_is_refused_naming_the_flag() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("notes.txt");
    std::fs::write(&file, "mine").unwrap();
    let o = haptloop()
        .args(["run", "four-bar", "--deterministic", "--seconds", "0.1"])
        .args(["--no-files", "--quiet", "--record"])
        .arg(&file)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    let err = String::from_utf8_lossy(&o.stderr);
    let want = format!("--record {}: that is a file", file.display());
    assert!(err.contains(&want), "{}", text(&o));
    assert!(!err.contains("running"), "{}", text(&o));
    assert_eq!(std::fs::read_to_string(&file).unwrap(), "mine");
}

/// Another scene's rows under an edited header load (every value is
/// plausible), but the replay sends forces that differ from the recorded
/// ones from the first tick that differs: the report says `DIVERGED`,
/// `summary.json` says where, the exit status is 3. The untouched
/// recording replays as `reproduced` with status 0.
#[test]
fn another_scenes_rows_under_an_edited_header_are_found_out() {
    let dir = tempfile::tempdir().unwrap();
    let (other, own) = (dir.path().join("other"), dir.path().join("own"));
    record("four-bar-design", 0.3, &other);
    record("four-bar", 0.3, &own);
    let path = other.join("right.trace");
    let edited = std::fs::read_to_string(&path)
        .unwrap()
        .replace("# scene: four-bar-design", "# scene: four-bar");
    std::fs::write(&path, edited).unwrap();
    let replay = |traces: &Path, out: &Path| {
        haptloop()
            .args(["run", "four-bar", "--deterministic", "--seconds", "0.3"])
            .args(["--quiet", "--replay"])
            .arg(traces)
            .arg("--out")
            .arg(out)
            .output()
            .unwrap()
    };
    let (a, b) = (dir.path().join("a"), dir.path().join("b"));
    let o = replay(&other, &a);
    assert_eq!(o.status.code(), Some(3), "{}", text(&o));
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(
        stdout.contains("replay: DIVERGED: device `right`"),
        "{stdout}"
    );
    assert!(stdout.contains("WARNING: device `right`"), "{stdout}");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(a.join("summary.json")).unwrap()).unwrap();
    let d = &summary["replay"]["devices"][0];
    assert!(d["diverged"].as_u64().unwrap() > 0, "{summary}");
    assert!(d["first_divergence_s"].as_f64().unwrap() > 0.0, "{summary}");
    let o = replay(&own, &b);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(b.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["replay"]["devices"][0]["diverged"], 0);
    assert_eq!(summary["replay"]["devices"][0]["compared"], 300);
    assert!(
        summary["replay"]["verdict"]
            .as_str()
            .unwrap()
            .starts_with("reproduced"),
        "{summary}"
    );
}
