//! The scenes' edits: a built-in scene's TOML changed (masses, geometry,
//! the hands' paths) before it is loaded.

use haptloop::scenes::{BUILTIN, Scene, check_loaded};
use std::path::Path;
use toml::{Table, Value};

/// A built-in scene with its TOML edited by `f`.
pub(super) fn edited(name: &str, f: impl FnOnce(&mut Table)) -> Scene {
    let text = BUILTIN.iter().find(|b| b.name == name).unwrap().text;
    let mut t: Table = text.parse().unwrap();
    f(&mut t);
    let text = toml::to_string(&t).unwrap();
    let loaded = haptloop_solver::scene::parse(
        &format!("stability/{name}.toml"),
        &text,
        Some(Path::new("scenes")),
    )
    .unwrap();
    check_loaded(loaded).unwrap_or_else(|e| panic!("{name}: {e}"))
}

pub(super) fn tables<'a>(t: &'a mut Table, key: &str) -> impl Iterator<Item = &'a mut Table> {
    t.get_mut(key)
        .and_then(Value::as_array_mut)
        .into_iter()
        .flatten()
        .filter_map(Value::as_table_mut)
}

fn scale_numbers(v: &mut Value, s: f64) {
    match v {
        Value::Float(x) => *x *= s,
        Value::Integer(i) => *v = Value::Float(*i as f64 * s),
        Value::Array(a) => a.iter_mut().for_each(|x| scale_numbers(x, s)),
        _ => {}
    }
}

/// Every moving body weighs `kg` (its inertia scaled with it).
pub(super) fn set_masses(t: &mut Table, kg: f64) {
    for b in tables(t, "body") {
        let Some(m) = b.get("mass").and_then(Value::as_float) else {
            continue;
        };
        if let Some(i) = b.get_mut("inertia") {
            scale_numbers(i, kg / m);
        }
        b.insert("mass".into(), Value::Float(kg));
    }
}

/// Every length × `s`: positions, anchors, lengths, prismatic limits,
/// finger points, the hand's path, shapes; inertias × s²; the scene's
/// violation tolerance × s (a relative accuracy).
pub(super) fn scale_geometry(t: &mut Table, s: f64) {
    for b in tables(t, "body") {
        for k in ["position", "shape"] {
            if let Some(v) = b.get_mut(k) {
                scale_numbers(v, s);
            }
        }
        if let Some(i) = b.get_mut("inertia") {
            scale_numbers(i, s * s);
        }
    }
    for j in tables(t, "joint") {
        let prismatic = j.get("kind").and_then(Value::as_str) == Some("prismatic");
        for k in ["anchors", "length"] {
            if let Some(v) = j.get_mut(k) {
                scale_numbers(v, s);
            }
        }
        if prismatic && let Some(v) = j.get_mut("limits") {
            scale_numbers(v, s);
        }
    }
    for f in tables(t, "finger") {
        if let Some(v) = f.get_mut("point") {
            scale_numbers(v, s);
        }
    }
    for d in tables(t, "device") {
        // The device's workspace scales too: the hand moves the arm as
        // before, and an encoder count is `s` times as long in the scene.
        let scale = d.get("scale").and_then(Value::as_float).unwrap_or(1.0);
        d.insert("scale".into(), Value::Float(scale * s));
        let Some(h) = d.get_mut("hand").and_then(Value::as_table_mut) else {
            continue;
        };
        if let Some(c) = h.get_mut("circle").and_then(Value::as_table_mut)
            && let Some(r) = c.get_mut("radius")
        {
            scale_numbers(r, s);
        }
        if let Some(l) = h.get_mut("line").and_then(Value::as_table_mut)
            && let Some(to) = l.get_mut("to")
        {
            scale_numbers(to, s);
        }
    }
    if let Some(tol) = t
        .get_mut("solver")
        .and_then(Value::as_table_mut)
        .and_then(|s| s.get_mut("violation_tolerance"))
    {
        scale_numbers(tol, s);
    }
}

/// Device `k`'s hand follows `points` (`[t, dx, dy, dz]`, scene frame).
pub(super) fn set_waypoints(t: &mut Table, k: usize, points: &[[f64; 4]]) {
    let d = tables(t, "device").nth(k).unwrap();
    let mut hand = Table::new();
    hand.insert(
        "waypoints".into(),
        Value::Array(
            points
                .iter()
                .map(|p| Value::Array(p.iter().map(|&x| Value::Float(x)).collect()))
                .collect(),
        ),
    );
    d.insert("hand".into(), Value::Table(hand));
}

/// A hand path out by `offset` over `ramp_s` at `t0`, held `hold_s`, and
/// back over `ramp_s`: (waypoints, time the disturbance ends).
pub(super) fn out_and_back(
    t0: f64,
    offset: [f64; 3],
    ramp_s: f64,
    hold_s: f64,
) -> (Vec<[f64; 4]>, f64) {
    let [x, y, z] = offset;
    let back = t0 + 2.0 * ramp_s + hold_s;
    (
        vec![
            [0.0, 0.0, 0.0, 0.0],
            [t0, 0.0, 0.0, 0.0],
            [t0 + ramp_s, x, y, z],
            [t0 + ramp_s + hold_s, x, y, z],
            [back, 0.0, 0.0, 0.0],
        ],
        back,
    )
}

pub(super) fn builtin(name: &str) -> Scene {
    edited(name, |_| {})
}
