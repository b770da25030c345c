//! Writing a [`ModelBuilder`]'s bodies, joints and fingers as scene-file
//! tables, so built-in scenes are printed from the same code that builds the
//! mechanisms (and a test proves the two agree).
//!
//! Numbers are written with Rust's shortest round-trip formatting, so a
//! written-then-parsed scene reproduces every `f64` bit for bit.

use crate::ModelBuilder;
use crate::model::{BodySpec, FingerSpec, JointSpec, Shape};
use std::fmt::Write as _;

fn num(x: f64) -> String {
    format!("{x:?}")
}

fn arr(xs: &[f64]) -> String {
    let parts: Vec<String> = xs.iter().map(|&x| num(x)).collect();
    format!("[{}]", parts.join(", "))
}

fn body(out: &mut String, b: &BodySpec) {
    let _ = writeln!(out, "[[body]]\nname = \"{}\"", b.name);
    if b.fixed {
        let _ = writeln!(out, "fixed = true");
    }
    let _ = writeln!(out, "position = {}", arr(&b.position_m));
    let _ = writeln!(out, "orientation = {}", arr(&b.orientation_wxyz));
    if let Some(m) = b.mass_kg {
        let _ = writeln!(out, "mass = {}", num(m));
    }
    if let Some(i) = b.inertia_kg_m2 {
        let _ = writeln!(out, "inertia = {}", arr(&i));
    }
    if let Some(d) = b.density_kg_m3 {
        let _ = writeln!(out, "density = {}", num(d));
    }
    if b.friction != 0.0 {
        let _ = writeln!(out, "friction = {}", num(b.friction));
    }
    match &b.shape {
        None => {}
        Some(Shape::Box { half_extents_m: h }) => {
            let _ = writeln!(out, "shape = {{ box = {} }}", arr(h));
        }
        Some(Shape::Sphere { radius_m }) => {
            let _ = writeln!(out, "shape = {{ sphere = {} }}", num(*radius_m));
        }
        Some(Shape::Capsule {
            half_height_m,
            radius_m,
        }) => {
            let _ = writeln!(
                out,
                "shape = {{ capsule = {{ half_height = {}, radius = {} }} }}",
                num(*half_height_m),
                num(*radius_m)
            );
        }
        Some(Shape::Convex { points_m }) => {
            let pts: Vec<String> = points_m.iter().map(|p| arr(p)).collect();
            let _ = writeln!(out, "shape = {{ convex = [{}] }}", pts.join(", "));
        }
    }
    if let Some(f) = &b.flexible {
        let _ = writeln!(
            out,
            "flexible = {{ span = {}, clamp = {}, stiffness = {}, stiffness_z = {}, modes = {} }}",
            arr(&f.span_m),
            num(f.clamp_m),
            num(f.stiffness_n_m2[0]),
            num(f.stiffness_n_m2[1]),
            f.modes
        );
    }
    out.push('\n');
}

fn joint(out: &mut String, j: &JointSpec) {
    let _ = writeln!(out, "[[joint]]");
    if let Some(n) = &j.name {
        let _ = writeln!(out, "name = \"{n}\"");
    }
    let _ = writeln!(out, "kind = \"{}\"", j.kind.as_str());
    let _ = writeln!(out, "bodies = [\"{}\", \"{}\"]", j.bodies[0], j.bodies[1]);
    let [a, b] = &j.anchors_m;
    let _ = writeln!(out, "anchors = [{}, {}]", arr(a), arr(b));
    if let Some([a, b]) = &j.axes {
        let _ = writeln!(out, "axes = [{}, {}]", arr(a), arr(b));
    }
    if let Some(l) = j.length_m {
        let _ = writeln!(out, "length = {}", num(l));
    }
    if let Some([lo, hi]) = j.limits {
        let _ = writeln!(out, "limits = [{}, {}]", num(lo), num(hi));
    }
    if !j.free.is_empty() {
        let names: Vec<String> = j
            .free
            .iter()
            .map(|p| format!("\"{}\"", p.as_str()))
            .collect();
        let _ = writeln!(out, "free = [{}]", names.join(", "));
    }
    if let Some(s) = &j.surface {
        use crate::parametric::SurfaceKind as K;
        let (kind, radius) = match s.kind {
            K::Plane => ("plane", None),
            K::Sphere { radius_m, concave } => {
                (if concave { "bowl" } else { "dome" }, Some(radius_m))
            }
            K::Cylinder { radius_m, concave } => {
                (if concave { "trough" } else { "ridge" }, Some(radius_m))
            }
        };
        let radius = radius.map_or(String::new(), |r| format!(", radius = {}", num(r)));
        let _ = writeln!(
            out,
            "surface = {{ type = \"{kind}\"{radius}, origin = {}, orientation = {} }}",
            arr(&s.origin_m),
            arr(&s.orientation_wxyz)
        );
    }
    if let Some(r) = j.radius_m {
        let _ = writeln!(out, "radius = {}", num(r));
    }
    out.push('\n');
}

fn finger(out: &mut String, f: &FingerSpec, device: &str) {
    if let Some(t) = f.tip {
        let _ = writeln!(
            out,
            "[[finger]]\nname = \"{}\"\ndevice = \"{device}\"\ngrasp = \"contact\"\nposition = {}\nradius = {}\nfriction = {}\n",
            f.name,
            arr(&t.position_m),
            num(t.radius_m),
            num(t.friction)
        );
        return;
    }
    let _ = writeln!(
        out,
        "[[finger]]\nname = \"{}\"\ndevice = \"{device}\"\nbody = \"{}\"\npoint = {}\ngrasp = \"{}\"\n",
        f.name,
        f.body,
        arr(&f.point_m),
        f.grasp.as_str()
    );
}

/// The `[[body]]`, `[[joint]]` and `[[finger]]` tables of `builder`, in scene
/// syntax; `device_of` names the `[[device]]` that drives each finger.
pub fn mechanism_tables(builder: &ModelBuilder, device_of: &dyn Fn(&str) -> String) -> String {
    let mut out = String::new();
    for b in builder.body_specs() {
        body(&mut out, b);
    }
    for j in builder.joint_specs() {
        joint(&mut out, j);
    }
    for f in builder.finger_specs() {
        finger(&mut out, f, &device_of(&f.name));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mechanisms;

    /// Written tables, with a header and one device per finger, compile to the
    /// same model the builder makes: same layout, same q0 bits, same C and C_q
    /// at q0.
    #[test]
    fn written_mechanisms_compile_to_identical_models() {
        for (name, builder) in [
            ("four-bar", mechanisms::four_bar_builder()),
            ("stewart", mechanisms::stewart_builder()),
            ("sphere-toy", mechanisms::sphere_toy_builder()),
        ] {
            let g = builder.gravity_m_s2();
            let mut text = format!("[scene]\nname = \"{name}\"\ngravity = {}\n\n", arr(&g));
            for f in builder.finger_specs() {
                text += &format!(
                    "[[device]]\nname = \"dev-{}\"\nmodel = \"phantom-premium-1.5\"\n\n",
                    f.name
                );
            }
            text += &mechanism_tables(&builder, &|f| format!("dev-{f}"));
            let scene =
                crate::scene::parse("t.toml", &text, None).unwrap_or_else(|e| panic!("{e}"));
            let compiled = scene.compile().unwrap_or_else(|e| panic!("{e}"));
            let (a, b) = (&compiled.model, &builder.build().unwrap());
            assert_eq!(
                (a.n_coords(), a.n_rows()),
                (b.n_coords(), b.n_rows()),
                "{name}"
            );
            assert_eq!(a.q0(), b.q0(), "{name}: q0 differs");
            let (mut ea, mut eb) = (a.evaluation(), b.evaluation());
            ea.evaluate(a, a.q0(), &a.initial_targets()).unwrap();
            eb.evaluate(b, b.q0(), &b.initial_targets()).unwrap();
            assert_eq!(ea.values(), eb.values(), "{name}: C differs");
            assert_eq!(
                ea.jacobian().values(),
                eb.jacobian().values(),
                "{name}: C_q differs"
            );
        }
    }
}
