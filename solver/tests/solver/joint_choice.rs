//! `coordinates = Auto | Joint`: what runs where the joint tick does not
//! apply, and the scene key.

use std::sync::Arc;

use haptloop_solver::{
    BodySpec, Coordinates, FingerSpec, JointKind as K, JointSpec, Model, ModelBuilder, Program,
    ProgramError, SolverSettings,
};

use super::joint_coordinates::scene;

/// A pendulum on a hinge with limits (a tree joint), one point finger.
pub fn limited_pendulum() -> Model {
    let mut b = ModelBuilder::new();
    b.body(BodySpec::fixed("ground"));
    b.body(BodySpec::new("arm").at([0.1, 0.0, 0.0]));
    b.joint(
        JointSpec::new(K::Revolute, "ground", "arm")
            .anchors([0.0; 3], [-0.1, 0.0, 0.0])
            .axes([0.0, 0.0, 1.0], [0.0, 0.0, 1.0])
            .limits(-0.5, 1.0),
    );
    b.finger(FingerSpec::point("index", "arm", [0.1, 0.0, 0.0]));
    b.build().unwrap()
}

/// A planar four-bar of revolutes whose loop-closing hinge (coupler–rocker:
/// the breadth-first tree reaches both ends first) has limits.
fn limited_loop() -> Model {
    let mut b = ModelBuilder::new();
    b.body(BodySpec::fixed("ground"));
    b.body(BodySpec::new("crank").at([0.0, 0.05, 0.0]));
    b.body(BodySpec::new("coupler").at([0.1, 0.1, 0.0]));
    b.body(BodySpec::new("rocker").at([0.2, 0.05, 0.0]));
    let z = [0.0, 0.0, 1.0];
    let hinge = |a: &str, b: &str, pa: [f64; 3], pb: [f64; 3]| {
        JointSpec::new(K::Revolute, a, b).anchors(pa, pb).axes(z, z)
    };
    b.joint(hinge("ground", "crank", [0.0; 3], [0.0, -0.05, 0.0]));
    b.joint(hinge(
        "ground",
        "rocker",
        [0.2, 0.0, 0.0],
        [0.0, -0.05, 0.0],
    ));
    b.joint(hinge(
        "crank",
        "coupler",
        [0.0, 0.05, 0.0],
        [-0.1, 0.0, 0.0],
    ));
    b.joint(hinge("coupler", "rocker", [0.1, 0.0, 0.0], [0.0, 0.05, 0.0]).limits(-1.0, 1.0));
    b.finger(FingerSpec::point("index", "coupler", [0.0, 0.0, 0.0]));
    b.build().unwrap()
}

/// `Auto` runs the augmented tick where the joint tick does not apply and
/// says why (limits on a loop-closing joint; contact rows), and the joint
/// tick where it does (a hinge with limits in the tree); `Joint` on the
/// models it refuses fails construction naming the reason.
#[test]
fn auto_chooses_and_joint_refuses_with_the_reason() {
    let auto = |m: Arc<Model>, s: SolverSettings| {
        Program::new(
            m,
            SolverSettings {
                coordinates: Coordinates::Auto,
                ..s
            },
        )
        .unwrap()
    };
    let joint = |m: Arc<Model>, s: SolverSettings| {
        Program::new(
            m,
            SolverSettings {
                coordinates: Coordinates::Joint,
                ..s
            },
        )
    };
    let pendulum = Arc::new(limited_pendulum());
    let c = auto(pendulum, SolverSettings::default())
        .coordinates()
        .clone();
    println!("pendulum with limits: {c}");
    assert!(c.joint && c.asked == Coordinates::Auto, "{c}");
    let four = Arc::new(limited_loop());
    let p = auto(four.clone(), SolverSettings::default());
    let c = p.coordinates();
    println!("four-bar with a limited loop-closing hinge: {c}");
    assert!(!c.joint && c.asked == Coordinates::Auto);
    assert!(c.why.contains("loop-closing joint"), "{c}");
    let e = joint(four, SolverSettings::default()).unwrap_err();
    assert!(
        matches!(&e, ProgramError::Coordinates(w) if w.contains("loop-closing joint")),
        "{e}"
    );
    assert!(e.to_string().contains("augmented"), "{e}");

    let (m, s) = scene("pendulum-wall", Coordinates::Augmented);
    let c = auto(m.clone(), s).coordinates().clone();
    println!("pendulum-wall: {c}");
    assert!(!c.joint && c.why.contains("contact"), "{c}");
    assert!(matches!(joint(m, s), Err(ProgramError::Coordinates(_))));

    let (m, s) = scene("four-bar", Coordinates::Augmented);
    let c = auto(m, s).coordinates().clone();
    println!("four-bar: {c}");
    assert!(c.joint, "{c}");
}

/// `[solver] coordinates` reaches the compiled settings: each spelling
/// parses to its value, and a scene without the key leaves it unset.
#[test]
fn the_scene_key_compiles_to_the_setting() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/four-bar.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    let with = |value: &str| {
        let t = text.replacen(
            "[solver]\n",
            &format!("[solver]\ncoordinates = \"{value}\"\n"),
            1,
        );
        haptloop_solver::scene::parse("four-bar.toml", &t, None)
            .unwrap()
            .compile()
            .unwrap()
            .settings
            .coordinates
    };
    assert_eq!(with("joint"), Some(Coordinates::Joint));
    assert_eq!(with("auto"), Some(Coordinates::Auto));
    assert_eq!(with("augmented"), Some(Coordinates::Augmented));
    let plain = haptloop_solver::scene::parse("four-bar.toml", &text, None).unwrap();
    assert_eq!(plain.compile().unwrap().settings.coordinates, None);
}
