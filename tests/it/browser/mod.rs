//! The viewer in a real browser (headless Chromium from the OS packages,
//! driven over the DevTools protocol, `cdp`): a replayed run's bodies are
//! drawn where the run's files say they were, the timeline moves them, a
//! page without WebGL says so in words, and a person's drag in the live
//! page moves a virtual device's tip by the dragged amount, with a force
//! rendered. Skipped with a message where no chromium is installed; a
//! failure in CI (`HAPTLOOP_BROWSER_REQUIRED`, set by `.ci/run`).
//!
//! Set `HAPTLOOP_SCREENSHOTS=DIR` to keep the screenshots (the README's
//! pictures in `docs/` come from there).

mod cdp;

use cdp::{Browser, Image, browser_or_skip};
use nalgebra::{Matrix4, UnitQuaternion, Vector3, Vector4};
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::Command;

/// One browser test at a time: two software-rendered pages at once would
/// starve a small machine (and the live test's real-time session).
static ONE_AT_A_TIME: std::sync::Mutex<()> = std::sync::Mutex::new(());

const WIDTH: u32 = 1280;
const HEIGHT: u32 = 800;

fn haptloop(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_haptloop"))
        .args(args)
        .output()
        .unwrap()
}

/// A deterministic run of `scene` for `seconds` into a fresh folder.
fn run(scene: &str, seconds: &str) -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    let o = haptloop(&[
        "run",
        scene,
        "--deterministic",
        "--seconds",
        seconds,
        "--quiet",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    (dir, out)
}

fn keep(img: &Image, name: &str) {
    if let Some(dir) = std::env::var_os("HAPTLOOP_SCREENSHOTS") {
        std::fs::write(Path::new(&dir).join(name), &img.png).unwrap();
    }
}

/// Drawn by a body, not the background (#fbfbfa) nor the light grid.
fn is_body(p: [u8; 3]) -> bool {
    let (lo, hi) = (*p.iter().min().unwrap(), *p.iter().max().unwrap());
    lo < 190 || hi - lo > 40
}

/// The page's camera: world → CSS pixel, from its view and projection
/// matrices (the page's state; the points come from the run's files).
struct Camera {
    m: Matrix4<f64>,
    rect: [f64; 4],
}

impl Camera {
    fn of(b: &mut Browser) -> Camera {
        let c = b.eval("window.haptloop.camera()");
        let mat = |k: &str| {
            let v: Vec<f64> = c[k]
                .as_array()
                .unwrap()
                .iter()
                .map(|x| x.as_f64().unwrap())
                .collect();
            Matrix4::from_column_slice(&v)
        };
        let r: Vec<f64> = b
            .eval("window.haptloop.canvasRect()")
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect();
        Camera {
            m: mat("projection") * mat("view"),
            rect: [r[0], r[1], r[2], r[3]],
        }
    }

    fn pixel(&self, p: &Vector3<f64>) -> (f64, f64) {
        let c = self.m * Vector4::new(p.x, p.y, p.z, 1.0);
        let (x, y) = (c.x / c.w, c.y / c.w);
        (
            self.rect[0] + (x + 1.0) / 2.0 * self.rect[2],
            self.rect[1] + (1.0 - y) / 2.0 * self.rect[3],
        )
    }
}

/// Where each moving body should be drawn at sample `k` of `bodies.csv`:
/// its pose applied to its link centre (shape-less) or origin (shaped).
fn expected_points(run: &Path, k: usize) -> (f64, Vec<(String, Vector3<f64>)>) {
    let scene: Value =
        serde_json::from_str(&std::fs::read_to_string(run.join("scene.json")).unwrap()).unwrap();
    let csv = std::fs::read_to_string(run.join("bodies.csv")).unwrap();
    let mut times: Vec<f64> = Vec::new();
    let mut rows = Vec::new();
    for line in csv.lines().skip(1) {
        let f: Vec<&str> = line.split(',').collect();
        let t: f64 = f[0].parse().unwrap();
        let body = scene["bodies"]
            .as_array()
            .unwrap()
            .iter()
            .find(|b| b["name"] == f[1])
            .unwrap();
        if body["fixed"] == true {
            continue;
        }
        if times.last() != Some(&t) {
            times.push(t);
        }
        if times.len() == k + 1 {
            let v: Vec<f64> = f[2..9].iter().map(|x| x.parse().unwrap()).collect();
            let links: Vec<Vector3<f64>> = body["links"]
                .as_array()
                .unwrap()
                .iter()
                .map(|p| {
                    Vector3::new(
                        p[0].as_f64().unwrap(),
                        p[1].as_f64().unwrap(),
                        p[2].as_f64().unwrap(),
                    )
                })
                .collect();
            let centre = if links.is_empty() {
                Vector3::zeros()
            } else {
                links.iter().sum::<Vector3<f64>>() / links.len() as f64
            };
            let q =
                UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(v[3], v[4], v[5], v[6]));
            rows.push((f[1].to_owned(), Vector3::new(v[0], v[1], v[2]) + q * centre));
        }
    }
    (times[k], rows)
}

/// A body pixel within `r` px of (x, y).
fn body_near(img: &Image, (x, y): (f64, f64), r: i64) -> bool {
    (-r..=r).any(|dy| {
        (-r..=r).any(|dx| {
            let (px, py) = (x.round() as i64 + dx, y.round() as i64 + dy);
            px >= 0
                && py >= 0
                && (px as u32) < img.width
                && (py as u32) < img.height
                && is_body(img.rgb(px as u32, py as u32))
        })
    })
}

fn count_in(img: &Image, rect: [f64; 4], f: impl Fn(u32, u32) -> bool) -> usize {
    let (x0, y0) = (rect[0].max(0.0) as u32, rect[1].max(0.0) as u32);
    let (x1, y1) = (
        ((rect[0] + rect[2]) as u32).min(img.width),
        ((rect[1] + rect[3]) as u32).min(img.height),
    );
    (y0..y1)
        .flat_map(|y| (x0..x1).map(move |x| (x, y)))
        .filter(|&(x, y)| f(x, y))
        .count()
}

/// Opens a run's `view.html`, shows sample `k` and checks every moving
/// body is drawn where `bodies.csv` puts it; returns the screenshot.
fn shows_sample(b: &mut Browser, run: &Path, k: usize, shot: &str) -> Image {
    let (t, points) = expected_points(run, k);
    b.eval(&format!("window.haptloop.setTime({t})"));
    let cam = Camera::of(b);
    let img = b.screenshot();
    keep(&img, shot);
    let drawn = count_in(&img, cam.rect, |x, y| is_body(img.rgb(x, y)));
    let area = (cam.rect[2] * cam.rect[3]) as usize;
    assert!(
        drawn > area / 500,
        "{shot}: {drawn} body pixels of {area}: a blank canvas"
    );
    for (name, p) in &points {
        let px = cam.pixel(p);
        assert!(
            body_near(&img, px, 4),
            "{shot}: `{name}` at t = {t} s should be drawn at {px:?} (world {p:?}), and is not"
        );
    }
    img
}

fn open(b: &mut Browser, run: &Path) {
    b.navigate(&format!("file://{}", run.join("view.html").display()));
    b.wait_for("!!(window.haptloop && window.haptloop.ready)", 60);
}

/// The four-bar (links only, no shapes) and pinch-lift (shapes, contacts):
/// the bodies are drawn where the files say, at two instants, and moving
/// the timeline changes the picture. A page without WebGL says so.
#[test]
fn view_html_draws_the_bodies_where_the_run_put_them_and_the_timeline_moves_them() {
    let Some(bin) = browser_or_skip("view_html_draws_the_bodies…") else {
        return;
    };
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let mut b = Browser::start(&bin, WIDTH, HEIGHT);
    for (scene, seconds, later) in [("four-bar", "2", 120), ("pinch-lift", "3", 250)] {
        let (_dir, out) = run(scene, seconds);
        open(&mut b, &out);
        let first = shows_sample(&mut b, &out, 0, &format!("view-{scene}-start.png"));
        let then = shows_sample(&mut b, &out, later, &format!("view-{scene}.png"));
        let cam = Camera::of(&mut b);
        let changed = count_in(&first, cam.rect, |x, y| {
            let (p, q) = (first.rgb(x, y), then.rgb(x, y));
            p.iter().zip(q).any(|(a, b)| a.abs_diff(b) > 40)
        });
        assert!(
            changed > 300,
            "{scene}: moving the timeline changed only {changed} pixels"
        );
    }
    // WebGL unavailable (getContext gives nothing, as a browser without it
    // does): the page says so in words.
    let (_dir, out) = run("four-bar", "0.2");
    b.page(
        "Page.addScriptToEvaluateOnNewDocument",
        serde_json::json!({"source": "HTMLCanvasElement.prototype.getContext = function () { return null; };"}),
    );
    b.navigate(&format!("file://{}", out.join("view.html").display()));
    b.wait_for("!!(window.haptloop && window.haptloop.error)", 30);
    let text = b.eval("document.getElementById('message').textContent");
    let shown = b.eval("!document.getElementById('message').hidden");
    assert!(
        text.as_str().unwrap().contains("WebGL") && shown == Value::Bool(true),
        "{text}"
    );
}

/// `run four-bar --live --device virtual`: a drag of the virtual device's
/// ball in the page moves the pointer by the dragged distance (pixels ×
/// metres per pixel at the ball's depth, from the page's camera), and the
/// tip follows: at rest, tip = pointer + force / k_pointer (the documented
/// mass-spring-damper), with a force rendered.
#[test]
fn a_drag_in_the_live_page_moves_the_virtual_device_by_the_dragged_amount() {
    let Some(bin) = browser_or_skip("a_drag_in_the_live_page…") else {
        return;
    };
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    let mut child = Command::new(env!("CARGO_BIN_EXE_haptloop"))
        .args([
            "run", "four-bar", "--live", "--port", "0", "--device", "virtual",
        ])
        .args(["--seconds", "8", "--quiet", "--out"])
        .arg(&out)
        .stderr(std::process::Stdio::piped())
        .stdout(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let stderr = child.stderr.take().unwrap();
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        use std::io::BufRead;
        let mut all = String::new();
        for line in std::io::BufReader::new(stderr)
            .lines()
            .map_while(Result::ok)
        {
            if let Some(url) = line.split("live view at ").nth(1) {
                let _ = tx.send(url.split_whitespace().next().unwrap().to_owned());
            }
            all += &line;
            all += "\n";
        }
        all
    });
    let url = rx
        .recv_timeout(std::time::Duration::from_secs(60))
        .expect("the run printed its live address");
    let mut b = Browser::start(&bin, WIDTH, HEIGHT);
    b.navigate(&url);
    b.wait_for(
        "!!(window.haptloop && window.haptloop.lastFrame && window.haptloop.frames > 10)",
        30,
    );
    // Wait out the start-up ramp (1 s), while the linkage's weight settles
    // the device, then take the ball where it is drawn now, and the metres
    // per pixel at its depth.
    b.wait_for("window.haptloop.time > 1.2", 30);
    let p: Vec<f64> = serde_json::from_value(b.eval("window.haptloop.devicePoint(0)")).unwrap();
    let ball = Vector3::new(p[0], p[1], p[2]);
    let c = b.eval("window.haptloop.camera()");
    let v = |k: &str| {
        let a: Vec<f64> = serde_json::from_value(c[k].clone()).unwrap();
        Vector3::new(a[0], a[1], a[2])
    };
    let (eye, dir_v, up) = (v("position"), v("direction"), v("up"));
    let depth = (ball - eye).dot(&dir_v);
    let rect: Vec<f64> = serde_json::from_value(b.eval("window.haptloop.canvasRect()")).unwrap();
    let fov = c["fov_deg"].as_f64().unwrap().to_radians();
    let m_per_px = 2.0 * depth * (fov / 2.0).tan() / rect[3];
    let right = dir_v.cross(&up).normalize();
    let screen_up = right.cross(&dir_v).normalize();
    let cam = Camera::of(&mut b);
    let (x0, y0) = cam.pixel(&ball);
    let (dx, dy) = (40.0, -25.0);
    let dragged = right * dx * m_per_px - screen_up * dy * m_per_px;
    // Press on the ball, move in 20 steps, release.
    b.mouse("mouseMoved", x0, y0, 0);
    b.mouse("mousePressed", x0, y0, 1);
    for k in 1..=20 {
        let f = f64::from(k) / 20.0;
        b.mouse("mouseMoved", x0 + dx * f, y0 + dy * f, 1);
        std::thread::sleep(std::time::Duration::from_millis(15));
    }
    b.mouse("mouseReleased", x0 + dx, y0 + dy, 1);
    if std::env::var_os("HAPTLOOP_SCREENSHOTS").is_some() {
        std::thread::sleep(std::time::Duration::from_millis(800));
        keep(&b.screenshot(), "view-live.png");
    }
    let sent = b.eval("window.haptloop.sent || 0");
    // Where the drag took the ball from (the page's start: the ball may
    // have crept a few µm since we looked).
    let from: Vec<f64> = serde_json::from_value(b.eval("window.haptloop.dragStart")).unwrap();
    let from = Vector3::new(from[0], from[1], from[2]);
    assert!(
        (from - ball).norm() < 5e-4,
        "the drag started at {from:?}, the ball was at {ball:?}"
    );
    assert!(
        sent.as_u64().unwrap() > 5,
        "the page sent {sent} pointer moves"
    );
    let status = child.wait().unwrap();
    assert!(status.success(), "the run failed");
    let summary: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let d = &summary["virtual_devices"][0];
    let vec = |k: &str| {
        let a: Vec<f64> = serde_json::from_value(d[k].clone()).unwrap();
        Vector3::new(a[0], a[1], a[2])
    };
    let (tip, pointer, force) = (vec("tip_end_m"), vec("pointer_end_m"), vec("force_end_n"));
    let k = d["pointer_stiffness_n_per_m"].as_f64().unwrap();
    // The pointer went where the mouse went: from where the drag started,
    // by the dragged pixels at the ball's depth, within two pixels' worth (the page rounds nothing; the
    // pointer keeps 1 µm).
    let moved = pointer - from;
    assert!(
        (moved - dragged).norm() < 2.0 * m_per_px,
        "pointer moved {moved:?}, dragged {dragged:?} ({m_per_px:e} m/px)"
    );
    // The tip came to rest where the pointer spring balances the rendered
    // force: tip = pointer + F/k. Checked in trace.csv (each tick's sensed
    // tip and rendered force) on the ticks after the drag at which the tip
    // and the force are at rest (over the 20 ticks before: tip within
    // 2 µm, force within 2 mN): a real-time run on a shared machine has
    // stalls, whose force cuts let the tip spring back for a while.
    let trace = std::fs::read_to_string(out.join("trace.csv")).unwrap();
    let rows: Vec<(Vector3<f64>, Vector3<f64>)> = trace
        .lines()
        .skip(1)
        .map(|l| {
            let f: Vec<f64> = l
                .split(',')
                .map(|x| x.parse().unwrap_or(f64::NAN))
                .collect();
            (
                Vector3::new(f[2], f[3], f[4]),
                Vector3::new(f[8], f[9], f[10]),
            )
        })
        .collect();
    let mut off: Vec<f64> = rows
        .windows(21)
        .filter(|w| {
            let (t0, f0) = w[20];
            (t0 - from).norm() > 0.5 * dragged.norm()
                && w.iter()
                    .all(|(t, f)| (t - t0).norm() <= 2e-6 && (f - f0).norm() <= 2e-3)
        })
        .map(|w| (w[20].0 - (pointer + w[20].1 / k)).norm())
        .collect();
    assert!(
        off.len() >= 200,
        "only {} ticks at rest after the drag (end: tip {tip:?}, F {force:?})",
        off.len()
    );
    off.sort_by(f64::total_cmp);
    let (median, worst) = (off[off.len() / 2], off[off.len() - 1]);
    assert!(
        median < 2e-5 && worst < 1e-4,
        "tip − (pointer + F/k) at rest: median {median:e} m, worst {worst:e} m over {} ticks",
        off.len()
    );
    let fmax = d["force_max_n"].as_f64().unwrap();
    assert!(fmax > 0.1, "force rendered: max {fmax} N");
}

/// `board-wall`: the lamp, declared but absent until its add at 0.3 s, is
/// not drawn before it and is after; the table is drawn until its removal
/// at 2.8 s and not after. Checked on the drawn scene graph and on the
/// picture: hiding the lamp changes the pixels where it stands.
#[test]
fn the_view_draws_a_body_only_while_it_is_in_the_scene() {
    let Some(bin) = browser_or_skip("the_view_draws_a_body_only_while…") else {
        return;
    };
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let mut b = Browser::start(&bin, WIDTH, HEIGHT);
    let (_dir, out) = run("board-wall", "3.2");
    open(&mut b, &out);
    let visible = |b: &mut Browser, t: f64, name: &str| {
        b.eval(&format!("window.haptloop.setTime({t})"));
        b.eval(&format!("window.haptloop.visible('{name}')"))
    };
    for (t, lamp, table) in [(0.1, false, true), (1.0, true, true), (3.1, true, false)] {
        assert_eq!(
            visible(&mut b, t, "lamp"),
            Value::Bool(lamp),
            "lamp at {t} s"
        );
        assert_eq!(
            visible(&mut b, t, "table"),
            Value::Bool(table),
            "table at {t} s"
        );
    }
    b.eval("window.haptloop.setTime(0.1)");
    let before = b.screenshot();
    b.eval("window.haptloop.setTime(1.0)");
    let after = b.screenshot();
    let cam = Camera::of(&mut b);
    let changed = count_in(&before, cam.rect, |x, y| {
        let (p, q) = (before.rgb(x, y), after.rgb(x, y));
        p.iter().zip(q).any(|(a, b)| a.abs_diff(b) > 40)
    });
    assert!(
        changed > 100,
        "adding the lamp changed only {changed} pixels"
    );
}
