//! `haptloop sweep`: its files and their fields, its usage errors, and
//! results that do not depend on how many threads ran them.

use haptloop::scenes::resolve;
use haptloop::sweep::{self, Grid, Options, Verdict};
use haptloop_rt::schedule::StopFlag;
use haptloop_solver::UpdateRule;
use std::process::Command;
use std::time::Duration;

fn haptloop() -> Command {
    Command::new(env!("CARGO_BIN_EXE_haptloop"))
}

/// A small sweep through the command line writes sweep.json (the fields
/// the issue names, per point), sweep.csv (one row per point) and
/// front.svg, and prints the table with its recommendation.
#[test]
fn the_cli_sweep_writes_its_files() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("sweep");
    let o = haptloop()
        .args([
            "sweep",
            "four-bar",
            "--iterations",
            "1,4",
            "--update",
            "gradient,projected",
            "--rate",
            "1000",
            "--seconds",
            "0.3",
            "--quiet",
            "--out",
        ])
        .arg(&out)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(stdout.contains("recommended: #"), "{stdout}");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("sweep.json")).unwrap()).unwrap();
    assert_eq!(json["scene"], "four-bar");
    let points = json["points"].as_array().unwrap();
    assert_eq!(points.len(), 4);
    for p in points {
        for key in [
            "iterations",
            "update",
            "gain",
            "rate_hz",
            "velocity_filter_ms",
            "failed_ticks",
            "pareto",
        ] {
            assert!(p.get(key).is_some(), "no `{key}` in {p}");
        }
        for (key, sub) in [
            ("tick_ns", ["p50", "p99"]),
            ("violation_m", ["max", "rms"]),
            ("force_error_n", ["max", "rms"]),
            ("tracking_m", ["max", "rms"]),
        ] {
            for s in sub {
                assert!(p[key][s].is_number(), "`{key}.{s}` of {p}");
            }
        }
    }
    let r = json["recommended"].as_u64().unwrap() as usize;
    assert_eq!(points[r]["update"], "projected");
    assert_eq!(points[r]["pareto"], true);
    // The figures mean what they say: grid order is iterations, then rule;
    // one gradient iteration misses the converged force by far more than
    // four projected steps, percentiles are ordered, and the front is
    // exactly the clean points no other clean point dominates in (load,
    // force error).
    let f = |p: &serde_json::Value, k: &str, s: &str| p[k][s].as_f64().unwrap();
    let (g1, p4) = (&points[0], &points[3]);
    assert_eq!(
        (g1["update"].as_str(), g1["iterations"].as_u64()),
        (Some("gradient"), Some(1))
    );
    assert_eq!(
        (p4["update"].as_str(), p4["iterations"].as_u64()),
        (Some("projected"), Some(4))
    );
    assert!(
        f(g1, "force_error_n", "max") >= 10.0 * f(p4, "force_error_n", "max"),
        "{g1} {p4}"
    );
    assert!(f(p4, "violation_m", "max") < 1e-6, "{p4}");
    let cost_acc: Vec<(f64, f64, bool)> = points
        .iter()
        .map(|p| {
            assert!(f(p, "tick_ns", "p50") <= f(p, "tick_ns", "p99"), "{p}");
            assert!(
                f(p, "force_error_n", "rms") <= f(p, "force_error_n", "max"),
                "{p}"
            );
            let clean = p["failed_ticks"].as_u64() == Some(0);
            (
                p["load"].as_f64().unwrap(),
                f(p, "force_error_n", "max"),
                clean,
            )
        })
        .collect();
    for (i, p) in points.iter().enumerate() {
        let (c, a, clean) = cost_acc[i];
        let dominated = cost_acc
            .iter()
            .any(|&(oc, oa, ok)| ok && oc <= c && oa <= a && (oc < c || oa < a));
        assert_eq!(p["pareto"].as_bool(), Some(clean && !dominated), "{p}");
    }
    let csv = std::fs::read_to_string(out.join("sweep.csv")).unwrap();
    assert_eq!(csv.lines().count(), 5);
    // The CSV holds the JSON's figures.
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    for (line, p) in csv.lines().skip(1).zip(points) {
        let cells: Vec<&str> = line.split(',').collect();
        let v: f64 = cells[col("force_error_max_n")].parse().unwrap();
        assert_eq!(v, f(p, "force_error_n", "max"));
        assert_eq!(cells[col("pareto")], p["pareto"].to_string());
    }
    let svg = std::fs::read_to_string(out.join("front.svg")).unwrap();
    assert!(svg.starts_with("<svg") && svg.contains("Pareto front"));
}

/// Bad lists are usage errors that name their flag (status 2) before
/// anything runs; an unknown scene is status 1.
#[test]
fn bad_sweep_flags_are_usage_errors_naming_the_flag() {
    for (flag, value) in [
        ("--iterations", ""),
        ("--iterations", "1,,4"),
        ("--rate", "50"),
        ("--rate", "1000,25000"),
        ("--update", "newton"),
        ("--gain", "0"),
        ("--velocity-filter-ms", "1001"),
        ("--seconds", "inf"),
        // Less than one tick at the slowest rate.
        ("--seconds", "0.001"),
    ] {
        let o = haptloop()
            .args(["sweep", "four-bar", flag, value, "--no-files"])
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(2), "{flag} {value}");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(err.contains(flag), "{flag} {value}: {err}");
    }
    let o = haptloop()
        .args(["sweep", "no-such-scene", "--no-files"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
}

/// Everything but the times is deterministic: one thread or two, the same
/// figures; a point whose gains are unstable is reported as not run, with
/// the reason, and the others still run.
#[test]
fn sweep_results_do_not_depend_on_the_thread_count() {
    let scene = resolve("four-bar").unwrap();
    let grid = Grid {
        iterations: vec![1, 4],
        update: vec![UpdateRule::Gradient, UpdateRule::Projected],
        force_solver: vec![haptloop_solver::ForceSolver::Cholesky],
        gain: vec![1000.0, 1.0],
        rate_hz: vec![1000],
        velocity_filter_ms: vec![10.0],
    };
    let run = |threads| {
        let options = Options {
            seconds: 0.3,
            reference_every: Duration::from_millis(10),
            threads,
            force_tolerance: 0.01,
        };
        sweep::run(&scene, &grid, &options, &StopFlag::new(), &|_| {}).unwrap()
    };
    let (a, b) = (run(1), run(2));
    assert_eq!(a.points.len(), 8);
    for (p, q) in a.points.iter().zip(&b.points) {
        assert_eq!(p.knobs, q.knobs);
        // Bit for bit (NaN figures included, which `==` never equates).
        assert_eq!(format!("{:?}", p.accuracy), format!("{:?}", q.accuracy));
    }
    // K = 1 with the default multiplier gain k₂ = 1000 fails the stability
    // check: not run, said why.
    let bad = a.points.iter().find(|p| p.knobs.gain == 1.0).unwrap();
    let why = bad.accuracy.as_ref().unwrap_err();
    assert!(why.contains("unstable gains"), "{why}");
    assert_eq!(bad.verdict, Verdict::NotRun);
    assert!(!bad.pareto && bad.timing.is_none());
    assert!(a.recommended.is_some());
}
