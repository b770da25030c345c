//! Gösele & Stuerzlinger §3.3 and §6 through a whole session: the
//! `board-wall` scene (Fig. 5/6) adds a lamp, switches to the unconstrained
//! mode while the hand holds the cup and back, and removes the table. The
//! counts of objects and constraints, where the added lamp lands (a closed
//! form), what the hand feels with the constraints off and on (the same
//! hand path with the mode entries taken out), the fast tick's allocations
//! across the add and the remove, and the errors of bad schedules.

use std::path::Path;
use std::process::Command;

use haptloop::report::summary::Summary;
use haptloop::scenes::{BUILTIN, check_loaded, resolve};
use haptloop::session::{self, Plan, SessionOptions};
use haptloop_rt::alloc::count;
use haptloop_rt::clock::{MockClock, Nanos};
use haptloop_rt::schedule::{Periodic, RunLimit, StopFlag};
use haptloop_solver::scene;

/// The cup's centre on the table (m) and the hand's lift while unconstrained.
const CUP_ON_TABLE_Z: f64 = 0.075;
const LIFT_M: f64 = 0.005;

fn text() -> &'static str {
    BUILTIN
        .iter()
        .find(|b| b.name == "board-wall")
        .unwrap()
        .text
}

/// Runs `scene` (a built-in name or a file) for 3.2 s on the mock clock.
fn run(scene: &str, dir: &Path) -> Summary {
    let out = Command::new(env!("CARGO_BIN_EXE_haptloop"))
        .args([
            "run",
            scene,
            "--deterministic",
            "--seconds",
            "3.2",
            "--quiet",
            "--out",
        ])
        .arg(dir)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap()
}

/// `(t, [x, y, z])` of body `name` from bodies.csv.
fn track(dir: &Path, name: &str) -> Vec<(f64, [f64; 3])> {
    let text = std::fs::read_to_string(dir.join("bodies.csv")).unwrap();
    text.lines()
        .skip(1)
        .filter_map(|l| {
            let v: Vec<&str> = l.split(',').collect();
            let f = |k: usize| v[k].parse::<f64>().unwrap();
            (v[1] == name).then(|| (f(0), [f(2), f(3), f(4)]))
        })
        .collect()
}

/// The mean vertical device force on the hand over [from, to) s.
fn mean_fz(dir: &Path, from: f64, to: f64) -> f64 {
    let text = std::fs::read_to_string(dir.join("trace.csv")).unwrap();
    let mut lines = text.lines();
    let head: Vec<&str> = lines.next().unwrap().split(',').collect();
    let (t, fz) = (
        head.iter().position(|h| *h == "t_s").unwrap(),
        head.iter().position(|h| *h == "force_z_n").unwrap(),
    );
    let v: Vec<f64> = lines
        .map(|l| l.split(',').collect::<Vec<_>>())
        .filter(|v| {
            let s: f64 = v[t].parse().unwrap();
            s >= from && s < to
        })
        .map(|v| v[fz].parse().unwrap())
        .collect();
    assert!(v.len() > 100);
    v.iter().sum::<f64>() / v.len() as f64
}

/// The cup's z over [from, to): (min, max).
fn z_range(p: &[(f64, [f64; 3])], from: f64, to: f64) -> (f64, f64) {
    p.iter()
        .filter(|s| s.0 >= from && s.0 < to)
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), s| {
            (lo.min(s.1[2]), hi.max(s.1[2]))
        })
}

#[test]
fn board_wall_adds_switches_modes_and_removes_consistently() {
    let tmp = tempfile::tempdir().unwrap();
    let (free_dir, held_dir) = (tmp.path().join("modes"), tmp.path().join("constrained"));
    let s = run("board-wall", &free_dir);
    assert_eq!(s.safety.solver_failures, 0);
    let sem = s.semantic.as_ref().unwrap();
    assert_eq!(
        (sem.adds, sem.removes, sem.add_failures, sem.inconsistent),
        (1, 1, 0, 0)
    );
    assert!(sem.consistency_checks >= 9);
    // 5 constraints at load (partition, table on the floor; board on the
    // table and the partition; cup on the table); the lamp adds one, the
    // table's removal takes its own and the two on its top: 3. Of the six
    // shaped objects five remain.
    assert_eq!(sem.loaded, 5);
    assert_eq!((sem.objects_at_end, sem.constraints_at_end), (5, 3));
    assert_eq!(sem.mode_at_end, "constrained");
    let graph: Vec<[&str; 2]> = sem
        .graph
        .iter()
        .map(|[a, b]| [a.as_str(), b.as_str()])
        .collect();
    assert_eq!(
        graph,
        [
            ["floor", "lamp"],
            ["floor", "partition"],
            ["partition", "board"]
        ]
    );
    let events: Vec<(f64, &str, &str, &str)> = sem
        .events
        .iter()
        .map(|e| {
            (
                e.t_s,
                e.kind.as_str(),
                e.binding_body.as_str(),
                e.offer_body.as_str(),
            )
        })
        .collect();
    assert_eq!(
        events,
        [
            (0.3, "add", "lamp", "floor"),
            (0.8, "release", "cup", "table"),
            (1.8, "snap", "cup", "table"),
            (2.8, "remove", "table", ""),
            (2.8, "release", "board", "table"),
            (2.8, "release", "cup", "table"),
        ]
    );
    // The lamp, declared where the table stands (centre y = 0.055, the
    // table's front at y = 0.015, the lamp 0.015 half wide), lands at the
    // nearest clear spot: y = 0, on the floor (z = its half height).
    let lamp = track(&free_dir, "lamp");
    let end = lamp.last().unwrap().1;
    assert!(
        end[0].abs() < 1e-9 && end[1].abs() < 1e-6 && (end[2] - 0.04).abs() < 1e-12,
        "lamp at {end:?}"
    );
    // The removed table stays where it was (out of the scene); the board
    // stays on the partition.
    let board = track(&free_dir, "board");
    let (b0, b1) = (board[0].1, board.last().unwrap().1);
    assert!(
        (0..3).all(|k| (b0[k] - b1[k]).abs() < 1e-9),
        "{b0:?} → {b1:?}"
    );

    // Unconstrained (0.8–1.8 s): the cup follows the hand 5 mm up with no
    // binding force; constrained again it is back on the table.
    let cup = track(&free_dir, "cup");
    let (lo, hi) = z_range(&cup, 1.55, 1.8);
    assert!(
        (lo - CUP_ON_TABLE_Z - LIFT_M).abs() < 5e-4 && (hi - CUP_ON_TABLE_Z - LIFT_M).abs() < 5e-4,
        "cup z {lo}–{hi}"
    );
    let (lo, hi) = z_range(&cup, 2.1, 2.8);
    assert!(
        (lo - CUP_ON_TABLE_Z).abs() < 1e-9 && (hi - CUP_ON_TABLE_Z).abs() < 1e-9,
        "cup z after the snap {lo}–{hi}"
    );
    let free_fz = mean_fz(&free_dir, 1.55, 1.8);

    // The same hand without the mode entries: the cup stays bound, the hand
    // feels the surface row hold it down.
    let constrained = text()
        .replace("[[schedule]]\nat = 0.8\nmode = \"unconstrained\"\n\n", "")
        .replace("[[schedule]]\nat = 1.8\nmode = \"constrained\"\n\n", "");
    assert_ne!(constrained, text());
    let file = tmp.path().join("board-wall-constrained.toml");
    std::fs::write(&file, constrained).unwrap();
    let s2 = run(file.to_str().unwrap(), &held_dir);
    assert_eq!(s2.semantic.as_ref().unwrap().inconsistent, 0);
    let (lo, hi) = z_range(&track(&held_dir, "cup"), 1.55, 1.8);
    assert!(
        (lo - CUP_ON_TABLE_Z).abs() < 1e-9 && (hi - CUP_ON_TABLE_Z).abs() < 1e-9,
        "constrained cup z {lo}–{hi}"
    );
    let held_fz = mean_fz(&held_dir, 1.55, 1.8);
    assert!(
        free_fz.abs() < 0.01 && held_fz < -0.2,
        "mean Fz on the hand: {free_fz} N unconstrained, {held_fz} N constrained"
    );
}

/// The fast tick allocates nothing across the add (0.3 s) and the remove
/// (2.8 s): the slow loop steps between chunks of five ticks (outside the
/// count) and hands over the programs; the counts after each are checked.
#[test]
fn the_fast_tick_allocates_nothing_across_an_add_and_a_remove() {
    let scene = resolve("board-wall").unwrap();
    let options = SessionOptions {
        seconds: 3.0,
        deterministic: true,
        ..SessionOptions::default()
    };
    let plan = Plan::new(&scene, &options).unwrap();
    let clock = MockClock::new(Nanos(0));
    let session::Built {
        mut fast,
        mut slow,
        trace,
        ..
    } = session::build(&scene, &plan, clock.clone()).unwrap();
    let (mut periodic, _iv) = Periodic::new(&plan.schedule(), clock).unwrap();
    let stop = StopFlag::new();
    let mut allocations = 0;
    let mut counts = Vec::new();
    for chunk in 0..600 {
        let (_, st) = count(|| periodic.run(&mut fast, RunLimit::slots(5), &stop));
        allocations += st.total();
        while trace.pop().is_some() {}
        slow.step();
        if chunk == 50 || chunk == 599 {
            let r = slow.semantic_report().unwrap();
            counts.push((r.present_at_end, r.constraints_at_end, r.adds, r.removes));
        }
    }
    assert_eq!(allocations, 0, "the fast loop allocated");
    // Before the add the five shaped objects without the lamp, five
    // constraints; after the remove five objects (lamp in, table out) and
    // three.
    assert_eq!(counts, [(5, 5, 0, 0), (5, 3, 1, 1)]);
    let r = slow.semantic_report().unwrap();
    assert_eq!(r.inconsistent, 0);
    assert!(fast.stats().programs_swapped >= r.programs && r.programs >= 4);
}

/// Bad `[[schedule]]` entries are refused at the file, line and column of
/// the field.
#[test]
fn bad_schedules_name_the_field() {
    let base = text();
    let lines = base.lines().count();
    let cases = [
        (
            "[[schedule]]\nat = 1.0\nadd = \"vase\"\n",
            "unknown body `vase`",
            3,
        ),
        (
            "[[schedule]]\nat = nan\nremove = \"cup\"\n",
            "expected a session time",
            2,
        ),
        (
            "[[schedule]]\nat = 1.0\nremove = \"floor\"\n",
            "`floor` is fixed",
            3,
        ),
        (
            "[[schedule]]\nat = 1.0\nadd = \"cup\"\n\n[[schedule]]\nat = 2.0\nadd = \"cup\"\n",
            "`cup` is already in the scene at 2 s",
            7,
        ),
        (
            "[[schedule]]\nat = 3.0\nremove = \"table\"\n",
            "`table` is not in the scene at 3 s",
            3,
        ),
        (
            "[[schedule]]\nat = 1.0\nadd = \"cup\"\nmode = \"constrained\"\n",
            "give exactly one of",
            2,
        ),
        (
            "[[schedule]]\nat = 1.0\nmode = \"loose\"\n",
            "unknown variant `loose`",
            3,
        ),
    ];
    for (extra, expected, line) in cases {
        let text = format!("{base}\n{extra}");
        let err = match scene::parse("bw.toml", &text, None) {
            Err(e) => e.to_string(),
            Ok(l) => match check_loaded(l) {
                Err(e) => e.to_string(),
                Ok(_) => panic!("loaded: {extra}"),
            },
        };
        assert!(err.contains(expected), "{extra}: {err}");
        let at = format!("bw.toml:{}:", lines + 1 + line);
        assert!(err.contains(&at), "{extra}: {err} (expected {at})");
    }
}

/// `--semantic-mode unconstrained` starts the run unconstrained: the hand's
/// grab at 0.5 s releases the cup at once (in the scene's own schedule that
/// happens at 0.8 s); a bad value or a scene without areas is a usage error.
#[test]
fn the_cli_sets_the_starting_mode() {
    let tmp = tempfile::tempdir().unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_haptloop"))
        .args([
            "run",
            "board-wall",
            "--deterministic",
            "--seconds",
            "1.0",
            "--quiet",
        ])
        .args(["--semantic-mode", "unconstrained", "--out"])
        .arg(tmp.path())
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let s: Summary =
        serde_json::from_str(&std::fs::read_to_string(tmp.path().join("summary.json")).unwrap())
            .unwrap();
    let sem = s.semantic.unwrap();
    let first: Vec<(f64, &str, &str)> = sem
        .events
        .iter()
        .map(|e| (e.t_s, e.kind.as_str(), e.binding_body.as_str()))
        .collect();
    assert_eq!(first, [(0.3, "add", "lamp"), (0.5, "release", "cup")]);
    assert_eq!(sem.mode_at_end, "unconstrained");
    for (args, expected) in [
        (
            ["board-wall", "--semantic-mode", "loose"],
            "expected `constrained` or `unconstrained`",
        ),
        (
            ["four-bar", "--semantic-mode", "constrained"],
            "has no semantic areas",
        ),
    ] {
        let r = Command::new(env!("CARGO_BIN_EXE_haptloop"))
            .arg("run")
            .args(args)
            .args(["--deterministic", "--seconds", "0.1", "--no-files"])
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&r.stderr);
        assert_eq!(r.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(expected), "{args:?}: {err}");
    }
}

/// A 4 cm block to be added onto a pad that only it fits, while the
/// fingertip sits where the block would go: the add at 0.2 s finds no valid
/// place; `{hand}` either moves the fingertip 6 cm east over 0.4–0.6 s or
/// keeps it still.
fn blocked_add_scene(hand: &str) -> String {
    format!(
        r#"
[scene]
name = "add-blocked"
description = "an add blocked by the fingertip"

[semantic]
snap_distance = 0.01
snap_angle = 0.35
snap_speed = 0.05
snap_force = 2.0
break_force = 3.0

[labels]
"sits" = ["pad"]

[[device]]
name = "right"
model = "phantom-premium-1.5"
scale = 2.0
hand = {{ waypoints = [{hand}] }}

[[body]]
name = "pad"
fixed = true
position = [0.0, 0.0, -0.01]
shape = {{ box = [0.02, 0.02, 0.01] }}

[[body.offer]]
label = "pad"
polygon = [[-0.02, -0.02, 0.01], [0.02, -0.02, 0.01], [0.02, 0.02, 0.01], [-0.02, 0.02, 0.01]]
normal = [0.0, 0.0, 1.0]

[[body]]
name = "block"
position = [0.0, 0.0, 0.02]
shape = {{ box = [0.02, 0.02, 0.02] }}
mass = 0.05
inertia = [1e-3, 1e-3, 1e-3]

[[body.binding]]
label = "sits"
polygon = [[-0.02, -0.02, -0.02], [-0.02, 0.02, -0.02], [0.02, 0.02, -0.02], [0.02, -0.02, -0.02]]
normal = [0.0, 0.0, -1.0]

[[finger]]
name = "index"
device = "right"
grasp = "contact"
position = [0.0, 0.0, 0.03]
radius = 0.008

[[schedule]]
at = 0.2
add = "block"
"#
    )
}

/// Gösele & Stuerzlinger §3.3 put an added object at the nearest valid
/// place; when there is none (here the fingertip is in the way) the add
/// waits: it is tried again every 50 ms, lands once the hand has moved away
/// (on the pad's centre: the only spot it fits), and is reported as late.
/// With the hand still, it never lands and the report says so.
#[test]
fn an_add_the_fingertip_blocks_lands_once_the_hand_moves_away() {
    let tmp = tempfile::tempdir().unwrap();
    let moving = "[0.0, 0.0, 0.0, 0.0], [0.4, 0.0, 0.0, 0.0], [0.6, 0.06, 0.0, 0.0]";
    let still = "[0.0, 0.0, 0.0, 0.0], [0.6, 0.0, 0.0, 0.0]";
    let mut out = Vec::new();
    for (name, hand) in [("moving", moving), ("still", still)] {
        let file = tmp.path().join(format!("{name}.toml"));
        std::fs::write(&file, blocked_add_scene(hand)).unwrap();
        let dir = tmp.path().join(name);
        let s = Command::new(env!("CARGO_BIN_EXE_haptloop"))
            .args([
                "run",
                file.to_str().unwrap(),
                "--deterministic",
                "--seconds",
                "1.0",
                "--quiet",
                "--out",
            ])
            .arg(&dir)
            .output()
            .unwrap();
        assert!(s.status.success(), "{}", String::from_utf8_lossy(&s.stderr));
        let summary: Summary =
            serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap())
                .unwrap();
        out.push((summary, dir));
    }
    let (moved, moved_dir) = &out[0];
    let sem = moved.semantic.as_ref().unwrap();
    assert_eq!(moved.safety.solver_failures, 0);
    assert_eq!(
        (
            sem.adds,
            sem.add_failures,
            sem.adds_late,
            sem.adds_waiting_at_end
        ),
        (1, 1, 1, 0)
    );
    // The fingertip (8 mm) clears the block's 2 cm half-width at 0.49 s on
    // its path; the retry after that lands it.
    let added_at: Vec<f64> = sem
        .events
        .iter()
        .chain(&sem.other_events)
        .filter(|e| e.kind == "add")
        .map(|e| e.t_s)
        .collect();
    assert_eq!(added_at.len(), 1, "{:?}", sem.events);
    assert!(
        (0.49..0.6).contains(&added_at[0])
            && (sem.add_wait_max_s - (added_at[0] - 0.2)).abs() < 1e-6,
        "added at {added_at:?}, waited {}",
        sem.add_wait_max_s
    );
    let end = track(moved_dir, "block").last().unwrap().1;
    assert!(
        end[0].abs() < 1e-9 && end[1].abs() < 1e-9 && (end[2] - 0.02).abs() < 1e-9,
        "block at {end:?}"
    );
    assert_eq!(sem.objects_at_end, 2);

    let (still, _) = &out[1];
    let sem = still.semantic.as_ref().unwrap();
    assert_eq!(
        (
            sem.adds,
            sem.add_failures,
            sem.adds_late,
            sem.adds_waiting_at_end
        ),
        (0, 1, 0, 1)
    );
    assert!(sem.add_wait_max_s.is_nan());
    assert_eq!(sem.objects_at_end, 1, "only the pad is in the scene");
}
