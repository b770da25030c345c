//! Small mechanisms carrying one objective each, random states, and F by
//! finite differences.

use std::ops::{Deref, DerefMut};
use std::sync::Arc;

use haptloop_solver::{
    BodySpec, Bounds, BuildError, DesignParam as P, JointKind as K, JointSpec, Model, ModelBuilder,
    ObjectiveSpec, Objectives, ObstacleSpec,
};
use nalgebra::{Quaternion, Vector3};

/// A model builder plus objectives: the solver compiles objectives apart
/// from the model ([`Objectives::compile`], against the built model), as a
/// scene does.
#[derive(Default)]
pub struct Designer {
    builder: ModelBuilder,
    specs: Vec<ObjectiveSpec>,
}

impl Designer {
    pub fn new() -> Self {
        Self::default()
    }

    pub fn objective(&mut self, spec: ObjectiveSpec) -> &mut Self {
        self.specs.push(spec);
        self
    }

    /// The model, then its objectives compiled against it.
    pub fn build(&self) -> Result<Designed, BuildError> {
        let model = self.builder.build()?;
        let objectives = Arc::new(Objectives::compile(&self.specs, &model)?);
        Ok(Designed { model, objectives })
    }
}

impl Deref for Designer {
    type Target = ModelBuilder;
    fn deref(&self) -> &ModelBuilder {
        &self.builder
    }
}

impl DerefMut for Designer {
    fn deref_mut(&mut self) -> &mut ModelBuilder {
        &mut self.builder
    }
}

/// A model and its compiled objectives.
#[derive(Debug)]
pub struct Designed {
    pub model: Model,
    pub objectives: Arc<Objectives>,
}

impl Deref for Designed {
    type Target = Model;
    fn deref(&self) -> &Model {
        &self.model
    }
}

const Z: [f64; 3] = [0.0, 0.0, 1.0];
const Y: [f64; 3] = [0.0, 1.0, 0.0];

/// A spatial 3R arm (yaw at the base, pitch, pitch) whose fixed base has a
/// free position; links 0.3 m and 0.25 m; the hand point at the forearm's
/// tip. Elbow bent by `elbow` radians.
pub fn arm(elbow: f64) -> Designer {
    let mut b = Designer::new();
    b.body(
        BodySpec::fixed("base")
            .free_position()
            .bounds(Bounds::Scalar([-1.0, 1.0])),
    );
    b.body(BodySpec::new("turret").mass(0.2));
    b.body(BodySpec::new("upper").at([0.15, 0.0, 0.0]).mass(0.1));
    let (s, c) = elbow.sin_cos();
    let fore = [0.3 + 0.125 * c, 0.0, -0.125 * s];
    let q = nalgebra::UnitQuaternion::from_axis_angle(&Vector3::y_axis(), elbow);
    let q = q.quaternion();
    b.body(
        BodySpec::new("fore")
            .at(fore)
            .oriented([q.w, q.i, q.j, q.k])
            .mass(0.1),
    );
    b.joint(
        JointSpec::new(K::Revolute, "base", "turret")
            .named("yaw")
            .axes(Z, Z),
    );
    b.joint(
        JointSpec::new(K::Revolute, "turret", "upper")
            .named("shoulder")
            .anchors([0.0; 3], [-0.15, 0.0, 0.0])
            .axes(Y, Y)
            .limits(-1.5, 1.5),
    );
    b.joint(
        JointSpec::new(K::Revolute, "upper", "fore")
            .named("elbow")
            .anchors([0.15, 0.0, 0.0], [-0.125, 0.0, 0.0])
            .axes(Y, Y)
            .limits(-2.5, 2.5),
    );
    b
}

/// The arm with a dexterity objective at the hand (all three directions).
pub fn dexterity() -> Designed {
    let mut b = arm(1.0);
    b.objective(ObjectiveSpec::Dexterity {
        name: None,
        weight: 0.7,
        chain: ["base", "turret", "upper", "fore"]
            .map(String::from)
            .to_vec(),
        point_m: [0.125, 0.0, 0.0],
        directions: Vec::new(),
        angular_directions: Vec::new(),
        closure: Vec::new(),
    });
    b.build().expect("dexterity model")
}

/// The 3R arm with Eq. 13 as written: the three linear rows and the three
/// angular rows (6 rows, 3 columns: G = J̃ᵀ J̃).
pub fn dexterity_angular() -> Designed {
    let mut b = arm(0.8);
    b.objective(ObjectiveSpec::Dexterity {
        name: None,
        weight: 0.9,
        chain: ["base", "turret", "upper", "fore"]
            .map(String::from)
            .to_vec(),
        point_m: [0.125, 0.0, 0.0],
        directions: Vec::new(),
        angular_directions: vec![[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
        closure: Vec::new(),
    });
    b.build().expect("angular dexterity model")
}

/// The built-in spatial R-S-U-R four-bar as a closed chain (crank, coupler;
/// closed by the rocker), dexterity at the coupler's middle along one
/// direction (the loop has one degree of freedom). With `spin`, the
/// coupler–rocker joint is spherical instead: the coupler may also spin
/// about BC (two degrees of freedom), and an angular row joins.
pub fn dexterity_closed(spin: bool) -> Designed {
    let src = haptloop_solver::mechanisms::four_bar_builder();
    let mut b = Designer::new();
    for s in src.body_specs() {
        b.body(s.clone());
    }
    for j in src.joint_specs() {
        let mut j = j.clone();
        if spin && j.kind == K::Universal {
            j.kind = K::Spherical;
            j.axes = None;
        }
        b.joint(j);
    }
    b.objective(ObjectiveSpec::Dexterity {
        name: Some("loop".into()),
        weight: 1.1,
        chain: ["ground", "crank", "coupler"].map(String::from).to_vec(),
        point_m: [0.0, 0.01, 0.0],
        directions: vec![[0.3, 1.0, 0.2]],
        angular_directions: if spin {
            vec![[0.2, 0.1, 1.0]]
        } else {
            Vec::new()
        },
        closure: ["rocker", "ground"].map(String::from).to_vec(),
    });
    b.build().expect("closed chain")
}

/// A chain of every joint kind with a column form (spherical, universal,
/// prismatic, revolute with free anchors), two task directions.
pub fn dexterity_mixed() -> Designed {
    let mut b = Designer::new();
    b.body(BodySpec::fixed("ground"));
    b.body(BodySpec::new("a").at([0.1, 0.0, 0.0]));
    b.body(
        BodySpec::new("b")
            .at([0.25, 0.05, 0.0])
            .oriented([0.9, 0.1, 0.2, 0.3]),
    );
    b.body(BodySpec::new("c").at([0.35, 0.1, 0.05]));
    b.body(BodySpec::new("d").at([0.5, 0.1, 0.1]));
    b.joint(JointSpec::new(K::Spherical, "ground", "a").anchors([0.0; 3], [-0.1, 0.0, 0.0]));
    b.joint(
        JointSpec::new(K::Universal, "a", "b")
            .anchors([0.1, 0.0, 0.0], [-0.05, -0.05, 0.0])
            .axes([0.0, 0.0, 1.0], [0.2, 1.0, 0.1]),
    );
    b.joint(
        JointSpec::new(K::Prismatic, "b", "c")
            .anchors([0.05, 0.05, 0.0], [-0.05, -0.05, -0.05])
            .axes([1.0, 0.2, 0.0], [1.0, 0.0, 0.0]),
    );
    b.joint(
        JointSpec::new(K::Revolute, "d", "c")
            .anchors([-0.1, 0.0, 0.0], [0.05, 0.0, 0.05])
            .axes([0.3, 0.0, 1.0], [0.0, 0.2, 1.0])
            .free(&[P::AnchorI, P::AnchorJ]),
    );
    b.objective(ObjectiveSpec::Dexterity {
        name: None,
        weight: 1.3,
        chain: ["ground", "a", "b", "c", "d"].map(String::from).to_vec(),
        point_m: [0.05, 0.02, -0.01],
        directions: vec![[1.0, 0.0, 0.0], [0.0, 1.0, 0.2]],
        angular_directions: Vec::new(),
        closure: Vec::new(),
    });
    b.build().expect("mixed chain")
}

/// Three bodies' points near an obstacle point on a fourth, moving body.
pub fn obstacle(on_body: bool) -> Designed {
    let mut b = Designer::new();
    b.body(BodySpec::fixed("ground").free_position());
    b.body(BodySpec::new("a").at([0.1, 0.0, 0.0]));
    b.body(BodySpec::new("b").at([0.0, 0.2, 0.0]));
    b.body(BodySpec::new("bullet").at([0.05, 0.05, 0.1]));
    b.joint(JointSpec::new(K::Spherical, "ground", "a").anchors([0.0; 3], [-0.1, 0.0, 0.0]));
    let obstacle = if on_body {
        ObstacleSpec::Body {
            body: "bullet".into(),
            point_m: [0.01, 0.0, -0.02],
        }
    } else {
        ObstacleSpec::World([0.05, 0.05, 0.1])
    };
    b.objective(ObjectiveSpec::Obstacle {
        name: Some("dodge".into()),
        weight: 2.0,
        points: vec![
            ("a".into(), [0.05, 0.0, 0.0]),
            ("b".into(), [0.0, -0.05, 0.02]),
            ("ground".into(), [0.02, 0.02, 0.0]),
        ],
        obstacle,
        distance_m: 0.4,
    });
    b.build().expect("obstacle model")
}

/// Eq. 15 as written for the points of [`obstacle`] (world obstacle).
pub fn inverse_distance() -> Designed {
    let mut b = Designer::new();
    b.body(BodySpec::fixed("ground").free_position());
    b.body(BodySpec::new("a").at([0.1, 0.0, 0.0]));
    b.body(BodySpec::new("b").at([0.0, 0.2, 0.0]));
    b.joint(JointSpec::new(K::Spherical, "ground", "a").anchors([0.0; 3], [-0.1, 0.0, 0.0]));
    b.objective(ObjectiveSpec::InverseDistance {
        name: None,
        weight: 0.8,
        points: vec![
            ("a".into(), [0.05, 0.0, 0.0]),
            ("b".into(), [0.0, -0.05, 0.02]),
            ("ground".into(), [0.02, 0.02, 0.0]),
        ],
        obstacle: ObstacleSpec::World([0.05, 0.05, 0.1]),
    });
    b.build().expect("inverse distance model")
}

/// A three-link spherical chain with free anchors (every link's length a
/// design variable somewhere), workspace volume at the last body's point.
pub fn workspace() -> Designed {
    let mut b = Designer::new();
    b.body(BodySpec::fixed("ground"));
    b.body(BodySpec::new("a").at([0.1, 0.0, 0.0]));
    b.body(BodySpec::new("b").at([0.25, 0.05, 0.0]));
    b.body(BodySpec::new("c").at([0.4, 0.05, 0.05]));
    b.joint(
        JointSpec::new(K::Spherical, "ground", "a")
            .anchors([0.0; 3], [-0.1, 0.0, 0.0])
            .free(&[P::AnchorJ]),
    );
    b.joint(
        JointSpec::new(K::Universal, "a", "b")
            .anchors([0.08, 0.0, 0.0], [-0.07, -0.05, 0.0])
            .axes([0.0, 0.0, 1.0], [0.2, 1.0, 0.1])
            .free(&[P::AnchorI]),
    );
    b.joint(
        JointSpec::new(K::Revolute, "c", "b")
            .anchors([-0.1, 0.0, -0.05], [0.05, 0.0, 0.0])
            .axes([0.0, 1.0, 0.0], [0.0, 1.0, 0.0])
            .free(&[P::AnchorI, P::AnchorJ]),
    );
    b.objective(ObjectiveSpec::WorkspaceVolume {
        name: Some("reach".into()),
        weight: 1.5,
        chain: ["ground", "a", "b", "c"].map(String::from).to_vec(),
        point_m: [0.06, 0.01, 0.0],
    });
    b.build().expect("workspace model")
}

/// A body point on a world line.
pub fn straight_line() -> Designed {
    let mut b = Designer::new();
    b.body(
        BodySpec::new("a")
            .at([0.1, 0.2, 0.0])
            .oriented([0.8, 0.3, -0.2, 0.1]),
    );
    b.objective(ObjectiveSpec::StraightLine {
        name: None,
        weight: 0.5,
        body: "a".into(),
        point_m: [0.05, -0.03, 0.02],
        line_point_m: [0.0, 0.1, 0.0],
        direction: [1.0, 0.5, 0.0],
    });
    b.build().expect("line model")
}

/// Revolute, prismatic and distance limits (free anchors on two of them).
pub fn joint_limits() -> Designed {
    let mut b = Designer::new();
    b.body(BodySpec::fixed("ground").free_position());
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
    b.joint(
        JointSpec::new(K::Revolute, "ground", "a")
            .named("hinge")
            .anchors([0.0, 0.1, 0.0], [0.1, -0.05, 0.2])
            .axes([0.0, 1.0, 0.0], [0.2, 1.0, 0.0])
            .limits(-1.0, 0.5)
            .free(&[P::AnchorJ]),
    );
    b.joint(
        JointSpec::new(K::Prismatic, "a", "b")
            .named("slider")
            .anchors([0.1, -0.05, 0.2], [-0.15, 0.1, 0.05])
            .axes([0.0, 0.3, 1.0], [1.0, 0.1, 0.0])
            .limits(-0.1, 0.2),
    );
    b.joint(
        JointSpec::new(K::Distance, "b", "ground")
            .named("strut")
            .anchors([0.0; 3], [0.1, 0.0, 0.0])
            .limits(0.1, 2.0)
            .free(&[P::AnchorI]),
    );
    b.objective(ObjectiveSpec::JointLimitDistance {
        name: None,
        weight: 3.0,
        joints: Vec::new(),
    });
    b.build().expect("limits model")
}

/// A random state from uniform numbers in [-1, 1]: positions ±0.5 m around
/// q0, quaternions of random direction with norm in [0.6, 1.5] (non-unit on
/// purpose), design variables ±0.1 m around q0.
pub fn state(model: &Model, u: &[f64]) -> Vec<f64> {
    let mut q = model.q0().to_vec();
    let mut it = u.iter().copied();
    let mut next = || it.next().expect("enough random numbers");
    for (_, o) in model.layout().moving_bodies() {
        for k in 0..3 {
            q[o + k] += 0.2 * next();
        }
        let dir = Quaternion::new(next(), next(), next(), next());
        let dir = if dir.norm() < 1e-3 {
            Quaternion::identity()
        } else {
            dir / dir.norm()
        };
        let norm = 0.6 + 0.45 * (next() + 1.0);
        q[o + 3..o + 7].copy_from_slice(&[dir.w * norm, dir.i * norm, dir.j * norm, dir.k * norm]);
    }
    for x in &mut q[model.layout().body_coords()..] {
        *x += 0.1 * next();
    }
    q
}

/// How many numbers [`state`] consumes.
pub fn state_len(model: &Model) -> usize {
    model.layout().moving_bodies().count() * 8 + model.layout().design_coords()
}

/// Σ w_k F_k by a fresh evaluation.
pub fn total(model: &Designed, q: &[f64]) -> f64 {
    let mut ev = model.objectives.evaluation(model);
    let mut f = vec![0.0; model.objectives.terms.len()];
    ev.values(model, q, &mut f).expect("values");
    f.iter()
        .zip(&model.objectives.terms)
        .map(|(f, t)| f * t.weight)
        .sum()
}

/// The analytic gradient of Σ w_k F_k, and the total it returns.
pub fn gradient(model: &Designed, q: &[f64]) -> (Vec<f64>, f64) {
    let mut ev = model.objectives.evaluation(model);
    let mut g = vec![0.0; model.n_coords()];
    let f = ev.gradient(model, q, &mut g).expect("gradient");
    (g, f)
}

/// Central differences of [`total`] with step `h`.
pub fn fd(model: &Designed, q: &[f64], h: f64) -> Vec<f64> {
    let mut x = q.to_vec();
    (0..q.len())
        .map(|c| {
            x[c] = q[c] + h;
            let plus = total(model, &x);
            x[c] = q[c] - h;
            let minus = total(model, &x);
            x[c] = q[c];
            (plus - minus) / (2.0 * h)
        })
        .collect()
}
