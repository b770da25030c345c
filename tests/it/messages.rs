//! Say what and where: the messages and reports the issue found wanting —
//! a failed tick written as a perfect row, `NaN` next to a unit, `0.000`
//! for a small number, a position for a file that does not exist, an I/O
//! error without its reason, a binary file echoed whole.

use haptloop::scenes::BUILTIN;
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

fn builtin(name: &str) -> &'static str {
    BUILTIN.iter().find(|b| b.name == name).unwrap().text
}

/// Runs `args` deterministically into `out` and returns the output.
fn run_into(out: &Path, args: &[&str]) -> Output {
    haptloop()
        .args(["run", "--deterministic", "--quiet", "--out"])
        .arg(out)
        .args(args)
        .output()
        .unwrap()
}

/// In `trace.csv` a failed tick says so (`failed` 1) and leaves its
/// position and violation empty; it used to be a row of zeros that looked
/// perfect. A healthy run's rows are all `failed` 0 and complete.
#[test]
fn trace_csv_marks_failed_ticks() {
    let dir = tempfile::tempdir().unwrap();
    for (gain, failed) in [("1e20", "1"), ("1000", "0")] {
        let out = dir.path().join(format!("gain-{gain}"));
        let o = run_into(&out, &["four-bar", "--seconds", "0.05", "--gain", gain]);
        let csv = std::fs::read_to_string(out.join("trace.csv")).unwrap_or_else(|_| text(&o));
        let mut lines = csv.lines();
        let head: Vec<&str> = lines.next().unwrap().split(',').collect();
        let col = |n: &str| head.iter().position(|h| *h == n).unwrap();
        let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
        assert_eq!(rows.len(), 50);
        for r in &rows {
            assert_eq!(r.len(), head.len());
            assert_eq!(r[col("failed")], failed, "gain {gain}: {r:?}");
            let empty = failed == "1";
            for c in [
                "position_x_m",
                "position_y_m",
                "position_z_m",
                "violation_m",
            ] {
                assert_eq!(r[col(c)].is_empty(), empty, "gain {gain}, {c}: {r:?}");
            }
            // The target is the device's reading either way.
            assert!(r[col("target_x_m")].parse::<f64>().is_ok(), "{r:?}");
        }
    }
}

/// Files that are missing, unreadable or binary are named with the reason
/// and without a made-up position; durations are written exactly.
#[test]
fn file_errors_say_what_and_where() {
    let dir = tempfile::tempdir().unwrap();
    // A scene that does not exist is not at line 1, column 1 of anything.
    let o = haptloop().args(["run", "nosuchscene"]).output().unwrap();
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.starts_with("nosuchscene: no such file"), "{err}");
    // A hand trace that cannot be read: the OS's reason.
    let scene = dir.path().join("traced.toml");
    let four_bar = builtin("four-bar");
    let circle = four_bar.lines().find(|l| l.starts_with("hand = ")).unwrap();
    std::fs::write(
        &scene,
        four_bar.replace(circle, "hand = { trace = \"missing.csv\" }"),
    )
    .unwrap();
    let o = haptloop().arg("check").arg(&scene).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("hand trace: ") && err.contains("missing.csv: cannot read it: No such file"),
        "{err}"
    );
    // A binary replay trace: refused, quoting only its first characters.
    let binary = dir.path().join("binary");
    std::fs::create_dir_all(&binary).unwrap();
    // Text with control characters and no newline: 200 KB in one line.
    let junk: Vec<u8> = (0..200_000u32)
        .map(|i| if i % 7 == 0 { 1 } else { b'a' + (i % 26) as u8 })
        .collect();
    std::fs::write(binary.join("right.trace"), junk).unwrap();
    let o = haptloop()
        .args([
            "run",
            "four-bar",
            "--deterministic",
            "--seconds",
            "0.1",
            "--no-files",
        ])
        .arg("--replay")
        .arg(&binary)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.len() < 1000, "{} bytes of error", err.len());
    assert!(err.contains("right.trace:1: "), "{err}");
    // A replay shorter than the run: the exact durations, not `0.000`.
    let traces = dir.path().join("traces");
    let rec = haptloop()
        .args(["run", "four-bar", "--deterministic", "--rate", "4000"])
        .args(["--seconds", "0.00025", "--no-files", "--quiet", "--record"])
        .arg(&traces)
        .output()
        .unwrap();
    assert!(rec.status.success(), "{}", text(&rec));
    let o = haptloop()
        .args(["run", "four-bar", "--deterministic", "--rate", "4000"])
        .args(["--seconds", "0.001", "--no-files", "--replay"])
        .arg(&traces)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("covers 0.00025 s; this run needs 0.001 s (pass --seconds 0.00025 or less)"),
        "{err}"
    );
}

/// Reports print no `NaN` next to a unit and no `0.000` for a small figure:
/// a contact scene with no witness update ("latency mean NaN ticks"), a
/// penetration tolerance of 0.2 µm ("0.000 mm"), a scene without fingers
/// ("RMS NaN N", "not measured (no tick succeeded)" although all did). A
/// deterministic `summary.json` says why it has no lateness and no
/// read-to-write time.
#[test]
fn reports_print_no_nan_and_keep_small_figures() {
    let dir = tempfile::tempdir().unwrap();
    let tight = dir.path().join("tight.toml");
    std::fs::write(
        &tight,
        builtin("box-slide").replace(
            "penetration_tolerance = 1e-4",
            "penetration_tolerance = 2e-7",
        ),
    )
    .unwrap();
    let out = dir.path().join("tight");
    let o = run_into(&out, &[tight.to_str().unwrap(), "--seconds", "0.2"]);
    let report = String::from_utf8_lossy(&o.stdout);
    assert!(
        report.contains("scene tolerance 2.00e-4 mm"),
        "{}",
        text(&o)
    );
    assert!(report.contains("witness → fast loop: "), "{report}");
    assert!(
        !report.contains("NaN") && !report.contains("0.000 mm"),
        "{report}"
    );
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert!(summary["lateness_ns"].is_null() && summary["read_to_write_ns"].is_null());
    let note = summary["clock_note"].as_str().unwrap_or_default();
    assert!(
        note.contains("mock clock") && note.contains("read_to_write_ns"),
        "{summary}"
    );
    // The four-bar without its device and finger: nothing to track.
    let four_bar = builtin("four-bar");
    let start = four_bar.find("\n[[device]]").unwrap();
    let end = four_bar.find("\n[[body]]").unwrap();
    let cut = four_bar.find("\n[[finger]]").unwrap();
    let bare = format!("{}{}", &four_bar[..start], &four_bar[end..cut]);
    let path = dir.path().join("bare.toml");
    std::fs::write(&path, bare).unwrap();
    let o = haptloop()
        .args([
            "run",
            "--deterministic",
            "--seconds",
            "0.2",
            "--no-files",
            "--quiet",
        ])
        .arg(&path)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    let report = String::from_utf8_lossy(&o.stdout);
    assert!(
        report.contains("finger tracking error: none: the scene has no fingers"),
        "{report}"
    );
    assert!(
        report.contains(
            "force error against the converged reference: not measured: the scene has no fingers"
        ),
        "{report}"
    );
    assert!(!report.contains("NaN"), "{report}");
}
