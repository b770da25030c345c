//! Small models exercising one constraint kind each, and random states.

use haptloop_solver::{
    BodySpec, Bounds, DesignParam as P, FingerSpec, FingerTarget, JointKind as K, JointSpec, Model,
    ModelBuilder, PlaneOwner, PointPlaneSpec,
};
use nalgebra::{Quaternion, UnitQuaternion, Vector3};

/// Two moving bodies `a`, `b` and a fixed `ground`, in general poses.
pub fn bodies() -> ModelBuilder {
    let mut b = ModelBuilder::new();
    b.body(
        BodySpec::fixed("ground")
            .at([0.1, -0.2, 0.05])
            .oriented([0.9, 0.1, -0.3, 0.2]),
    );
    b.body(
        BodySpec::new("a")
            .at([0.3, 0.1, 0.2])
            .oriented([0.8, 0.2, 0.4, -0.1]),
    );
    b.body(
        BodySpec::new("b")
            .at([-0.2, 0.4, 0.1])
            .oriented([0.5, -0.5, 0.1, 0.6]),
    );
    b
}

fn build(b: &ModelBuilder) -> Model {
    b.build().expect("test model builds")
}

const KI: [f64; 3] = [0.1, -0.05, 0.2];
const KJ: [f64; 3] = [-0.15, 0.1, 0.05];

pub fn spherical() -> Model {
    let mut b = bodies();
    b.joint(
        JointSpec::new(K::Spherical, "a", "b")
            .anchors(KI, KJ)
            .free(&[P::AnchorI, P::AnchorJ]),
    );
    b.joint(
        JointSpec::new(K::Spherical, "ground", "a")
            .anchors(KJ, KI)
            .free(&[P::AnchorI]),
    );
    build(&b)
}

pub fn perpendicular() -> Model {
    let mut b = bodies();
    b.joint(JointSpec::new(K::Perpendicular, "a", "b").axes([1.0, 0.2, 0.0], [0.3, 1.0, -0.4]));
    b.joint(JointSpec::new(K::Perpendicular, "a", "ground").axes([0.0, 0.0, 1.0], [1.0, 0.0, 0.0]));
    build(&b)
}

pub fn universal() -> Model {
    let mut b = bodies();
    b.joint(
        JointSpec::new(K::Universal, "a", "b")
            .anchors(KI, KJ)
            .axes([1.0, 0.0, 0.2], [0.0, 1.0, 0.3])
            .free(&[P::AnchorJ]),
    );
    b.joint(
        JointSpec::new(K::Universal, "ground", "b")
            .anchors(KI, KJ)
            .axes([0.0, 0.0, 1.0], [1.0, 0.0, 0.0]),
    );
    build(&b)
}

pub fn revolute() -> Model {
    let mut b = bodies();
    b.joint(
        JointSpec::new(K::Revolute, "a", "b")
            .anchors(KI, KJ)
            .axes([0.2, 0.3, 1.0], [1.0, -0.2, 0.1])
            .limits(-1.0, 1.5)
            .free(&[P::AnchorI, P::AnchorJ]),
    );
    b.joint(
        JointSpec::new(K::Revolute, "ground", "a")
            .anchors(KJ, KI)
            .axes([0.0, 1.0, 0.0], [0.0, 1.0, 0.0]),
    );
    build(&b)
}

pub fn prismatic() -> Model {
    let mut b = bodies();
    b.joint(
        JointSpec::new(K::Prismatic, "a", "b")
            .anchors(KI, KJ)
            .axes([0.0, 0.3, 1.0], [1.0, 0.1, 0.0])
            .limits(-0.1, 0.2)
            .free(&[P::AnchorJ, P::AnchorI]),
    );
    b.joint(
        JointSpec::new(K::Prismatic, "b", "ground")
            .anchors(KJ, KI)
            .axes([1.0, 0.0, 0.0], [0.0, 0.0, 1.0]),
    );
    build(&b)
}

pub fn fixed() -> Model {
    let mut b = bodies();
    b.joint(
        JointSpec::new(K::Fixed, "a", "b")
            .anchors(KI, KJ)
            .free(&[P::AnchorI]),
    );
    b.joint(JointSpec::new(K::Fixed, "ground", "a").anchors(KJ, KI));
    build(&b)
}

pub fn distance() -> Model {
    let mut b = bodies();
    b.joint(
        JointSpec::new(K::Distance, "a", "b")
            .anchors(KI, KJ)
            .length(0.4)
            .limits(0.2, 0.6)
            .free(&[P::Length, P::AnchorI, P::AnchorJ]),
    );
    b.joint(
        JointSpec::new(K::Distance, "a", "ground")
            .anchors(KJ, KI)
            .limits(0.1, 2.0),
    );
    build(&b)
}

pub fn point_on_plane() -> Model {
    let mut b = bodies();
    b.joint(
        JointSpec::new(K::PointOnPlane, "a", "b")
            .anchors(KI, KJ)
            .axes([0.0; 3], [0.3, -0.2, 1.0])
            .free(&[P::AnchorI, P::AnchorJ]),
    );
    b.joint(
        JointSpec::new(K::PointOnPlane, "b", "ground")
            .anchors(KJ, KI)
            .axes([0.0; 3], [0.0, 0.0, 1.0]),
    );
    build(&b)
}

/// Fixed bodies with free positions (one bounded per component with a
/// pinned z, one bounded by one range) joined to moving bodies by several
/// kinds, plus a bounded free length and a bounded anchor.
pub fn free_positions() -> Model {
    let mut b = bodies();
    b.body(
        BodySpec::fixed("foot")
            .at([0.2, 0.3, -0.1])
            .oriented([0.7, 0.1, 0.5, -0.2])
            .free_position()
            .bounds(Bounds::Vector([[-1.0, -1.0, -0.1], [1.0, 1.0, -0.1]])),
    );
    b.body(
        BodySpec::fixed("base")
            .at([-0.1, 0.0, 0.2])
            .free_position()
            .bounds(Bounds::Scalar([-1.0, 1.0])),
    );
    b.joint(JointSpec::new(K::Spherical, "foot", "a").anchors(KI, KJ));
    b.joint(
        JointSpec::new(K::Revolute, "b", "base")
            .anchors(KJ, KI)
            .axes([0.2, 0.3, 1.0], [1.0, -0.2, 0.1])
            .limits(-1.0, 1.5),
    );
    b.joint(
        JointSpec::new(K::Distance, "foot", "b")
            .anchors(KI, KJ)
            .length(0.4)
            .free(&[P::Length, P::AnchorI])
            .bounds(Bounds::Scalar([-2.0, 2.0])),
    );
    b.joint(
        JointSpec::new(K::Prismatic, "base", "a")
            .anchors(KJ, KI)
            .axes([0.0, 0.3, 1.0], [1.0, 0.1, 0.0]),
    );
    build(&b)
}

/// Gear pairs and racks in every arrangement of their joints' bodies: both
/// gears on the fixed ground, a gear riding on its mate (joint a–b), a rack
/// on the ground and a pinion on a sliding carriage (prismatic ground–b,
/// pinion b–a), with a free anchor on a revolute (its angle ignores it).
pub fn gears() -> Model {
    use haptloop_solver::GearSpec;
    let mut b = bodies();
    b.joint(
        JointSpec::new(K::Revolute, "ground", "a")
            .named("ra")
            .anchors(KJ, KI)
            .axes([0.0, 1.0, 0.0], [0.0, 1.0, 0.0])
            .free(&[P::AnchorJ]),
    );
    b.joint(
        JointSpec::new(K::Revolute, "ground", "b")
            .named("rb")
            .anchors(KI, KJ)
            .axes([0.2, 0.3, 1.0], [1.0, -0.2, 0.1]),
    );
    b.joint(
        JointSpec::new(K::Revolute, "b", "a")
            .named("rba")
            .anchors(KJ, KI)
            .axes([0.0, 0.3, 1.0], [1.0, 0.1, 0.0]),
    );
    b.joint(
        JointSpec::new(K::Prismatic, "ground", "b")
            .named("pb")
            .anchors(KI, KJ)
            .axes([1.0, 0.0, 0.2], [0.0, 1.0, 0.0]),
    );
    b.joint(
        JointSpec::new(K::Prismatic, "a", "b")
            .named("pab")
            .anchors(KI, KJ)
            .axes([0.1, 1.0, 0.0], [1.0, 0.0, 0.3]),
    );
    b.gear(GearSpec::gear("g-ground", "ra", "rb", -0.5));
    b.gear(GearSpec::gear("g-riding", "rb", "rba", 3.0));
    b.gear(GearSpec::rack_pinion("k-ground", "ra", "pb", 0.02));
    b.gear(GearSpec::rack_pinion("k-carriage", "rba", "pb", -0.05));
    b.gear(GearSpec::rack_pinion("k-moving", "rb", "pab", 0.04));
    build(&b)
}

pub fn fingers() -> Model {
    let mut b = bodies();
    b.finger(FingerSpec::point("index", "a", [0.05, 0.1, -0.02]));
    b.finger(FingerSpec::rigid("palm", "b", [-0.03, 0.02, 0.07]));
    build(&b)
}

pub fn point_plane_inequalities() -> Model {
    let base = build(&bodies());
    let [ground, a, b] = ["ground", "a", "b"].map(|n| base.body_id(n).unwrap());
    let spec = |name: &str, body, plane| PointPlaneSpec {
        name: name.into(),
        body,
        point_m: KI,
        plane,
        plane_point_m: KJ,
        normal: [0.2, -0.4, 1.0],
    };
    base.with_inequalities(&[
        spec("a-on-b", a, PlaneOwner::Body(b)),
        spec("b-on-world", b, PlaneOwner::World),
        spec("a-on-ground", a, PlaneOwner::Body(ground)),
        spec("ground-on-b", ground, PlaneOwner::Body(b)),
    ])
    .expect("inequalities build")
}

/// Maps uniform numbers in [-1, 1] to a state: positions in [-0.5, 0.5] m,
/// quaternions of random direction with norm in [0.6, 1.5] (non-unit on
/// purpose), anchors in [-0.2, 0.2] m, lengths in [0.1, 0.5] m, and random
/// finger targets. `u` must hold `state_len(model)` numbers.
pub fn state(model: &Model, u: &[f64]) -> (Vec<f64>, Vec<FingerTarget>) {
    let mut q = model.q0().to_vec();
    let mut it = u.iter().copied();
    let mut next = || it.next().expect("enough random numbers");
    for (_, o) in model.layout().moving_bodies() {
        for k in 0..3 {
            q[o + k] = 0.5 * next();
        }
        let e = Vector3::new(next(), next(), next());
        let w = next();
        let dir = Quaternion::new(w, e.x, e.y, e.z);
        let dir = if dir.norm() < 1e-3 {
            Quaternion::identity()
        } else {
            dir / dir.norm()
        };
        let norm = 0.6 + 0.45 * (next() + 1.0);
        q[o + 3..o + 7].copy_from_slice(&[dir.w * norm, dir.i * norm, dir.j * norm, dir.k * norm]);
    }
    for d in model.layout().design_vars() {
        for k in 0..d.width {
            q[d.offset + k] = if d.width == 1 {
                0.3 + 0.2 * next()
            } else {
                0.2 * next()
            };
        }
    }
    let targets = model
        .fingers()
        .iter()
        .map(|_| FingerTarget {
            position_m: Vector3::new(next(), next(), next()) * 0.5,
            orientation: UnitQuaternion::from_scaled_axis(
                Vector3::new(next(), next(), next()) * 3.0,
            ),
        })
        .collect();
    (q, targets)
}

/// How many uniform numbers [`state`] consumes.
pub fn state_len(model: &Model) -> usize {
    let bodies = model.layout().moving_bodies().count();
    let dv: usize = model.layout().design_vars().iter().map(|d| d.width).sum();
    bodies * 8 + dv + model.fingers().len() * 6
}

/// max |C(q0)| of a model at its initial configuration and targets.
pub fn initial_residual(model: &Model) -> f64 {
    let mut ev = model.evaluation();
    ev.evaluate(model, model.q0(), &model.initial_targets())
        .expect("evaluate q0");
    ev.values()[model.equality_rows()]
        .iter()
        .fold(0.0, |m, v| m.max(v.abs()))
}

/// The settings the joint-coordinate tests run a compiled scene with: its
/// `[solver]` step and iterations over the defaults, with `coordinates`.
/// Deliberately not `SceneSettings::solver_settings`: these tests compare
/// ticks at the solver's default gains, filter and dynamics.
pub fn step_and_iterations(
    settings: &haptloop_solver::scene::SceneSettings,
    coordinates: haptloop_solver::Coordinates,
) -> haptloop_solver::SolverSettings {
    let mut s = haptloop_solver::SolverSettings {
        coordinates,
        ..haptloop_solver::SolverSettings::default()
    };
    if let Some(v) = settings.step {
        s.step = v;
    }
    if let Some(v) = settings.iterations {
        s.iterations = v;
    }
    s
}
