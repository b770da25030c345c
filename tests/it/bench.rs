//! `haptloop bench` and the per-stage tick timing behind it: the JSON it
//! writes, figures that add up, real compute time in deterministic runs, and
//! clear errors for bad input. Structure and consistency only: speed belongs
//! to benches/ and BENCHMARKS.md.

use haptloop::report::summary::Summary;
use haptloop::scenes::resolve;
use haptloop::session::{self, Plan, SessionOptions, Stage};
use haptloop_rt::schedule::StopFlag;
use std::process::Command;

fn haptloop() -> Command {
    Command::new(env!("CARGO_BIN_EXE_haptloop"))
}

/// `haptloop bench SCENE --ticks N --json FILE` (in `dir`), which must
/// succeed: its printed report and its JSON.
fn bench_json(scene: &str, ticks: u32, dir: &std::path::Path) -> (String, serde_json::Value) {
    let json = dir.join(format!("{scene}.json"));
    let out = haptloop()
        .args(["bench", scene, "--ticks", &ticks.to_string(), "--json"])
        .arg(&json)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).expect("valid JSON");
    (String::from_utf8_lossy(&out.stdout).into_owned(), v)
}

#[test]
fn bench_writes_every_figure_and_they_add_up() {
    let dir = tempfile::tempdir().unwrap();
    let (text, v) = bench_json("four-bar", 300, dir.path());
    for label in ["tick w/o device", "force (Eq. 7)", "constraint violation"] {
        assert!(text.contains(label), "{text}");
    }
    assert_eq!(v["scene"], "four-bar");
    assert_eq!(v["ticks"], 300);
    let keys = ["p50", "p99", "p999", "max"];
    for figure in ["tick_ns", "tick_without_device_ns"] {
        for k in keys {
            assert!(v[figure][k].as_u64().is_some(), "{figure}.{k}");
        }
    }
    let q = |f: &serde_json::Value, k: &str| f[k].as_u64().unwrap();
    let (tick, without) = (&v["tick_ns"], &v["tick_without_device_ns"]);
    assert!(
        q(tick, "p50") > 0,
        "a tick takes time even on the mock clock"
    );
    assert!(q(without, "max") <= q(tick, "max"));
    assert!(q(tick, "p50") <= q(tick, "p99") && q(tick, "p99") <= q(tick, "max"));
    for s in Stage::ALL {
        let st = &v["stages"][s.key()];
        for k in keys {
            assert!(st[k].as_u64().is_some(), "stages.{}.{k}", s.key());
        }
        assert!(q(st, "max") <= q(tick, "max"), "{}", s.key());
    }
    // The solver stages run every tick and take time.
    for s in ["update", "evaluation", "force"] {
        assert!(q(&v["stages"][s], "p50") > 0, "{s}");
    }
    let viol = v["violation"]["max"].as_f64().unwrap();
    assert!(viol.is_finite() && viol < 1e-6, "{viol}");
    assert!(v["violation"]["rms"].as_f64().unwrap() <= viol);
}

/// `run --deterministic` reports the monotonic clock's compute time, not the
/// mock clock's zeros, and the stage figures cover every tick.
#[test]
fn deterministic_runs_report_real_compute_time_per_stage() {
    let scene = resolve("stewart").unwrap();
    let options = SessionOptions {
        seconds: 0.3,
        deterministic: true,
        ..SessionOptions::default()
    };
    let plan = Plan::new(&scene, &options).unwrap();
    let o = session::run(&scene, plan, &StopFlag::new(), &mut |_| {}).unwrap();
    let s = Summary::of(&o);
    assert!(s.compute_ns.p50 > 0 && s.compute_ns == s.stages_ns.tick);
    assert_eq!(o.stats.stages.tick.count(), o.stats.ticks);
    for stage in Stage::ALL {
        assert_eq!(o.stats.stages.stage(stage).count(), o.stats.ticks);
    }
    // The scheduler's own compute histogram follows the mock clock.
    assert_eq!(o.report.compute_ns.max, 0);
    assert!(s.slow_loop.step_ns.max > 0);
}

#[test]
fn bench_refuses_bad_input_with_a_clear_error() {
    let cases: [(&[&str], i32, &str); 4] = [
        (&["bench", "four-bar", "--ticks", "0"], 2, "--ticks"),
        (&["bench", "four-bar", "--rate", "5"], 2, "--rate"),
        (&["bench", "no-such-scene"], 1, "not a built-in scene"),
        (
            &["bench", "four-bar", "--json", "/no/such/dir/x.json"],
            1,
            "cannot write",
        ),
    ];
    for (args, code, says) in cases {
        let out = haptloop().args(args).output().unwrap();
        assert_eq!(out.status.code(), Some(code), "{args:?}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(says), "{args:?}: {err}");
    }
}

/// `bench` takes `run`'s solver flags, and a scene file as well as a built-in
/// name: with the same flags its session is `run --deterministic`'s (the
/// same violation to the bit, from two processes), the JSON records the
/// settings used, and the flags change the result.
#[test]
fn bench_takes_the_solver_flags_and_scene_files() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("my-bennett.toml");
    std::fs::write(
        &file,
        haptloop::scenes::BUILTIN
            .iter()
            .find(|b| b.name == "bennett")
            .unwrap()
            .text,
    )
    .unwrap();
    let flags = [
        "--update",
        "gradient",
        "--iterations",
        "3",
        "--gain",
        "500",
        "--velocity-filter-ms",
        "5",
    ];
    let bench = |extra: &[&str], name: &str| -> serde_json::Value {
        let json = dir.path().join(name);
        let out = haptloop()
            .args(["bench", file.to_str().unwrap(), "--ticks", "400", "--json"])
            .arg(&json)
            .args(extra)
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap()
    };
    let flagged = bench(&flags, "flagged.json");
    assert_eq!(flagged["scene"], "bennett");
    assert_eq!(flagged["update"], "gradient");
    assert_eq!(flagged["iterations"], 3);
    assert_eq!(flagged["gain"], 500.0);
    assert_eq!(flagged["velocity_filter_ms"], 5.0);
    let plain = bench(&[], "plain.json");
    assert_eq!(plain["update"], "projected");
    let (vf, vp) = (
        flagged["violation"]["max"].as_f64().unwrap(),
        plain["violation"]["max"].as_f64().unwrap(),
    );
    assert_ne!(vf, vp, "the flags changed nothing");
    let run_dir = dir.path().join("run");
    let out = haptloop()
        .args([
            "run",
            file.to_str().unwrap(),
            "--deterministic",
            "--seconds",
            "0.4",
            "--quiet",
            "--out",
        ])
        .arg(&run_dir)
        .args(flags)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(run_dir.join("summary.json")).unwrap())
            .unwrap();
    assert_eq!(summary["violation"]["max"].as_f64(), Some(vf));
    // Bad values are usage errors naming the flag.
    for (flag, value) in [
        ("--update", "sideways"),
        ("--gain", "0"),
        ("--velocity-filter-ms", "2000"),
    ] {
        let out = haptloop()
            .args(["bench", "bennett", flag, value])
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(2), "{flag} {value}");
        assert!(
            String::from_utf8_lossy(&out.stderr).contains(flag),
            "{flag}"
        );
    }
}

/// A contact scene has no joint rows: bench says so, as `run` does, and
/// never prints NaN for the violation it has no rows to measure (it printed
/// "max NaN m, NaN rad"); a joint scene keeps its three figures.
#[test]
fn bench_says_why_a_scene_has_no_violation_figure() {
    let dir = tempfile::tempdir().unwrap();
    let (text, v) = bench_json("stack", 50, dir.path());
    assert!(!text.contains("NaN"), "{text}");
    assert!(
        text.contains(
            "constraint violation: none: the scene has no joint rows to violate; solver failures: 0"
        ),
        "{text}"
    );
    assert!(v["violation"]["max"].is_null(), "{}", v["violation"]);
    assert!(
        v["violation"]["verdict"]
            .as_str()
            .unwrap()
            .starts_with("none")
    );
    let joints = haptloop()
        .args(["bench", "four-bar", "--ticks", "50"])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&joints.stdout);
    let line = text
        .lines()
        .find(|l| l.starts_with("constraint violation: max "))
        .unwrap_or_else(|| panic!("{text}"));
    let max: f64 = line["constraint violation: max ".len()..]
        .split(' ')
        .next()
        .unwrap()
        .parse()
        .unwrap();
    assert!(max.is_finite() && max < 1e-6, "{line}");
}
