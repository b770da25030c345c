//! Bad objective entries: `build` fails naming the objective and what is
//! wrong.

use haptloop_solver::{BuildError as E, ObjectiveSpec, ObstacleSpec};

use crate::common::{Designer, arm};

fn err(spec: ObjectiveSpec) -> E {
    let mut b = arm(1.0);
    b.objective(spec);
    b.build().expect_err("the objective is refused")
}

fn dexterity(chain: &[&str]) -> ObjectiveSpec {
    ObjectiveSpec::Dexterity {
        name: Some("reach".into()),
        weight: 1.0,
        chain: chain.iter().map(|s| s.to_string()).collect(),
        point_m: [0.0; 3],
        directions: Vec::new(),
        angular_directions: Vec::new(),
        closure: Vec::new(),
    }
}

#[test]
fn a_chain_names_known_bodies_joined_in_order() {
    let e = err(dexterity(&["base", "turet"]));
    assert!(
        matches!(e, E::UnknownBody { ref body, .. } if body == "turet"),
        "{e:?}"
    );
    assert!(e.to_string().starts_with("objective `reach`"), "{e}");
    let e = err(dexterity(&["base", "upper"]));
    assert!(
        matches!(e, E::ChainNotJoined { ref a, ref b, .. } if a == "base" && b == "upper"),
        "{e:?}"
    );
    let e = err(dexterity(&["base"]));
    assert!(matches!(e, E::BadObjective { field: "chain", .. }), "{e:?}");
}

#[test]
fn bad_numbers_are_refused() {
    let e = err(ObjectiveSpec::StraightLine {
        name: None,
        weight: -1.0,
        body: "fore".into(),
        point_m: [0.0; 3],
        line_point_m: [0.0; 3],
        direction: [1.0, 0.0, 0.0],
    });
    assert!(
        matches!(
            e,
            E::BadObjective {
                field: "weight",
                ..
            }
        ),
        "{e:?}"
    );
    assert!(
        e.to_string().starts_with("objective `straight_line`"),
        "{e}"
    );
    let e = err(ObjectiveSpec::StraightLine {
        name: None,
        weight: 1.0,
        body: "fore".into(),
        point_m: [0.0; 3],
        line_point_m: [0.0; 3],
        direction: [0.0; 3],
    });
    assert!(
        matches!(
            e,
            E::BadObjective {
                field: "direction",
                ..
            }
        ),
        "{e:?}"
    );
    let e = err(ObjectiveSpec::Obstacle {
        name: None,
        weight: 1.0,
        points: vec![("fore".into(), [0.0; 3])],
        obstacle: ObstacleSpec::World([0.0; 3]),
        distance_m: 0.0,
    });
    assert!(
        matches!(
            e,
            E::BadObjective {
                field: "distance",
                ..
            }
        ),
        "{e:?}"
    );
    let e = err(ObjectiveSpec::Obstacle {
        name: None,
        weight: 1.0,
        points: vec![("fore".into(), [0.0; 3])],
        obstacle: ObstacleSpec::Body {
            body: "fore".into(),
            point_m: [0.0; 3],
        },
        distance_m: 0.1,
    });
    assert!(
        matches!(
            e,
            E::BadObjective {
                field: "points",
                ..
            }
        ),
        "{e:?}"
    );
    let mut d = dexterity(&["base", "turret"]);
    if let ObjectiveSpec::Dexterity { directions, .. } = &mut d {
        *directions = vec![[1.0, 0.0, 0.0], [2.0, 0.0, 0.0]];
    }
    assert!(matches!(
        err(d),
        E::BadObjective {
            field: "directions",
            ..
        }
    ));
}

#[test]
fn joint_limit_distance_needs_limited_joints() {
    let e = err(ObjectiveSpec::JointLimitDistance {
        name: None,
        weight: 1.0,
        joints: vec!["yaw".into()],
    });
    assert!(
        matches!(e, E::NoLimits { ref joint, .. } if joint == "yaw"),
        "{e:?}"
    );
    let e = err(ObjectiveSpec::JointLimitDistance {
        name: None,
        weight: 1.0,
        joints: vec!["wrist".into()],
    });
    assert!(matches!(e, E::UnknownJoint { .. }), "{e:?}");
}

#[test]
fn a_name_is_used_once_and_builtin_weights_once() {
    let mut b = arm(1.0);
    b.objective(dexterity(&["base", "turret"]));
    b.objective(dexterity(&["turret", "upper"]));
    assert!(matches!(b.build().unwrap_err(), E::DuplicateName { .. }));
    // A second `finger` objective is refused at its kind (one per scene),
    // not as a name used twice (it has no name of its own).
    let mut b = arm(1.0);
    b.objective(ObjectiveSpec::Finger { weight: 1.0 });
    b.objective(ObjectiveSpec::Finger { weight: 2.0 });
    assert!(matches!(
        b.build().unwrap_err(),
        E::BadObjective { field: "kind", .. }
    ));
    let e = err(ObjectiveSpec::LeastAstonishment {
        weight: 0.0,
        design_weight: 1.0,
    });
    assert!(
        matches!(
            e,
            E::BadObjective {
                field: "weight",
                ..
            }
        ),
        "{e:?}"
    );
}

/// A closed chain's `closure` leads back to the base, names joined bodies,
/// and the loop must move the point in as many directions as there are task
/// rows (the four-bar's loop: one).
#[test]
fn a_closed_chain_closes_on_its_base_and_asks_no_more_rows_than_it_moves() {
    let four_bar = |closure: &[&str], directions: Vec<[f64; 3]>| {
        let src = haptloop_solver::mechanisms::four_bar_builder();
        let mut b = Designer::new();
        for s in src.body_specs() {
            b.body(s.clone());
        }
        for j in src.joint_specs() {
            b.joint(j.clone());
        }
        b.objective(ObjectiveSpec::Dexterity {
            name: Some("loop".into()),
            weight: 1.0,
            chain: ["ground", "crank", "coupler"].map(String::from).to_vec(),
            point_m: [0.0; 3],
            directions,
            angular_directions: Vec::new(),
            closure: closure.iter().map(|s| s.to_string()).collect(),
        });
        b.build()
    };
    let one = vec![[1.0, 0.0, 0.0]];
    assert!(four_bar(&["rocker", "ground"], one.clone()).is_ok());
    let e = four_bar(&["rocker"], one.clone()).unwrap_err();
    assert!(
        matches!(
            e,
            E::BadObjective {
                field: "closure",
                ..
            }
        ),
        "{e:?}"
    );
    let e = four_bar(&["crank", "ground"], one.clone()).unwrap_err();
    assert!(
        matches!(
            e,
            E::BadObjective {
                field: "closure",
                ..
            }
        ),
        "{e:?}"
    );
    let e = four_bar(&["ground"], one).unwrap_err();
    assert!(matches!(e, E::ChainNotJoined { .. }), "{e:?}");
    let e = four_bar(&["rocker", "ground"], Vec::new()).unwrap_err();
    assert!(
        matches!(
            e,
            E::BadObjective {
                field: "directions",
                ..
            }
        ),
        "{e:?}"
    );
    assert!(e.to_string().contains("degrees of freedom"), "{e}");
}
