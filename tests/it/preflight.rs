//! `check` tries what `run` will meet and says where to change it, and a
//! run's report warns when the device could not render what the scene
//! asked (a workspace stop, the peak-force clamp, the thermal cut).

use haptloop::scenes::BUILTIN;
use haptloop_devices::PREMIUM_1_5;
use std::path::{Path, PathBuf};
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

/// `text` with `from` replaced (which must be there), written to `dir/name`.
fn edited(dir: &Path, name: &str, text: &str, from: &str, to: &str) -> PathBuf {
    assert!(text.contains(from), "{from}");
    let path = dir.join(name);
    std::fs::write(&path, text.replacen(from, to, 1)).unwrap();
    path
}

/// 1-based line of the first line of `path` that starts with `prefix`.
fn line_of(path: &Path, prefix: &str) -> usize {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .position(|l| l.starts_with(prefix))
        .unwrap()
        + 1
}

/// A four-bar whose coupler is 0.45 m too long cannot close: `check` says
/// the assembly ends in LeastSquares with its residual and the rows that
/// conflict, at the first joint among them (it used to print "ok").
#[test]
fn check_names_the_rows_of_an_assembly_that_cannot_close() {
    let dir = tempfile::tempdir().unwrap();
    let path = edited(
        dir.path(),
        "open.toml",
        builtin("four-bar"),
        "-0.049749371855331]",
        "-0.5]",
    );
    let o = haptloop()
        .args(["check", "--seconds", "0.2"])
        .arg(&path)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(3), "{}", text(&o));
    let err = String::from_utf8_lossy(&o.stderr);
    let at = format!(
        "{}:{}:8: warning: the assembly ends in LeastSquares: residual ",
        path.display(),
        line_of(&path, "name = \"crank-coupler\"")
    );
    assert!(err.contains(&at), "{}", text(&o));
    assert!(err.contains("`crank-coupler` row 0 ("), "{}", text(&o));
    // The residual it prints is the one `run` reports for its assembly.
    let run = haptloop()
        .args([
            "run",
            "--deterministic",
            "--seconds",
            "0.01",
            "--no-files",
            "--quiet",
        ])
        .arg(&path)
        .output()
        .unwrap();
    let report = String::from_utf8_lossy(&run.stdout);
    let residual = report
        .split("LeastSquares after ")
        .nth(1)
        .and_then(|r| r.split("residual ").nth(1))
        .and_then(|r| r.split(' ').next())
        .unwrap_or_else(|| panic!("{report}"));
    assert!(
        err.contains(&format!("residual {residual} m")),
        "{err}\n{report}"
    );
}

/// Bodies that start inside each other are refused by `check` and `run`
/// alike, at the second body's `position` (a contact scene used to accept
/// them and back up 200 times; only scenes with semantic areas refused).
#[test]
fn bodies_that_start_inside_each_other_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let path = edited(
        dir.path(),
        "sunk.toml",
        builtin("box-slide"),
        "position = [0.0, 0.0, 0.03]",
        "position = [0.0, 0.0, 0.025]",
    );
    let o = haptloop().arg("check").arg(&path).output().unwrap();
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    let at = format!(
        "{}:{}:12: the scene loads but cannot run: ",
        path.display(),
        line_of(&path, "position = [0.0, 0.0, 0.025]")
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.starts_with(&at), "{}", text(&o));
    // The box's bottom is 5 mm below the table's top.
    assert!(
        err.contains("bodies `table` and `box` interpenetrate by 5.000e-3 m"),
        "{err}"
    );
    let run = haptloop()
        .args([
            "run",
            "--deterministic",
            "--seconds",
            "0.1",
            "--no-files",
            "--quiet",
        ])
        .arg(&path)
        .output()
        .unwrap();
    assert_eq!(run.status.code(), Some(1), "{}", text(&run));
}

/// A hand circle of 10 cm radius leaves the Premium's workspace box and
/// asks for more than its peak force: `check` warns of both at the fields
/// to change; the run's report warns that the arm sat at a workspace stop
/// (as many ticks as its trace shows the tip outside the box) and
/// saturated (as many ticks as the device's clamp counted).
#[test]
fn a_hand_path_beyond_the_workspace_is_found_before_and_warned_after() {
    let dir = tempfile::tempdir().unwrap();
    let path = edited(
        dir.path(),
        "wide.toml",
        builtin("four-bar"),
        "radius = 0.01,",
        "radius = 0.1,",
    );
    let o = haptloop()
        .args(["check", "--seconds", "0.5"])
        .arg(&path)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(3), "{}", text(&o));
    let err = String::from_utf8_lossy(&o.stderr);
    let hand = format!(
        "{}:{}:8: warning: device `right`: the hand's path leaves the phantom-premium-1.5's workspace box",
        path.display(),
        line_of(&path, "hand = ")
    );
    assert!(err.contains(&hand), "{}", text(&o));
    assert!(
        err.contains("above the phantom-premium-1.5's 8.5 N peak force"),
        "{}",
        text(&o)
    );
    let out = dir.path().join("run");
    let run = haptloop()
        .args([
            "run",
            "--deterministic",
            "--seconds",
            "2",
            "--quiet",
            "--out",
        ])
        .arg(&out)
        .arg(&path)
        .output()
        .unwrap();
    let report = String::from_utf8_lossy(&run.stdout);
    assert!(
        report
            .contains("WARNING: device `right` (phantom-premium-1.5) sat at a workspace stop on "),
        "{report}"
    );
    assert!(
        report.contains("WARNING: device `right` (phantom-premium-1.5) saturated on "),
        "{report}"
    );
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let limits = &summary["device_limits"][0];
    let outside = limits["outside_workspace_ticks"].as_u64().unwrap();
    // The trace's targets are the device's tip in the scene: registration
    // put the home pose (tip 0, within a count) on the finger's first
    // point, so target − that point is the tip in the device frame.
    let scene = haptloop::scenes::resolve(path.to_str().unwrap()).unwrap();
    let m = &scene.compiled.model;
    let finger0 = m
        .finger_point(m.q0(), haptloop_solver::FingerId(0))
        .unwrap();
    let half = PREMIUM_1_5.workspace_half_extent_m;
    let trace = std::fs::read_to_string(out.join("trace.csv")).unwrap();
    let (mut beyond, mut well_beyond) = (0, 0);
    for row in trace.lines().skip(1) {
        let f: Vec<f64> = row
            .split(',')
            .skip(2)
            .take(3)
            .map(|v| v.parse().unwrap())
            .collect();
        let excess = (0..3)
            .map(|i| (f[i] - finger0[i]).abs() - half[i])
            .fold(f64::NEG_INFINITY, f64::max);
        beyond += usize::from(excess > -1e-4);
        well_beyond += usize::from(excess > 1e-4);
    }
    assert!(
        well_beyond > 100 && well_beyond as u64 <= outside && outside <= beyond as u64,
        "counted {outside}, the trace shows {well_beyond}–{beyond}"
    );
}

/// A 2 kg weight on one finger asks for 19.6 N of a Premium: clamped to
/// 8.5 N, and the thermal model cuts it to the 1.4 N continuous rating
/// after about half a second. The report warns of both next to "0 force
/// cuts by the session" (it used to say "0 force cuts" and nothing else),
/// and the thermal count is the number of ticks the trace shows at exactly
/// 1.4 N.
#[test]
fn the_report_warns_of_the_thermal_cut_and_the_clamp() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("heavy.toml");
    std::fs::write(
        &path,
        "[scene]\nname = \"heavy\"\ndescription = \"a 2 kg weight on one finger\"\n\
         gravity = [0.0, 0.0, -9.81]\n\n[[device]]\nname = \"right\"\nmodel = \"phantom-premium-1.5\"\n\n\
         [[body]]\nname = \"weight\"\nmass = 2.0\n\n\
         [[finger]]\nname = \"index\"\ndevice = \"right\"\nbody = \"weight\"\n",
    )
    .unwrap();
    let out = dir.path().join("run");
    let run = haptloop()
        .args([
            "run",
            "--deterministic",
            "--seconds",
            "2",
            "--quiet",
            "--out",
        ])
        .arg(&out)
        .arg(&path)
        .output()
        .unwrap();
    assert_eq!(run.status.code(), Some(0), "{}", text(&run));
    let report = String::from_utf8_lossy(&run.stdout);
    assert!(
        report.contains("safety: 0 force cuts by the session"),
        "{report}"
    );
    assert!(
        report.contains(
            "WARNING: device `right` (phantom-premium-1.5) was cut by its thermal model on "
        ),
        "{report}"
    );
    assert!(report.contains("saturated on "), "{report}");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let thermal = summary["device_limits"][0]["thermal_cut_ticks"]
        .as_u64()
        .unwrap();
    let trace = std::fs::read_to_string(out.join("trace.csv")).unwrap();
    let at_rating = trace
        .lines()
        .skip(1)
        .filter(|row| {
            let f: Vec<f64> = row
                .split(',')
                .skip(8)
                .take(3)
                .map(|v| v.parse().unwrap())
                .collect();
            ((f[0] * f[0] + f[1] * f[1] + f[2] * f[2]).sqrt() - PREMIUM_1_5.continuous_force_n)
                .abs()
                < 1e-9
        })
        .count();
    assert!(thermal > 100, "{thermal} ticks");
    assert_eq!(thermal, at_rating as u64);
    // `check` finds it before the run.
    let o = haptloop().arg("check").arg(&path).output().unwrap();
    assert_eq!(o.status.code(), Some(3), "{}", text(&o));
    assert!(
        String::from_utf8_lossy(&o.stderr).contains("cut by the thermal model on "),
        "{}",
        text(&o)
    );
}

/// A scene whose tick cannot fit its period: the lattice (a few hundred µs
/// a tick on any machine) asked to run at 20 kHz (a 50 µs period). `check`
/// warns at `[solver]` with the trial's median tick and the period, and
/// exits 3; a cheap scene (the four-bar, tens of µs a tick) at 1 kHz is not
/// warned about.
#[test]
fn check_warns_when_the_tick_cannot_fit_the_period() {
    let dir = tempfile::tempdir().unwrap();
    let path = edited(
        dir.path(),
        "fast.toml",
        builtin("lattice"),
        "[solver]\n",
        "[solver]\nrate_hz = 20000\n",
    );
    let o = haptloop()
        .args(["check", "--seconds", "0.05"])
        .arg(&path)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(3), "{}", text(&o));
    let err = String::from_utf8_lossy(&o.stderr);
    let at = format!(
        "{}:{}:1: warning: in a 0.05 s trial the tick costs ",
        path.display(),
        line_of(&path, "[solver]")
    );
    assert!(err.contains(&at), "{}", text(&o));
    let median: f64 = err[err.find(&at).unwrap() + at.len()..]
        .split(' ')
        .next()
        .unwrap()
        .parse()
        .unwrap();
    assert!(median > 100.0, "a 50 µs period warned at {median} µs");
    assert!(
        err.contains("over twice the 50 µs period at 20000 Hz"),
        "{}",
        text(&o)
    );
    let own = haptloop()
        .args(["check", "--seconds", "0.05", "four-bar"])
        .output()
        .unwrap();
    let own_err = String::from_utf8_lossy(&own.stderr);
    assert!(!own_err.contains("the tick costs"), "{}", text(&own));
}
