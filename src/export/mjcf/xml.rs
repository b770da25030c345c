//! The MJCF text: options, the body tree with its joints, mocap hands, and
//! the loop closures and finger ties as equality constraints.

use super::input::{JointView, Mechanism};
use super::tree::{Closure, Tree};
use super::{Options, Stiffness};
use haptloop_solver::JointKind;
use nalgebra::{UnitQuaternion, Vector3};

/// The finger ties' `solref`: a 20 ms time constant, soft like haptloop's
/// 400 N/m virtual coupling, so an unreachable hand loads the mechanism
/// instead of tearing its joints.
pub const FINGER_SOLREF: &str = "0.02 1";
/// MuJoCo's own default `solimp`, written out for the finger ties so a
/// `<default>` for the joints does not reach them.
pub const FINGER_SOLIMP: &str = "0.9 0.95 0.001 0.5 2";
/// The stiff loops' `solimp`.
pub const STIFF_SOLIMP: &str = "0.99 0.999 0.001";

fn num(x: f64) -> String {
    // Shortest round-trip form; MuJoCo reads it with strtod.
    format!("{x:?}")
}

fn vec3(v: &Vector3<f64>) -> String {
    format!("{} {} {}", num(v.x), num(v.y), num(v.z))
}

fn quat(q: &UnitQuaternion<f64>) -> String {
    let q = q.quaternion();
    format!("{} {} {} {}", num(q.w), num(q.i), num(q.j), num(q.k))
}

/// `s` escaped for a double-quoted XML attribute.
pub fn attr(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('"', "&quot;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

/// The mocap body of a finger.
pub fn hand_body(finger: &str) -> String {
    format!("hand.{finger}")
}

struct Writer<'a> {
    m: &'a Mechanism,
    tree: &'a Tree,
    options: &'a Options,
    out: String,
}

impl Writer<'_> {
    fn line(&mut self, depth: usize, text: &str) {
        for _ in 0..depth {
            self.out.push_str("  ");
        }
        self.out.push_str(text);
        self.out.push('\n');
    }

    fn damping(&self) -> String {
        if self.options.damping > 0.0 {
            format!(r#" damping="{}""#, num(self.options.damping))
        } else {
            String::new()
        }
    }

    /// The tree joint(s) of `child`, which hangs from joint `j`.
    fn joint(&mut self, depth: usize, child: usize, j: &JointView) {
        let side = if j.bodies[1] == child { 1 } else { 0 };
        let rot = self.m.bodies[child].rotation;
        let pos = vec3(&j.anchors[side]);
        let name = attr(&j.name);
        let damp = self.damping();
        let to_child = |v: Vector3<f64>| rot.inverse() * v;
        match j.kind {
            JointKind::Revolute => {
                // Right-handed about A_i h_i, zero at q0: haptloop's angle of j
                // relative to i, negated when the child is body i.
                let axis = to_child(self.m.world_axis(j, 0).expect("axes"));
                let range = j.limits.map_or(String::new(), |[lo, hi]| {
                    let (lo, hi) = if side == 1 { (lo, hi) } else { (-hi, -lo) };
                    format!(r#" range="{} {}""#, num(lo), num(hi))
                });
                let text = format!(
                    r#"<joint name="{name}" type="hinge" pos="{pos}" axis="{}"{damp}{range}/>"#,
                    vec3(&axis)
                );
                self.line(depth, &text);
            }
            JointKind::Universal => {
                // The parent's axis first (fixed in the parent), then the
                // child's own (fixed in the child): a Hooke joint.
                let parent_axis = to_child(self.m.world_axis(j, 1 - side).expect("axes"));
                let own = j.axes.expect("axes")[side];
                for (k, a) in [(1, parent_axis), (2, own)] {
                    let text = format!(
                        r#"<joint name="{name}.{k}" type="hinge" pos="{pos}" axis="{}"{damp}/>"#,
                        vec3(&a)
                    );
                    self.line(depth, &text);
                }
            }
            JointKind::Prismatic => {
                // The displacement (A_i h_i)·(p_j − p_i), measured from q0.
                let world = self.m.world_axis(j, 0).expect("axes");
                let axis = if side == 1 {
                    to_child(world)
                } else {
                    -to_child(world)
                };
                let s0 = world.dot(&(self.m.world_point(j, 1) - self.m.world_point(j, 0)));
                let range = j.limits.map_or(String::new(), |[lo, hi]| {
                    format!(r#" range="{} {}""#, num(lo - s0), num(hi - s0))
                });
                let text = format!(
                    r#"<joint name="{name}" type="slide" pos="{pos}" axis="{}"{damp}{range}/>"#,
                    vec3(&axis)
                );
                self.line(depth, &text);
            }
            JointKind::Spherical => {
                let text = format!(r#"<joint name="{name}" type="ball" pos="{pos}"{damp}/>"#);
                self.line(depth, &text);
            }
            _ => {} // fixed: the child is welded to its parent
        }
    }

    fn body(&mut self, depth: usize, b: usize) {
        let body = &self.m.bodies[b];
        let (pp, pq) = match self.tree.parent[b] {
            Some(p) => (self.m.bodies[p].position, self.m.bodies[p].rotation),
            None => (Vector3::zeros(), UnitQuaternion::identity()),
        };
        let rel_pos = pq.inverse() * (body.position - pp);
        let rel_rot = pq.inverse() * body.rotation;
        let text = format!(
            r#"<body name="{}" pos="{}" quat="{}">"#,
            attr(&body.name),
            vec3(&rel_pos),
            quat(&rel_rot)
        );
        self.line(depth, &text);
        let text = format!(
            r#"<inertial pos="0 0 0" mass="{}" diaginertia="{}"/>"#,
            num(body.mass),
            vec3(&body.inertia)
        );
        self.line(depth + 1, &text);
        if self.tree.roots.contains(&b) {
            let text = format!(r#"<freejoint name="{}.free"/>"#, attr(&body.name));
            self.line(depth + 1, &text);
        } else if let Some(k) = self.tree.via[b] {
            let j = &self.m.joints[k];
            self.joint(depth + 1, b, j);
        }
        for &c in &self.tree.children[b] {
            self.body(depth + 1, c);
        }
        self.line(depth, "</body>");
    }

    fn closure(&mut self, k: usize, how: Closure) {
        let j = &self.m.joints[k];
        // body1 is a moving body (anchors are in its frame); body2 may be the world.
        let side = if self.m.bodies[j.bodies[0]].fixed {
            1
        } else {
            0
        };
        let b1 = attr(&self.m.bodies[j.bodies[side]].name);
        let other = &self.m.bodies[j.bodies[1 - side]];
        let b2 = if other.fixed {
            "world".to_owned()
        } else {
            attr(&other.name)
        };
        let name = attr(&j.name);
        let anchor = j.anchors[side];
        match how {
            Closure::Weld => {
                let text = format!(r#"<weld name="{name}" body1="{b1}" body2="{b2}"/>"#);
                self.line(2, &text);
            }
            Closure::Connect | Closure::TwoConnects => {
                let text = format!(
                    r#"<connect name="{name}" body1="{b1}" body2="{b2}" anchor="{}"/>"#,
                    vec3(&anchor)
                );
                self.line(2, &text);
                if how == Closure::TwoConnects {
                    let far =
                        anchor + j.axes.expect("a revolute joint has axes")[side] * self.m.length_m;
                    let text = format!(
                        r#"<connect name="{name}.axis" body1="{b1}" body2="{b2}" anchor="{}"/>"#,
                        vec3(&far)
                    );
                    self.line(2, &text);
                }
            }
        }
    }
}

/// The MJCF of `m` with `tree`.
pub fn write(m: &Mechanism, tree: &Tree, options: &Options) -> String {
    let mut w = Writer {
        m,
        tree,
        options,
        out: String::new(),
    };
    let rate = f64::from(options.rate_hz.unwrap_or(m.rate_hz));
    w.line(0, &format!(r#"<mujoco model="{}">"#, attr(&m.name)));
    w.line(1, r#"<compiler angle="radian" autolimits="true"/>"#);
    let text = format!(
        r#"<option timestep="{}" solver="Newton" gravity="{}">"#,
        num(1.0 / rate),
        vec3(&m.gravity)
    );
    w.line(1, &text);
    w.line(2, r#"<flag contact="disable"/>"#);
    w.line(1, "</option>");
    if let Stiffness::Timesteps(n) = options.stiffness {
        let solref = format!("{} 1", num(n / rate));
        w.line(1, "<default>");
        let text = format!(r#"<joint solreflimit="{solref}" solimplimit="{STIFF_SOLIMP}"/>"#);
        w.line(2, &text);
        let text = format!(r#"<equality solref="{solref}" solimp="{STIFF_SOLIMP}"/>"#);
        w.line(2, &text);
        w.line(1, "</default>");
    }
    w.line(1, "<worldbody>");
    for &c in &tree.world_children {
        w.body(2, c);
    }
    for f in &m.fingers {
        let b = &m.bodies[f.body];
        let start = b.position + b.rotation * f.point;
        let q = if f.rigid {
            b.rotation
        } else {
            UnitQuaternion::identity()
        };
        let text = format!(
            r#"<body name="{}" mocap="true" pos="{}" quat="{}"/>"#,
            attr(&hand_body(&f.name)),
            vec3(&start),
            quat(&q)
        );
        w.line(2, &text);
    }
    w.line(1, "</worldbody>");
    w.line(1, "<equality>");
    for &(k, how) in &tree.closures {
        w.closure(k, how);
    }
    for f in &m.fingers {
        let body = attr(&m.bodies[f.body].name);
        let hand = attr(&hand_body(&f.name));
        let name = attr(&format!("finger.{}", f.name));
        let tie = if f.rigid {
            format!(r#"<weld name="{name}" body1="{body}" body2="{hand}""#)
        } else {
            format!(
                r#"<connect name="{name}" body1="{body}" body2="{hand}" anchor="{}""#,
                vec3(&f.point)
            )
        };
        let text = format!(r#"{tie} solref="{FINGER_SOLREF}" solimp="{FINGER_SOLIMP}"/>"#);
        w.line(2, &text);
    }
    w.line(1, "</equality>");
    w.line(0, "</mujoco>");
    w.out
}
