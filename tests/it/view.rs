//! The viewer's data and the virtual device, without a browser: every
//! scene's track, `haptloop view`'s refusals, the live flags' refusals, the
//! virtual device's equilibrium in a session, record and replay of it, and
//! the fast loop's zero-allocation rule with the live exchange on.

use haptloop::scenes::resolve;
use haptloop::session::{self, Plan, SessionOptions};
use haptloop_rt::clock::{MockClock, Nanos};
use haptloop_rt::schedule::{Periodic, RunLimit, StopFlag};
use nalgebra::Vector3;

fn deterministic(seconds: f64) -> SessionOptions {
    SessionOptions {
        seconds,
        deterministic: true,
        ..SessionOptions::default()
    }
}

/// The four-bar on a virtual device whose pointer is moved 1 cm at 0.2 s:
/// the tip comes to rest at pointer + F/k (the documented mass-spring-
/// damper against the rendered force), with a force rendered.
#[test]
fn a_virtual_device_comes_to_rest_where_its_pointer_spring_balances_the_force() {
    let scene = resolve("four-bar")
        .unwrap()
        .with_device_model("virtual")
        .unwrap();
    let plan = Plan::new(&scene, &deterministic(3.0)).unwrap();
    let clock = MockClock::new(Nanos(0));
    let mut b = session::build(&scene, &plan, clock.clone()).unwrap();
    let pointer = b.fast.rig().pointers[0].clone().unwrap();
    let mount = b.fast.rig().devices[0].mount;
    let (mut periodic, _iv) = Periodic::new(&plan.schedule(), clock).unwrap();
    let stop = StopFlag::new();
    let (mut worst_late, mut force_late) = (0.0f64, f64::INFINITY);
    for chunk in 0..600u64 {
        periodic.run(&mut b.fast, RunLimit::slots(5), &stop);
        b.slow.step();
        if chunk == 40 {
            pointer.set(&Vector3::new(0.01, 0.0, 0.0));
        }
        let mut last = None;
        while let Some(s) = b.trace.pop() {
            last = Some(s);
        }
        let s = last.unwrap();
        let tip = Vector3::from(s.target_m);
        let f = Vector3::from(s.force_n);
        let target = mount.point_to_scene(&pointer.get().unwrap_or_default());
        let k = 300.0 / (mount.scale * mount.scale);
        let off = (tip - (target + f / k)).norm();
        // Settled after 1.5 s (the linkage creeps for about a second).
        if chunk >= 300 {
            worst_late = worst_late.max(off);
            force_late = force_late.min(f.norm());
        }
    }
    // A few µm: the tip is sensed to 1 µm, the pointer kept to 1 µm.
    assert!(
        worst_late < 5e-6,
        "tip − (pointer + F/k) up to {worst_late:e} m"
    );
    assert!(
        force_late > 0.5,
        "the linkage held the tip back with {force_late} N"
    );
}

/// Every built-in scene, mechanisms included, is tracked: every moving
/// body at 100 Hz of session time from t = 0 (fixed ones once), every
/// finger at 100 Hz, and a body without a shape has points to be drawn by.
#[test]
fn every_scene_is_tracked_body_by_body_at_100_hz() {
    use haptloop::scenes::BUILTIN;
    use haptloop::view::SceneInfo;
    for b in BUILTIN {
        let scene = resolve(b.name).unwrap();
        let seconds = 0.2;
        let o = session::run(
            &scene,
            Plan::new(&scene, &deterministic(seconds)).unwrap(),
            &StopFlag::new(),
            &mut |_| {},
        )
        .unwrap();
        let model = &scene.compiled.model;
        let moving = model.bodies().iter().filter(|b| !b.fixed).count();
        assert_eq!(o.track.bodies.len(), moving, "{}", b.name);
        assert_eq!(
            o.track.fixed.len(),
            model.bodies().len() - moving,
            "{}",
            b.name
        );
        for (what, times) in [
            (
                "bodies",
                o.track.samples.iter().map(|s| s.0).collect::<Vec<f64>>(),
            ),
            (
                "fingers",
                o.recorder.fingers.samples.iter().map(|s| s.0).collect(),
            ),
        ] {
            assert!(times[0] <= 0.01, "{}: {what} start at {}", b.name, times[0]);
            // One sample in every 10 ms slot (the first snapshot at or
            // after it: the slow loop looks every 5 ms, 6 ms at 500 Hz).
            let gaps: Vec<f64> = times.windows(2).map(|w| w[1] - w[0]).collect();
            let slots: std::collections::BTreeSet<i64> = times
                .iter()
                .map(|t| (t / 0.01 + 1e-9).floor() as i64)
                .collect();
            assert!(
                gaps.iter().all(|g| *g < 0.02)
                    && slots.len() == times.len()
                    && times.len() as f64 >= seconds / 0.01,
                "{}: {what} at {} samples, gaps up to {:?}",
                b.name,
                times.len(),
                gaps.iter().cloned().fold(0.0, f64::max)
            );
        }
        let info = SceneInfo::of(&scene);
        for body in &info.bodies {
            assert!(
                body.shape.is_some() || !body.links.is_empty(),
                "{}: `{}` has nothing to be drawn by",
                b.name,
                body.name
            );
        }
    }
}

fn haptloop(args: &[&str]) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_haptloop"))
        .args(args)
        .output()
        .unwrap()
}

/// `haptloop view` on a folder that is not a whole run says what is
/// missing or wrong, where, with exit status 1; never a panic.
#[test]
fn view_refuses_an_incomplete_or_damaged_run_folder_by_name() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    let o = haptloop(&[
        "run",
        "four-bar",
        "--deterministic",
        "--seconds",
        "0.2",
        "--quiet",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success());
    assert!(out.join("view.html").is_file(), "run writes view.html");
    let again = haptloop(&["view", out.to_str().unwrap()]);
    assert!(
        again.status.success(),
        "{}",
        String::from_utf8_lossy(&again.stderr)
    );
    let bodies = std::fs::read_to_string(out.join("bodies.csv")).unwrap();
    // Damaged: a number that is not one, on line 3.
    let mut lines: Vec<String> = bodies.lines().map(str::to_owned).collect();
    lines[2] = lines[2].replacen(",", ",x", 2).replacen(",x", ",", 1);
    std::fs::write(out.join("bodies.csv"), lines.join("\n")).unwrap();
    let bad = haptloop(&["view", out.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&bad.stderr);
    assert_eq!(bad.status.code(), Some(1), "{err}");
    assert!(
        err.contains("bodies.csv:3:") && err.contains("not a number"),
        "{err}"
    );
    // Missing files: every one named.
    std::fs::remove_file(out.join("fingers.csv")).unwrap();
    std::fs::remove_file(out.join("scene.json")).unwrap();
    let missing = haptloop(&["view", out.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&missing.stderr);
    assert_eq!(missing.status.code(), Some(1), "{err}");
    assert!(err.contains("missing scene.json, fingers.csv"), "{err}");
    let nowhere = haptloop(&["view", dir.path().join("nowhere").to_str().unwrap()]);
    let err = String::from_utf8_lossy(&nowhere.stderr);
    assert_eq!(nowhere.status.code(), Some(1));
    assert!(err.contains("nowhere: not a directory"), "{err}");
}

/// The live flags refuse what cannot work, before anything runs: a port
/// in use (exit 1, naming it), `--live` with `--deterministic` and an
/// unknown `--device` model (usage errors, exit 2); a scene file's virtual
/// device with a scripted hand is an error at its place.
#[test]
fn the_live_flags_refuse_a_port_in_use_and_what_cannot_work() {
    let taken = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let port = taken.local_addr().unwrap().port().to_string();
    let o = haptloop(&["run", "four-bar", "--live", "--port", &port, "--no-files"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains(&format!("127.0.0.1:{port} is already in use")),
        "{err}"
    );
    let o = haptloop(&["run", "four-bar", "--live", "--deterministic", "--no-files"]);
    assert_eq!(o.status.code(), Some(2));
    let o = haptloop(&[
        "run",
        "four-bar",
        "--device",
        "phantom-desktop",
        "--no-files",
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("phantom-desktop") && err.contains("virtual"),
        "{err}"
    );
    let base = haptloop::scenes::BUILTIN
        .iter()
        .find(|b| b.name == "four-bar")
        .unwrap()
        .text;
    let text = base.replacen("model = \"phantom-premium-1.5\"", "model = \"virtual\"", 1);
    assert!(text.contains("hand ="), "the four-bar's device has a hand");
    let err = haptloop_solver::scene::parse("v.toml", &text, None)
        .map(haptloop::scenes::check_loaded)
        .unwrap()
        .err()
        .expect("a virtual device with a scripted hand is refused")
        .to_string();
    assert!(
        err.starts_with("v.toml:") && err.contains("is virtual"),
        "{err}"
    );
}

/// A run on virtual devices (the four-bar's weight pushes the tip, so it
/// moves) recorded and replayed: the same fingers' figures, bit for bit.
#[test]
fn a_virtual_device_is_recorded_and_replayed_bit_for_bit() {
    let scene = resolve("four-bar")
        .unwrap()
        .with_device_model("virtual")
        .unwrap();
    let dir = tempfile::tempdir().unwrap();
    let go = |options: SessionOptions| {
        let plan = Plan::new(&scene, &options).unwrap();
        session::run(&scene, plan, &StopFlag::new(), &mut |_| {}).unwrap()
    };
    let recorded = go(SessionOptions {
        record: Some(dir.path().to_path_buf()),
        ..deterministic(1.0)
    });
    let replayed = go(SessionOptions {
        replay: Some(dir.path().to_path_buf()),
        ..deterministic(1.0)
    });
    let (a, b) = (
        recorded.recorder.fingers.csv(),
        replayed.recorder.fingers.csv(),
    );
    assert_eq!(a, b);
    let tips: Vec<[f64; 3]> = recorded
        .recorder
        .fingers
        .samples
        .iter()
        .map(|s| s.1[0].device_m)
        .collect();
    assert!(
        tips.first() != tips.last(),
        "the tip never moved: nothing was compared"
    );
    assert_eq!(recorded.virtual_devices.len(), 1);
    // The replay checked every tick's force against the recording's
    // (the virtual device's own clamp, not a PHANToM's motor model).
    let check = replayed.device_limits[0]
        .replay
        .expect("a replayed device reports its check");
    assert!(
        check.compared > 900 && check.diverged == 0,
        "replay check: {check:?}"
    );
    assert_eq!(replayed.device_limits[0].model, "virtual");
}

/// The fast loop allocates nothing with the live exchange on, while the
/// slow loop publishes frames, a viewer thread reads them and moves the
/// virtual devices' pointers, and the reporter publishes the fingers:
/// the four-bar and pinch-lift on virtual devices.
#[test]
fn the_fast_loop_tick_allocates_nothing_with_the_live_view_on() {
    use haptloop::session::{LiveHook, LiveSources, Recorder};
    use haptloop_rt::alloc::count;
    use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
    use std::sync::{Arc, Mutex};
    for name in ["four-bar", "pinch-lift"] {
        let scene = resolve(name).unwrap().with_device_model("virtual").unwrap();
        let slot: Arc<Mutex<Option<LiveSources>>> = Arc::default();
        let put = slot.clone();
        let options = SessionOptions {
            live: Some(LiveHook(Arc::new(move |s| *put.lock().unwrap() = Some(s)))),
            ..deterministic(3.0)
        };
        let plan = Plan::new(&scene, &options).unwrap();
        let clock = MockClock::new(Nanos(0));
        let mut built = session::build(&scene, &plan, clock.clone()).unwrap();
        let names: Vec<String> = scene
            .compiled
            .model
            .fingers()
            .iter()
            .map(|f| f.name.clone())
            .collect();
        let mut recorder = Recorder::new(&names, plan.ticks(), None).unwrap();
        built.start_live(&plan, &mut recorder);
        let mut sources = slot
            .lock()
            .unwrap()
            .take()
            .expect("the hook got the viewer's ends");
        let session::Built {
            mut fast,
            mut slow,
            trace,
            ..
        } = built;
        let done = Arc::new(AtomicBool::new(false));
        let (frames, moves) = (Arc::new(AtomicU64::new(0)), Arc::new(AtomicU64::new(0)));
        let (flag, seen, moved) = (done.clone(), frames.clone(), moves.clone());
        let viewer = std::thread::spawn(move || {
            let mut k = 0u32;
            while !flag.load(Ordering::Acquire) {
                if sources.frames.refresh() {
                    seen.fetch_add(1, Ordering::Relaxed);
                }
                sources.fingers.refresh();
                k += 1;
                let x = 0.005 * (f64::from(k) * 0.01).sin();
                for p in &sources.pointers {
                    p.pointer.set(&Vector3::new(x, 0.0, x));
                    moved.fetch_add(1, Ordering::Relaxed);
                }
                std::thread::yield_now();
            }
        });
        let flag = done.clone();
        let slow_thread = std::thread::spawn(move || {
            while !flag.load(Ordering::Acquire) {
                slow.step();
                std::thread::yield_now();
            }
        });
        let (mut periodic, _iv) = Periodic::new(&plan.schedule(), clock).unwrap();
        let stop = StopFlag::new();
        periodic.run(&mut fast, RunLimit::slots(50), &stop);
        let chunks = (plan.ticks() - 50) / 50;
        let mut total = 0;
        for _ in 0..chunks {
            let (_, stats) = count(|| periodic.run(&mut fast, RunLimit::slots(50), &stop));
            total += stats.total();
            recorder.drain(&trace, &names).unwrap();
            std::thread::yield_now();
        }
        done.store(true, Ordering::Release);
        viewer.join().unwrap();
        slow_thread.join().unwrap();
        assert_eq!(total, 0, "{name}: the fast loop allocated {total} times");
        assert!(
            frames.load(Ordering::Relaxed) > 0,
            "{name}: no live frame was read"
        );
        assert!(moves.load(Ordering::Relaxed) > 0, "{name}: no pointer move");
        let moved = recorder.fingers.samples.iter().any(|(_, f)| {
            f[0].device_m != recorder.fingers.samples.iter().next().unwrap().1[0].device_m
        });
        assert!(moved, "{name}: the pointer never moved the device");
    }
}

/// A real-time session with the live exchange on and a viewer reading it:
/// every tick is accounted for, the viewer saw frames, a stop ends it
/// cleanly (the real scheduler: structure, not speed).
#[test]
fn a_real_time_session_with_the_live_view_on_accounts_for_every_tick() {
    use haptloop::session::LiveHook;
    use haptloop_rt::thread::ThreadConfig;
    use std::sync::Arc;
    use std::sync::atomic::{AtomicU64, Ordering};
    let scene = resolve("four-bar")
        .unwrap()
        .with_device_model("virtual")
        .unwrap();
    let frames = Arc::new(AtomicU64::new(0));
    let seen = frames.clone();
    let options = SessionOptions {
        seconds: 1.0,
        thread: ThreadConfig {
            fifo_priority: None,
            lock_memory: false,
            ..ThreadConfig::default()
        },
        live: Some(LiveHook(Arc::new(move |mut s| {
            let seen = seen.clone();
            std::thread::spawn(move || {
                for _ in 0..400 {
                    if s.frames.refresh() {
                        seen.fetch_add(1, Ordering::Relaxed);
                    }
                    std::thread::sleep(std::time::Duration::from_millis(2));
                }
            });
        }))),
        ..SessionOptions::default()
    };
    let plan = Plan::new(&scene, &options).unwrap();
    let o = session::run(&scene, plan, &StopFlag::new(), &mut |_| {}).unwrap();
    assert_eq!(
        o.stats.ticks, o.report.ticks,
        "every tick was accounted for"
    );
    assert!(o.report.ticks > 500, "{} ticks", o.report.ticks);
    assert!(
        frames.load(Ordering::Relaxed) > 10,
        "{} frames",
        frames.load(Ordering::Relaxed)
    );
}

/// The fast loop's tick does not know the viewer exists: a deterministic
/// run with the live exchange on, and a viewer thread reading every frame
/// as it comes (a copy of each, as the page's server takes), gives the
/// same fingers, bodies, contacts and violation, bit for bit, as the same
/// run without it. PHANToM devices: nothing moves a pointer, so any
/// difference would be the viewer's doing.
#[test]
fn a_deterministic_run_is_the_same_bit_for_bit_with_the_live_view_on() {
    use haptloop::session::{LiveHook, LiveSources};
    use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
    use std::sync::{Arc, Mutex};
    for (name, seconds) in [("four-bar", 1.0), ("pinch-lift", 1.0)] {
        let scene = resolve(name).unwrap();
        let frames = Arc::new(AtomicU64::new(0));
        let done = Arc::new(AtomicBool::new(false));
        let viewer: Arc<Mutex<Option<std::thread::JoinHandle<()>>>> = Arc::default();
        let (seen, flag, slot) = (frames.clone(), done.clone(), viewer.clone());
        let hook = LiveHook(Arc::new(move |mut s: LiveSources| {
            let (seen, flag) = (seen.clone(), flag.clone());
            *slot.lock().unwrap() = Some(std::thread::spawn(move || {
                while !flag.load(Ordering::Acquire) {
                    if s.frames.refresh() {
                        let frame = s.frames.latest().clone();
                        assert!(frame.t_s.is_finite());
                        seen.fetch_add(1, Ordering::Relaxed);
                    }
                    if s.fingers.refresh() {
                        let _ = s.fingers.latest().clone();
                    }
                    std::thread::yield_now();
                }
            }));
        }));
        let go = |live: Option<LiveHook>| {
            let options = SessionOptions {
                live,
                ..deterministic(seconds)
            };
            let plan = Plan::new(&scene, &options).unwrap();
            session::run(&scene, plan, &StopFlag::new(), &mut |_| {}).unwrap()
        };
        let off = go(None);
        let on = go(Some(hook));
        // A loaded machine may not have scheduled the viewer during the
        // run; the last frame is still in the mailbox for it to read.
        let waited = std::time::Instant::now();
        while frames.load(Ordering::Relaxed) == 0 && waited.elapsed().as_secs() < 30 {
            std::thread::sleep(std::time::Duration::from_millis(1));
        }
        done.store(true, Ordering::Release);
        viewer
            .lock()
            .unwrap()
            .take()
            .expect("the live hook started a viewer")
            .join()
            .unwrap();
        assert_eq!(off.stats.ticks, on.stats.ticks, "{name}: ticks");
        // scene.json, bodies.csv, fingers.csv and contacts.csv, as `run`
        // writes them.
        let info = haptloop::view::SceneInfo::of(&scene);
        let files =
            |o: &session::SessionOutcome| haptloop::view::files::contents(&info, o).unwrap();
        for ((file, a), (_, b)) in files(&off).into_iter().zip(files(&on)) {
            assert!(a == b, "{name}: {file} differs with the live view on");
        }
        let bits = |s: &haptloop::session::Series| -> Vec<(u64, u64)> {
            s.points
                .iter()
                .map(|(t, v)| (t.to_bits(), v.to_bits()))
                .collect()
        };
        assert_eq!(
            bits(&off.recorder.violation),
            bits(&on.recorder.violation),
            "{name}: violation"
        );
        assert!(
            off.recorder.fingers.samples.len() >= 99,
            "{name}: {} samples compared",
            off.recorder.fingers.samples.len()
        );
        assert!(
            frames.load(Ordering::Relaxed) > 0,
            "{name}: the viewer read no frame"
        );
    }
}

/// The page's force plot of a run with fewer ticks than plot bins (1 s at
/// 1 kHz, 2000 bins): every bin holds a force some tick near it actually
/// rendered (trace.csv, parsed here), never a 0 for a bin no tick fell in.
#[test]
fn every_bin_of_the_page_force_plot_is_a_rendered_force_near_its_time() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_haptloop"))
        .args(["run", "four-bar", "--deterministic", "--seconds", "1"])
        .args(["--quiet", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let rows: Vec<(f64, f32)> = std::fs::read_to_string(out.join("trace.csv"))
        .unwrap()
        .lines()
        .skip(1)
        .map(|l| {
            let f: Vec<f64> = l
                .split(',')
                .map(|x| x.parse().unwrap_or(f64::NAN))
                .collect();
            (
                f[0],
                (f[8] * f[8] + f[9] * f[9] + f[10] * f[10]).sqrt() as f32,
            )
        })
        .collect();
    let page = haptloop::view::PageData::read(&out).unwrap();
    let (t, force) = (&page.series.t, &page.series.force[0]);
    assert!(
        t.len() > rows.len(),
        "{} bins, {} ticks",
        t.len(),
        rows.len()
    );
    let width = f64::from(t[1] - t[0]);
    let mut zeros = 0;
    for (b, (&tb, &v)) in t.iter().zip(force).enumerate() {
        let tb = f64::from(tb);
        let near = rows
            .iter()
            .filter(|(tr, _)| (*tr - tb).abs() <= 2.0 * width + 1e-6);
        assert!(
            near.clone().any(|(_, f)| *f == v),
            "bin {b} at {tb} s holds {v} N, which no tick within two bins of it rendered"
        );
        zeros += usize::from(v == 0.0);
    }
    assert!(zeros < 10, "{zeros} bins hold 0 N");
}

/// `board-wall` declares the lamp absent until its `[[schedule]] add` at
/// 0.3 s and removes the table at 2.8 s: the page's data says which bodies
/// start absent and carries the add and remove events with their bodies,
/// at the scene file's times (within one slow-loop step), so the viewer
/// can draw a body only while it is in the scene.
#[test]
fn the_page_knows_when_each_body_is_in_the_scene() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_haptloop"))
        .args(["run", "board-wall", "--deterministic", "--seconds", "3.2"])
        .args(["--quiet", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let page = haptloop::view::PageData::read(&out).unwrap();
    let scene = page.scene.as_ref().unwrap();
    let absent: Vec<&str> = scene
        .bodies
        .iter()
        .filter(|b| b.absent)
        .map(|b| b.name.as_str())
        .collect();
    assert_eq!(absent, ["lamp"]);
    let when = |kind: &str, body: &str| -> Vec<f64> {
        page.events
            .iter()
            .filter(|e| e.kind == kind && e.body == body)
            .map(|e| e.t_s)
            .collect()
    };
    let (added, removed) = (when("add", "lamp"), when("remove", "table"));
    assert!(
        added.len() == 1 && (added[0] - 0.3).abs() <= 0.0051,
        "lamp added at {added:?} s, scheduled at 0.3 s"
    );
    assert!(
        removed.len() == 1 && (removed[0] - 2.8).abs() <= 0.0051,
        "table removed at {removed:?} s, scheduled at 2.8 s"
    );
}
