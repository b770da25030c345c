//! Design variables switched on and off during a run (Nelson & Cohen §3's
//! flags): from the scene's `[[design_flag]]` schedule and from
//! `--design-off` / `--design-on`. A switched-off variable stays exactly
//! where it was at the switch while the others keep moving, moves again when
//! switched back on, and the fast tick that switches allocates nothing.

use crate::mock_session::MockSession;
use haptloop::report::summary::Summary;
use haptloop::scenes::{BUILTIN, Scene, check_loaded};
use haptloop::session::{self, Plan, SessionOptions, SessionOutcome};
use haptloop_rt::alloc::count;
use haptloop_rt::schedule::StopFlag;
use haptloop_solver::scene;

fn deterministic(seconds: f64) -> SessionOptions {
    SessionOptions {
        seconds,
        deterministic: true,
        ..SessionOptions::default()
    }
}

/// `stewart-feet` with `extra` appended to its text.
fn feet_with(extra: &str) -> Result<Scene, String> {
    let base = BUILTIN.iter().find(|b| b.name == "stewart-feet").unwrap();
    let text = format!("{}\n{extra}", base.text);
    let loaded = scene::parse("feet-flags.toml", &text, None).map_err(|e| e.to_string())?;
    check_loaded(loaded).map_err(|e| e.to_string())
}

fn scene_without_flags() -> Scene {
    feet_with("").unwrap()
}

/// The recorded series of design column `name`: (t, value).
fn series<'a>(o: &'a SessionOutcome, name: &str) -> &'a [(f64, f64)] {
    let k = o
        .recorder
        .design_names
        .iter()
        .position(|n| n == name)
        .unwrap_or_else(|| panic!("no design column {name}"));
    &o.recorder.design_series[k].points
}

/// The spread (max − min) of `points` with t in [from, to).
fn spread(points: &[(f64, f64)], from: f64, to: f64) -> f64 {
    let v: Vec<f64> = points
        .iter()
        .filter(|p| p.0 >= from && p.0 < to)
        .map(|p| p.1)
        .collect();
    assert!(v.len() > 10, "too few samples in [{from}, {to})");
    let max = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let min = v.iter().copied().fold(f64::INFINITY, f64::min);
    max - min
}

/// The scene's schedule: foot 1 is switched off at 0.5 s and on again at
/// 1.5 s. Between the two its position is bit-for-bit constant while foot 2
/// (same objective, same hands) keeps sliding; before and after, foot 1
/// moves too, and without the schedule it slides between 0.5 and 1.5 s as
/// well. The joints stay within the scene's tolerance throughout.
#[test]
fn a_scheduled_switch_holds_one_variable_while_the_others_move() {
    let scene = feet_with(
        "[[design_flag]]\nat = 0.5\noff = [\"foot1.position\"]\n\n\
         [[design_flag]]\nat = 1.5\non = [\"foot1.position\"]\n",
    )
    .unwrap();
    let flags = &scene.compiled.design_flags;
    assert_eq!(flags.len(), 2);
    assert!(!flags[0].on && flags[1].on && flags[0].at_s == 0.5);
    let o = session::run(
        &scene,
        Plan::new(&scene, &deterministic(2.5)).unwrap(),
        &StopFlag::new(),
        &mut |_| {},
    )
    .unwrap();
    // The same hands without the schedule: foot 1 slides between 0.5 and
    // 1.5 s, so holding it is the flag's doing.
    let plain = scene_without_flags();
    let free = session::run(
        &plain,
        Plan::new(&plain, &deterministic(1.5)).unwrap(),
        &StopFlag::new(),
        &mut |_| {},
    )
    .unwrap();
    let s = Summary::of(&o);
    let tol = s.violation.tolerance.unwrap();
    assert!(
        s.violation.max <= tol && s.safety.solver_failures == 0,
        "violation {:e} (tolerance {tol:e}), {} failed ticks",
        s.violation.max,
        s.safety.solver_failures
    );
    for axis in ["x", "y"] {
        let held = series(&o, &format!("foot1.position.{axis}_m"));
        let other = series(&o, &format!("foot2.position.{axis}_m"));
        // Samples are stamped with the tick's start; the switch applies
        // before the first tick at or after 0.5 s, so from 0.5 s on the
        // value is the one the tick before left.
        let off = spread(held, 0.5, 1.5);
        assert_eq!(off, 0.0, "foot1.{axis} moved by {off:e} m while off");
        let unflagged = spread(series(&free, &format!("foot1.position.{axis}_m")), 0.5, 1.5);
        assert!(
            unflagged > 1e-3,
            "foot1.{axis} moved only {unflagged:e} m unflagged"
        );
        let moving = spread(other, 0.5, 1.5);
        assert!(moving > 1e-3, "foot2.{axis} moved only {moving:e} m");
        let before = spread(held, 0.0, 0.5);
        let after = spread(held, 1.5, 2.5);
        assert!(
            before > 5e-4 && after > 5e-4,
            "foot1.{axis} did not move while on: {before:e} m before, {after:e} m after"
        );
    }
}

/// `--design-off` on the command line: foot 0, the one the second hand
/// drags through its puck, stays where it starts (summary.json's min, max
/// and end of each component equal its start, the scene's position to the
/// initial assembly's round-off) while
/// the other feet slide; a bad switch is a usage error naming the flag.
#[test]
fn the_cli_switches_a_variable_off_and_names_a_bad_switch() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    let haptloop = || std::process::Command::new(env!("CARGO_BIN_EXE_haptloop"));
    let args = [
        "run",
        "stewart-feet",
        "--deterministic",
        "--seconds",
        "1.0",
        "--quiet",
    ];
    let r = haptloop()
        .args(args)
        .args(["--design-off", "foot0.position@0"])
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let s: Summary =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let start = [0.09659258262890684, -0.025881904510252074, 0.0];
    for (axis, x0) in ["x", "y", "z"].iter().zip(start) {
        let f = &s.design[&format!("foot0.position.{axis}")];
        // Exactly constant; the start is the scene's position to the
        // initial assembly's round-off.
        assert!(
            f.min == f.start
                && f.max == f.start
                && f.end == f.start
                && (f.start - x0).abs() < 1e-15,
            "foot0.{axis} switched off from 0 s: {f:?}"
        );
    }
    let moved = (1..6)
        .filter(|k| {
            let f = &s.design[&format!("foot{k}.position.y")];
            f.max - f.min > 1e-4
        })
        .count();
    assert!(moved >= 3, "only {moved} of the other feet moved");

    let cases = [
        (
            vec!["--design-off", "foot9.position@1"],
            "--design-off:1:1: `foot9.position` is not a design variable (free: foot0.position",
        ),
        (
            vec!["--design-on", "foot1.position@-1"],
            "--design-on:1:16: -1 s: expected a finite time ≥ 0",
        ),
        (
            vec!["--design-off", "foot1.position"],
            "--design-off:1:1: expected NAME@SECONDS",
        ),
    ];
    for (flags, expected) in cases {
        let r = haptloop().args(args).args(&flags).output().unwrap();
        let err = String::from_utf8_lossy(&r.stderr);
        assert_eq!(r.status.code(), Some(2), "{flags:?}: {err}");
        assert!(err.starts_with(expected), "{flags:?}: {err}");
    }
}

/// Bad `[[design_flag]]` tables are refused with the file, line and column
/// of what is wrong.
#[test]
fn bad_design_flag_tables_name_what_is_wrong() {
    let cases = [
        (
            "[[design_flag]]\nat = -1.0\noff = [\"foot1.position\"]\n",
            "expected a session time in seconds, finite and ≥ 0",
        ),
        (
            "[[design_flag]]\nat = 1.0\n",
            "a design flag switches nothing",
        ),
        (
            "[[design_flag]]\nat = 1.0\noff = [\"foot7.position\"]\n",
            "`foot7.position` is not a design variable (free: foot0.position",
        ),
        (
            "[[design_flag]]\nat = 1.0\noff = [\"foot1.position\"]\non = [\"foot1.position\"]\n",
            "`foot1.position` is switched both on and off at 1 s",
        ),
    ];
    let lines = BUILTIN
        .iter()
        .find(|b| b.name == "stewart-feet")
        .unwrap()
        .text
        .lines()
        .count();
    for (extra, expected) in cases {
        let Err(e) = feet_with(extra) else {
            panic!("loaded: {extra}");
        };
        assert!(e.contains(expected), "{extra}: {e}");
        // The error points into the appended table, not elsewhere.
        assert!(
            (lines + 2..=lines + 5).any(|l| e.contains(&format!("feet-flags.toml:{l}:"))),
            "{extra}: {e}"
        );
    }
}

/// The fast loop's tick allocates nothing on the ticks that switch design
/// variables off and on (the schedule is a cursor over a list built before
/// the run), and the switches took effect.
#[test]
fn the_fast_tick_that_switches_allocates_nothing() {
    let scene = feet_with(
        "[[design_flag]]\nat = 0.3\noff = [\"foot1.position\", \"foot4.position\"]\n\n\
         [[design_flag]]\nat = 0.6\non = [\"foot4.position\"]\n",
    )
    .unwrap();
    let mut m = MockSession::new(&scene, &deterministic(2.0));
    m.run(200);
    let index = |name: &str| {
        let vars = scene.compiled.model.layout().design_vars();
        vars.iter().position(|d| d.name == name).unwrap()
    };
    let (f1, f4) = (index("foot1.position"), index("foot4.position"));
    assert!(m.built.fast.program().design_active(f1));
    let (_, stats) = count(|| {
        for _ in 0..8 {
            m.run(100);
            while m.built.trace.pop().is_some() {}
        }
    });
    assert_eq!(stats.total(), 0, "the fast loop allocated: {stats:?}");
    assert_eq!(m.built.fast.stats().ticks, 1000);
    let p = m.built.fast.program();
    assert!(!p.design_active(f1), "foot1 was not switched off");
    assert!(p.design_active(f4), "foot4 was not switched back on");
}
