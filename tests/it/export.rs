//! `haptloop export mjcf`: the MJCF parses as XML, rebuilds every body's
//! initial pose from its nested frames (composed here, independently of the
//! exporter), puts every tree joint where the scene's joint is on both of its
//! bodies, closes one loop per independent cycle of the joint graph, and
//! refuses what MJCF cannot say with the reason. With MuJoCo installed
//! (`bash benches/peers/run.sh` makes benches/peers/.venv), the ignored test
//! loads every export in MuJoCo and checks its equality rows at q0.

use haptloop::export::mjcf::{self, Export, Options};
use haptloop::scenes::resolve;
use nalgebra::{Quaternion, UnitQuaternion, Vector3};
use std::collections::HashMap;
use std::process::Command;

const MECHANISMS: &[&str] = &[
    "four-bar",
    "stewart",
    "peaucellier",
    "sphere-toy",
    "bennett",
    "lattice",
    "chain",
    "lattice-2x8",
];

fn export(scene: &str, options: &Options) -> Export {
    let s = resolve(scene).unwrap();
    mjcf::export(&s, options).unwrap_or_else(|e| panic!("{scene}: {e:#}"))
}

fn numbers(s: &str) -> Vec<f64> {
    s.split_whitespace().map(|x| x.parse().unwrap()).collect()
}

fn vec_attr(n: roxmltree::Node, name: &str) -> Vector3<f64> {
    let v = numbers(n.attribute(name).unwrap_or("0 0 0"));
    Vector3::new(v[0], v[1], v[2])
}

fn quat_attr(n: roxmltree::Node) -> UnitQuaternion<f64> {
    let q = numbers(n.attribute("quat").unwrap_or("1 0 0 0"));
    UnitQuaternion::from_quaternion(Quaternion::new(q[0], q[1], q[2], q[3]))
}

/// World pose of every body and the tree joints (name, type, world
/// position, world axis) in it, composed from the nested frames.
struct Parsed {
    poses: HashMap<String, (Vector3<f64>, UnitQuaternion<f64>)>,
    joints: Vec<(String, String, Vector3<f64>, Vector3<f64>)>,
    mocap: usize,
    nv: usize,
}

fn walk(n: roxmltree::Node, at: (Vector3<f64>, UnitQuaternion<f64>), out: &mut Parsed) {
    for c in n.children().filter(|c| c.has_tag_name("body")) {
        let (p, r) = at;
        let pose = (p + r * vec_attr(c, "pos"), r * quat_attr(c));
        let name = c.attribute("name").unwrap().to_owned();
        if c.attribute("mocap") == Some("true") {
            out.mocap += 1;
        }
        for j in c
            .children()
            .filter(|j| j.has_tag_name("joint") || j.has_tag_name("freejoint"))
        {
            let kind = if j.has_tag_name("freejoint") {
                "free"
            } else {
                j.attribute("type").unwrap()
            };
            out.nv += match kind {
                "hinge" | "slide" => 1,
                "ball" => 3,
                "free" => 6,
                other => panic!("joint type {other}"),
            };
            let world = pose.0 + pose.1 * vec_attr(j, "pos");
            let axis = pose.1 * vec_attr(j, "axis");
            let name = j.attribute("name").unwrap().to_owned();
            out.joints.push((name, kind.to_owned(), world, axis));
        }
        assert!(out.poses.insert(name, pose).is_none(), "a body twice");
        walk(c, pose, out);
    }
}

fn parse(xml: &str) -> (roxmltree::Document<'_>, Parsed) {
    let doc = roxmltree::Document::parse(xml).expect("the MJCF is well-formed XML");
    let world = doc
        .descendants()
        .find(|n| n.has_tag_name("worldbody"))
        .unwrap();
    let mut out = Parsed {
        poses: HashMap::new(),
        joints: Vec::new(),
        mocap: 0,
        nv: 0,
    };
    walk(
        world,
        (Vector3::zeros(), UnitQuaternion::identity()),
        &mut out,
    );
    (doc, out)
}

/// Independent loops of the joint graph (fixed bodies merged into one
/// node): joints − nodes + components.
fn cycle_rank(scene: &haptloop::scenes::Scene) -> usize {
    let m = &scene.compiled.model;
    let node = |b: &str| {
        let i = m.body_id(b).unwrap().index();
        if m.bodies()[i].fixed { 0 } else { i + 1 }
    };
    let mut parent: Vec<usize> = (0..=m.bodies().len()).collect();
    fn find(p: &mut [usize], i: usize) -> usize {
        if p[i] != i {
            p[i] = find(p, p[i]);
        }
        p[i]
    }
    let mut loops = 0;
    for j in scene.loaded.joint_specs() {
        let (a, b) = (node(&j.bodies[0]), node(&j.bodies[1]));
        let (ra, rb) = (find(&mut parent, a), find(&mut parent, b));
        if ra == rb {
            loops += usize::from(a != b);
        } else {
            parent[ra] = rb;
        }
    }
    loops
}

#[test]
fn the_mjcf_rebuilds_every_pose_and_joint_of_the_scene() {
    for &name in MECHANISMS {
        let scene = resolve(name).unwrap();
        let e = export(name, &Options::default());
        let (doc, p) = parse(&e.xml);
        let m = &scene.compiled.model;
        let moving: Vec<_> = m.bodies().iter().filter(|b| !b.fixed).collect();
        assert_eq!(p.poses.len(), moving.len() + m.fingers().len(), "{name}");
        assert_eq!(p.mocap, m.fingers().len(), "{name}");
        for b in &moving {
            let (pos, rot) = p.poses[&b.name];
            assert!(
                (pos - b.position_m).norm() < 1e-12,
                "{name}: {} at {pos:?}",
                b.name
            );
            assert!(rot.angle_to(&b.orientation) < 1e-12, "{name}: {}", b.name);
        }
        assert_eq!(p.nv, e.meta.dof, "{name}: nv");
        // Every tree joint sits on the scene joint's anchor on both bodies,
        // along its axis.
        let joints = scene.loaded.joint_specs();
        for (jname, kind, at, axis) in &p.joints {
            if kind == "free" {
                continue;
            }
            // A universal joint is two hinges, `NAME.1` and `NAME.2`.
            let base = match kind.as_str() {
                "hinge" => jname
                    .strip_suffix(".1")
                    .or(jname.strip_suffix(".2"))
                    .filter(|b| {
                        joints.iter().any(|j| {
                            j.name.as_deref() == Some(*b)
                                && j.kind == haptloop_solver::JointKind::Universal
                        })
                    }),
                _ => None,
            };
            let spec = joints
                .iter()
                .find(|j| j.name.as_deref() == Some(base.unwrap_or(jname)))
                .unwrap_or_else(|| panic!("{name}: {jname} is no scene joint"));
            for s in 0..2 {
                let b = &m.bodies()[m.body_id(&spec.bodies[s]).unwrap().index()];
                let anchor = b.position_m + b.orientation * Vector3::from(spec.anchors_m[s]);
                assert!((anchor - at).norm() < 1e-12, "{name}: {jname} side {s}");
            }
            if kind == "hinge" || kind == "slide" {
                let h = spec.axes.unwrap();
                let candidates: Vec<Vector3<f64>> = (0..2)
                    .map(|s| {
                        let b = &m.bodies()[m.body_id(&spec.bodies[s]).unwrap().index()];
                        b.orientation * Vector3::from(h[s]).normalize()
                    })
                    .collect();
                assert!(
                    candidates.iter().any(|c| c.cross(axis).norm() < 1e-12),
                    "{name}: {jname} axis {axis:?}"
                );
            }
        }
        // One closure per independent loop; each is an equality, with the
        // fingers' ties beside them.
        assert_eq!(
            e.meta.joints.iter().filter(|j| j.closure.is_some()).count(),
            cycle_rank(&scene),
            "{name}"
        );
        let equalities = doc
            .root_element()
            .children()
            .find(|n| n.has_tag_name("equality"))
            .unwrap()
            .children()
            .filter(|n| n.is_element())
            .count();
        let two = e
            .meta
            .joints
            .iter()
            .filter(|j| j.closure == Some("two_connects"))
            .count();
        assert_eq!(
            equalities,
            cycle_rank(&scene) + two + m.fingers().len(),
            "{name}"
        );
        assert!(
            !e.xml.contains("damping"),
            "{name}: damping not in the scene"
        );
    }
}

/// Planar loops close with one `connect` (the tree's parallel hinges keep
/// the axes together), spatial ones with two; the flags change the tree.
#[test]
fn loops_close_as_the_tree_allows_and_the_flags_change_the_tree() {
    let closures = |e: &Export| -> Vec<&str> {
        e.meta
            .joints
            .iter()
            .filter_map(|j| j.closure)
            .collect::<Vec<_>>()
    };
    let lattice = export("lattice-2x8", &Options::default());
    assert_eq!(closures(&lattice), vec!["connect"; 16]);
    let two = export(
        "lattice-2x8",
        &Options {
            two_connects: true,
            ..Options::default()
        },
    );
    assert_eq!(closures(&two), vec!["two_connects"; 16]);
    assert_eq!(
        closures(&export("bennett", &Options::default())),
        vec!["two_connects"]
    );
    // The Stewart platform cut at its six spheres floats on a freejoint.
    let cut = export(
        "stewart",
        &Options {
            cut: (0..6).map(|k| format!("top{k}")).collect(),
            ..Options::default()
        },
    );
    assert_eq!(cut.meta.roots, vec!["platform"]);
    assert_eq!(closures(&cut).len(), 6);
    assert_eq!(cut.meta.dof, 6 * 3 + 6);
    // The sphere toy rooted elsewhere: same loops, another tree.
    let rooted = export(
        "sphere-toy",
        &Options {
            root: Some("bead0.0".into()),
            ..Options::default()
        },
    );
    assert_eq!(rooted.meta.roots, vec!["bead0.0"]);
    assert_ne!(
        export("sphere-toy", &Options::default()).meta.roots,
        vec!["bead0.0"]
    );
}

fn haptloop() -> Command {
    Command::new(env!("CARGO_BIN_EXE_haptloop"))
}

#[test]
fn export_refuses_what_mjcf_cannot_say_with_the_reason() {
    let cases: &[(&[&str], &str)] = &[
        (&["box-slide"], "collision shapes"),
        (&["four-bar-design"], "design variables"),
        (
            &["four-bar", "--cut", "coupler-rocker"],
            "cannot be cut: MuJoCo closes no loop with a universal joint",
        ),
        (&["four-bar", "--cut", "nope"], "--cut nope: no joint"),
        (
            &["sphere-toy", "--root", "nope"],
            "--root nope: no moving body",
        ),
    ];
    for (args, says) in cases {
        let out = haptloop()
            .args(["export", "mjcf"])
            .args(*args)
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(1), "{args:?}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(says), "{args:?}: {err}");
    }
    let out = haptloop()
        .args(["export", "mjcf", "four-bar", "--damping=-1"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    // A loop of universal joints only has nowhere MuJoCo can cut it.
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("u-loop.toml");
    let mut text = String::from(
        "[scene]\nname = \"u-loop\"\n\n[[device]]\nname = \"d\"\nmodel = \"phantom-premium-1.5\"\n\n",
    );
    for (k, x) in [(0, 0.0), (1, 0.1), (2, 0.2)] {
        text += &format!("[[body]]\nname = \"b{k}\"\nposition = [{x}, 0.0, 0.0]\n\n");
    }
    for (a, b, x) in [(0, 1, 0.05), (1, 2, 0.15), (2, 0, 0.1)] {
        let (xa, xb) = (x - 0.1 * f64::from(a), x - 0.1 * f64::from(b));
        text += &format!(
            "[[joint]]\nname = \"u{a}\"\nkind = \"universal\"\nbodies = [\"b{a}\", \"b{b}\"]\n\
             anchors = [[{xa}, 0.0, 0.0], [{xb}, 0.0, 0.0]]\naxes = [[0.0, 0.0, 1.0], [0.0, 1.0, 0.0]]\n\n"
        );
    }
    text += "[[finger]]\nname = \"f\"\ndevice = \"d\"\nbody = \"b0\"\n";
    std::fs::write(&file, text).unwrap();
    let out = haptloop()
        .args(["export", "mjcf"])
        .arg(&file)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(
        err.contains("closes a loop of universal and prismatic joints"),
        "{err}"
    );
}

/// `export mjcf` writes the XML and the metadata files.
#[test]
fn the_cli_writes_the_model_and_its_metadata() {
    let dir = tempfile::tempdir().unwrap();
    let (xml, meta) = (dir.path().join("b.xml"), dir.path().join("b.json"));
    let out = haptloop()
        .args(["export", "mjcf", "bennett", "--out"])
        .arg(&xml)
        .arg("--meta")
        .arg(&meta)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = std::fs::read_to_string(&xml).unwrap();
    assert_eq!(text, export("bennett", &Options::default()).xml);
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&meta).unwrap()).unwrap();
    assert_eq!(v["dof"], 3);
    assert_eq!(v["fingers"][0]["body"], "link2");
}

/// MuJoCo loads every export, its `nv` is the tree's and every equality row
/// (loop closures and finger ties) is zero at q0. Needs the virtual
/// environment `bash benches/peers/run.sh` creates (or
/// `HAPTLOOP_MUJOCO_PYTHON`): `cargo test --release --test it export -- --ignored`.
#[test]
#[ignore = "needs MuJoCo: bash benches/peers/run.sh creates benches/peers/.venv"]
fn mujoco_loads_every_export_assembled() {
    let python = std::env::var("HAPTLOOP_MUJOCO_PYTHON").unwrap_or_else(|_| {
        format!(
            "{}/benches/peers/.venv/bin/python",
            env!("CARGO_MANIFEST_DIR")
        )
    });
    let dir = tempfile::tempdir().unwrap();
    for &name in MECHANISMS {
        let e = export(name, &Options::default());
        let fingers = resolve(name).unwrap().compiled.model.fingers().to_vec();
        let tie_rows: usize = fingers
            .iter()
            .map(|f| {
                if f.grasp == haptloop_solver::Grasp::Rigid {
                    6
                } else {
                    3
                }
            })
            .sum();
        let file = dir.path().join(format!("{name}.xml"));
        std::fs::write(&file, &e.xml).unwrap();
        let script = "import sys, mujoco, numpy as np\n\
             m = mujoco.MjModel.from_xml_path(sys.argv[1]); d = mujoco.MjData(m)\n\
             mujoco.mj_forward(m, d)\n\
             print(m.nv, d.ne, np.abs(d.efc_pos[:d.ne]).max(initial=0.0))";
        let out = Command::new(&python)
            .args(["-c", script])
            .arg(&file)
            .output()
            .unwrap_or_else(|e| panic!("{python}: {e}"));
        assert!(
            out.status.success(),
            "{name}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let text = String::from_utf8_lossy(&out.stdout);
        let f: Vec<f64> = numbers(&text);
        assert_eq!(f[0] as usize, e.meta.dof, "{name}: nv");
        assert_eq!(
            f[1] as usize,
            e.meta.closure_rows + tie_rows,
            "{name}: equality rows"
        );
        assert!(f[2] < 1e-9, "{name}: equality residual {} at q0", f[2]);
    }
}
