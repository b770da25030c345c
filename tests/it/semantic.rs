//! Semantic constraints through the whole program: `haptloop run room`
//! (deterministic) furnishes the room as its script says, and what the
//! device renders while it does is bounded by the scene's `[semantic]` keys.
//! The algorithms themselves are tested on hand-made geometry in
//! `solver/tests/semantic/`.

use std::collections::BTreeMap;
use std::path::Path;
use std::process::Command;

use serde_json::Value;

/// The room's `[semantic]` limits (scenes/room.toml).
const SNAP_FORCE_N: f64 = 2.0;
const BREAK_FORCE_N: f64 = 2.0;
/// Its shelf's top (world z, m) and the west wall's face (world x, m).
const SHELF_TOP_M: f64 = 0.094;
const WEST_WALL_M: f64 = -0.15;

/// One run of the room on the mock clock; its output directory and stdout.
fn run_room(dir: &Path) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_haptloop"))
        .args(["run", "room", "--deterministic", "--out"])
        .arg(dir)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// `(t_s, device force)` per tick, from trace.csv (the motors' force after
/// the safety layer).
fn device_forces(dir: &Path) -> Vec<(f64, [f64; 3])> {
    let text = std::fs::read_to_string(dir.join("trace.csv")).unwrap();
    let mut lines = text.lines();
    let head: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |n: &str| head.iter().position(|h| *h == n).unwrap();
    let (t, fx) = (col("t_s"), col("force_x_n"));
    lines
        .map(|l| {
            let v: Vec<&str> = l.split(',').collect();
            let f = |k: usize| v[k].parse::<f64>().unwrap();
            (f(t), [f(fx), f(fx + 1), f(fx + 2)])
        })
        .collect()
}

/// Per body, `(t_s, position, quaternion [w, x, y, z])` from bodies.csv.
type Poses = BTreeMap<String, Vec<(f64, [f64; 3], [f64; 4])>>;

fn poses(dir: &Path) -> Poses {
    let text = std::fs::read_to_string(dir.join("bodies.csv")).unwrap();
    let mut out: Poses = BTreeMap::new();
    for l in text.lines().skip(1) {
        let v: Vec<&str> = l.split(',').collect();
        let f = |k: usize| v[k].parse::<f64>().unwrap();
        out.entry(v[1].to_owned()).or_default().push((
            f(0),
            [f(2), f(3), f(4)],
            [f(5), f(6), f(7), f(8)],
        ));
    }
    out
}

fn at(p: &[(f64, [f64; 3], [f64; 4])], t: f64) -> [f64; 3] {
    pose_at(p, t).0
}

fn pose_at(p: &[(f64, [f64; 3], [f64; 4])], t: f64) -> ([f64; 3], [f64; 4]) {
    let k = p.partition_point(|s| s.0 <= t + 1e-9).max(1) - 1;
    (p[k].1, p[k].2)
}

fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// The scripted hand furnishes the room: the events come in the script's
/// order, the grouping graph ends as the scene file says, every consistency
/// check held, and the bodies are where the constraints put them.
#[test]
fn the_room_is_furnished_as_scripted_and_felt_within_its_limits() {
    let dir = tempfile::tempdir().unwrap();
    let stdout = run_room(dir.path());
    assert!(
        stdout.contains(
            "grouping graph: floor → chair, floor → lamp, floor → table, shelf → cup, wall-west → picture"
        ),
        "{stdout}"
    );
    assert!(stdout.contains("snaps onto wall-west"), "{stdout}");

    let summary: Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("summary.json")).unwrap())
            .unwrap();
    assert_eq!(summary["safety"]["solver_failures"], 0);
    let sem = &summary["semantic"];
    let graph: Vec<(String, String)> = sem["graph"]
        .as_array()
        .unwrap()
        .iter()
        .map(|e| {
            (
                e[0].as_str().unwrap().to_owned(),
                e[1].as_str().unwrap().to_owned(),
            )
        })
        .collect();
    let want = [
        ("floor", "chair"),
        ("floor", "lamp"),
        ("floor", "table"),
        ("shelf", "cup"),
        ("wall-west", "picture"),
    ];
    assert_eq!(
        graph,
        want.map(|(a, b)| (a.to_owned(), b.to_owned())).to_vec()
    );
    let events: Vec<(f64, &str, &str, &str)> = sem["events"]
        .as_array()
        .unwrap()
        .iter()
        .map(|e| {
            (
                e["t_s"].as_f64().unwrap(),
                e["kind"].as_str().unwrap(),
                e["binding_body"].as_str().unwrap(),
                e["offer_body"].as_str().unwrap(),
            )
        })
        .collect();
    let script = [
        ("snap", "picture", "wall-west"),
        ("break", "cup", "floor"),
        ("release", "cup", "floor"),
        ("snap", "cup", "table"),
        ("group_move", "cup", "table"),
        ("break", "cup", "table"),
        ("release", "cup", "table"),
        ("snap", "cup", "shelf"),
    ];
    assert_eq!(
        events.iter().map(|e| (e.1, e.2, e.3)).collect::<Vec<_>>(),
        script.to_vec(),
        "{events:?}"
    );
    assert!(events.windows(2).all(|w| w[0].0 <= w[1].0));
    // The hand's part, printed with them: it takes hold of each object,
    // moves it and lets go.
    let other: Vec<(&str, &str, &str)> = sem["other_events"]
        .as_array()
        .unwrap()
        .iter()
        .map(|e| {
            (
                e["kind"].as_str().unwrap(),
                e["binding_body"].as_str().unwrap(),
                e["offer_body"].as_str().unwrap(),
            )
        })
        .collect();
    for body in ["picture", "cup", "table"] {
        for kind in ["hold", "move", "let_go"] {
            assert!(
                other.contains(&(kind, body, "index")),
                "no {kind} of {body}: {other:?}"
            );
        }
    }
    assert!(stdout.contains("index moves table"), "{stdout}");
    assert_eq!(
        sem["loaded"], 4,
        "table, cup, lamp and chair stand on the floor"
    );
    assert_eq!(sem["inconsistent"], 0, "{}", sem["first_inconsistency"]);
    assert!(sem["consistency_checks"].as_u64().unwrap() > events.len() as u64);
    assert_eq!(sem["pending_at_end"], 0, "every snap arrived");
    let arrival = sem["arrival_max_s"].as_f64().unwrap();
    assert!(arrival > 0.0 && arrival < 1.0, "arrival {arrival} s");

    // Where the constraints put the bodies at the end.
    let p = poses(dir.path());
    let end = summary["seconds"].as_f64().unwrap();
    let cup = at(&p["cup"], end);
    assert!(
        (cup[2] - 0.015 - SHELF_TOP_M).abs() < 2e-4,
        "the cup's bottom is {} m off the shelf",
        cup[2] - 0.015 - SHELF_TOP_M
    );
    let picture = at(&p["picture"], end);
    assert!(
        (picture[0] - 0.003 - WEST_WALL_M).abs() < 2e-4,
        "the picture's back is {} m off the wall",
        picture[0] - 0.003 - WEST_WALL_M
    );

    // Dragging the table carries the cup: while the table moves over 4 cm the cup
    // keeps its place on it to within a millimetre.
    // The hand holds the table from 5.16 s and drags it from 5.1 s to
    // 5.88 s (scenes/room.toml).
    let (drag0, drag1) = (5.1, 6.3);
    let table_moved = dist(at(&p["table"], drag0), at(&p["table"], drag1));
    assert!(table_moved > 0.04, "the table moved only {table_moved} m");
    // The cup's centre in the table's frame.
    let rel = |s: f64| {
        let c = at(&p["cup"], s);
        let (b, [w, x, y, z]) = pose_at(&p["table"], s);
        let q = nalgebra::UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(w, x, y, z));
        let v = q.inverse_transform_vector(&nalgebra::Vector3::new(
            c[0] - b[0],
            c[1] - b[1],
            c[2] - b[2],
        ));
        [v.x, v.y, v.z]
    };
    let slid = dist(rel(drag0), rel(drag1));
    assert!(slid < 1e-3, "the cup slid {slid} m on the moving table");

    // A snap is a bounded pull: from the snap until it has surely arrived,
    // the device's force stays within snap_force of what it was.
    let f = device_forces(dir.path());
    let k_at = |s: f64| f.partition_point(|x| x.0 < s - 1e-9);
    for &(ts, kind, b, o) in &events {
        let k0 = k_at(ts);
        match kind {
            "snap" => {
                let window = &f[k0..k_at(ts + arrival + 0.05)];
                let worst = window
                    .iter()
                    .map(|x| dist(x.1, f[k0].1))
                    .fold(0.0, f64::max);
                assert!(
                    worst <= SNAP_FORCE_N,
                    "snapping {b} onto {o} changed the device force by {worst} N"
                );
            }
            "break" => {
                // Felt as a release: the pull that broke it falls away.
                let peak = f[k0.saturating_sub(20)..k_at(ts + 0.02)]
                    .iter()
                    .map(|x| dist(x.1, [0.0; 3]))
                    .fold(0.0, f64::max);
                let after = dist(f[k_at(ts + 0.05)].1, [0.0; 3]);
                assert!(
                    peak > 0.9 * BREAK_FORCE_N && after < 0.5 * BREAK_FORCE_N,
                    "breaking {b} off {o}: {peak} N before, {after} N 50 ms after"
                );
            }
            _ => {}
        }
    }
}

/// A scene without semantic areas or holds has no "semantic" section.
#[test]
fn a_scene_without_semantics_reports_none() {
    let dir = tempfile::tempdir().unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_haptloop"))
        .args([
            "run",
            "four-bar",
            "--deterministic",
            "--seconds",
            "0.2",
            "--out",
        ])
        .arg(dir.path())
        .output()
        .unwrap();
    assert!(out.status.success());
    let summary: Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("summary.json")).unwrap())
            .unwrap();
    assert!(summary.get("semantic").is_none());
    assert!(!String::from_utf8_lossy(&out.stdout).contains("grouping graph"));
}
