//! Planar linkages built from spatial revolutes (every pin along world z, every
//! link a rod in the plane z = 0): the Peaucellier–Lipkin straight-line
//! linkage of `scenes/peaucellier.toml` and a planar four-bar. A closed loop
//! of such pins repeats its out-of-plane rows: the four-bar has 3 redundant
//! rows, the Peaucellier linkage 9.

use haptloop_solver::{BodySpec, FingerSpec, JointKind, JointSpec, Model, ModelBuilder};
use nalgebra::{UnitQuaternion, Vector2, Vector3};

/// Mass of every link, kilograms (the scene's 20 g rods).
pub const LINK_KG: f64 = 0.02;

/// A builder of rods in z = 0 pinned along world z.
pub struct Planar {
    b: ModelBuilder,
    links: Vec<(String, Vector3<f64>, UnitQuaternion<f64>)>,
}

fn p3(p: Vector2<f64>) -> Vector3<f64> {
    Vector3::new(p.x, p.y, 0.0)
}

impl Planar {
    /// An empty linkage with a fixed `ground` and the given gravity.
    pub fn new(gravity: [f64; 3]) -> Self {
        let mut b = ModelBuilder::new();
        b.gravity(gravity);
        b.body(BodySpec::fixed("ground"));
        Self {
            b,
            links: vec![(
                "ground".into(),
                Vector3::zeros(),
                UnitQuaternion::identity(),
            )],
        }
    }

    /// A 20 g rod from `from` to `to` (its body z), placed at its midpoint.
    pub fn link(&mut self, name: &str, from: Vector2<f64>, to: Vector2<f64>) {
        let d = p3(to - from);
        let len = d.norm();
        let rot = UnitQuaternion::rotation_between(&Vector3::z(), &(d / len)).unwrap();
        let mid = p3((from + to) / 2.0);
        let t = LINK_KG * len * len / 12.0;
        let q = rot.quaternion();
        self.b.body(
            BodySpec::new(name)
                .at(mid.into())
                .oriented([q.w, q.i, q.j, q.k])
                .mass(LINK_KG)
                .inertia([t, t, 0.01 * t]),
        );
        self.links.push((name.into(), mid, rot));
    }

    fn local(&self, body: &str, world: Vector3<f64>, point: bool) -> [f64; 3] {
        let (_, p, r) = self.links.iter().find(|(n, ..)| n == body).unwrap();
        let v = if point { world - p } else { world };
        (r.inverse() * v).into()
    }

    /// A revolute between `i` and `j` at world point `at`, axis world z.
    pub fn pin(&mut self, name: &str, i: &str, j: &str, at: Vector2<f64>) {
        let z = Vector3::z();
        let spec = JointSpec::new(JointKind::Revolute, i, j)
            .named(name)
            .anchors(self.local(i, p3(at), true), self.local(j, p3(at), true))
            .axes(self.local(i, z, false), self.local(j, z, false));
        self.b.joint(spec);
    }

    /// A point finger on `body` at world point `at`.
    pub fn finger(&mut self, body: &str, at: Vector2<f64>) {
        let p = self.local(body, p3(at), true);
        self.b.finger(FingerSpec::point("index", body, p));
    }

    pub fn build(self) -> Model {
        self.b.build().expect("the planar linkage builds")
    }
}

/// Peaucellier geometry (metres): pivots O = (0, 0), O2 = (R, 0); long links
/// a, rhombus sides b, crank R at `CRANK_RAD` from O2. Q, the inverse of P,
/// runs on the line x = (a² − b²)/(2R) = 0.084.
pub const R: f64 = 0.05;
pub const A: f64 = 0.10;
pub const B: f64 = 0.04;
pub const CRANK_RAD: f64 = std::f64::consts::FRAC_PI_3;
/// x of the straight line Q follows.
pub const LINE_X: f64 = (A * A - B * B) / (2.0 * R);
/// y of the dead point on Q's line: where the crank circle crosses the line,
/// P = Q and the rhombus is flat; the linkage can fold there (Q then follows
/// the crank circle).
pub fn dead_point_y() -> f64 {
    (R * R - (LINE_X - R) * (LINE_X - R)).sqrt()
}

/// The Peaucellier–Lipkin linkage of `scenes/peaucellier.toml`, assembled,
/// its finger on Q.
pub fn peaucellier(gravity: [f64; 3]) -> Model {
    let o = Vector2::zeros();
    let o2 = Vector2::new(R, 0.0);
    let p = o2 + Vector2::new(CRANK_RAD.cos(), CRANK_RAD.sin()) * R;
    let d = p.norm();
    let u = p / d;
    let x = (A * A - B * B + d * d) / (2.0 * d);
    let h = (A * A - x * x).sqrt();
    let perp = Vector2::new(-u.y, u.x);
    let a = u * x + perp * h;
    let b = u * x - perp * h;
    let q = u * (2.0 * x) - p;
    let mut l = Planar::new(gravity);
    l.link("crank", o2, p);
    l.link("long-a", o, a);
    l.link("long-b", o, b);
    l.link("side-ap", a, p);
    l.link("side-pb", p, b);
    l.link("side-bq", b, q);
    l.link("side-qa", q, a);
    l.pin("O-a", "ground", "long-a", o);
    l.pin("O-b", "ground", "long-b", o);
    l.pin("O2", "ground", "crank", o2);
    l.pin("P-crank", "crank", "side-ap", p);
    l.pin("P-side", "side-ap", "side-pb", p);
    l.pin("A-ap", "long-a", "side-ap", a);
    l.pin("A-qa", "long-a", "side-qa", a);
    l.pin("B-pb", "long-b", "side-pb", b);
    l.pin("B-bq", "long-b", "side-bq", b);
    l.pin("Q", "side-bq", "side-qa", q);
    l.finger("side-bq", q);
    l.build()
}

/// A planar crank-rocker four-bar: ground pivots (0, 0) and (0.10, 0), crank
/// 0.04 at 70°, coupler 0.09, rocker 0.07; the finger at the coupler's middle.
pub fn planar_four_bar(gravity: [f64; 3]) -> Model {
    let (o, o2) = (Vector2::zeros(), Vector2::new(0.10, 0.0));
    let t = 70f64.to_radians();
    let a = Vector2::new(t.cos(), t.sin()) * 0.04;
    // B: on the circle (A, 0.09) and the circle (O2, 0.07), the upper one.
    let (d, u) = ((o2 - a).norm(), (o2 - a).normalize());
    let x = (0.09f64.powi(2) - 0.07f64.powi(2) + d * d) / (2.0 * d);
    let h = (0.09f64.powi(2) - x * x).sqrt();
    let b = a + u * x + Vector2::new(-u.y, u.x) * h;
    let mut l = Planar::new(gravity);
    l.link("crank", o, a);
    l.link("coupler", a, b);
    l.link("rocker", o2, b);
    l.pin("O", "ground", "crank", o);
    l.pin("A", "crank", "coupler", a);
    l.pin("B", "coupler", "rocker", b);
    l.pin("O2", "ground", "rocker", o2);
    l.finger("coupler", (a + b) / 2.0);
    l.build()
}

/// A ladder of `cells` square cells of side 5 cm in z = 0: rails and rungs
/// are rods, every corner a pin; the first rung is pinned to the ground. Each
/// cell closes a loop, so each repeats 3 out-of-plane rows.
pub fn ladder(cells: usize) -> Model {
    let mut p = Planar::new([0.0, 0.0, -9.81]);
    let h = 0.05;
    for k in 0..=cells {
        let x = k as f64 * h;
        p.link(&format!("v{k}"), Vector2::new(x, 0.0), Vector2::new(x, h));
    }
    for k in 0..cells {
        let (x0, x1) = (k as f64 * h, (k + 1) as f64 * h);
        let (b, t) = (format!("b{k}"), format!("t{k}"));
        p.link(&b, Vector2::new(x0, 0.0), Vector2::new(x1, 0.0));
        p.link(&t, Vector2::new(x0, h), Vector2::new(x1, h));
        let (v0, v1) = (format!("v{k}"), format!("v{}", k + 1));
        p.pin(&format!("{b}a"), &b, &v0, Vector2::new(x0, 0.0));
        p.pin(&format!("{b}b"), &b, &v1, Vector2::new(x1, 0.0));
        p.pin(&format!("{t}a"), &t, &v0, Vector2::new(x0, h));
        p.pin(&format!("{t}b"), &t, &v1, Vector2::new(x1, h));
    }
    p.pin("ground-pin", "ground", "v0", Vector2::new(0.0, 0.0));
    p.finger(&format!("v{cells}"), Vector2::new(cells as f64 * h, h));
    p.build()
}

/// A link hanging from the ground by `n` identical revolutes (axis y, pin at
/// the origin, link centre 5 cm below), with a point finger at its centre:
/// every joint after the first repeats the first's 5 rows.
pub fn many_revolutes(n: usize) -> Model {
    let mut b = ModelBuilder::new();
    b.gravity([0.0, 0.0, -9.81]);
    b.body(BodySpec::fixed("ground"));
    b.body(BodySpec::new("crank").at([0.0, 0.0, -0.05]).mass(0.05));
    for k in 0..n {
        b.joint(
            JointSpec::new(JointKind::Revolute, "ground", "crank")
                .named(format!("j{k}"))
                .anchors([0.0; 3], [0.0, 0.0, 0.05])
                .axes([0.0, 1.0, 0.0], [0.0, 1.0, 0.0]),
        );
    }
    b.finger(FingerSpec::point("index", "crank", [0.0; 3]));
    b.build().expect("the revolute stack builds")
}
