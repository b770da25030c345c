//! Bad flexible bodies and surface joints are refused with an error that
//! names the offender and what is wrong, at the builder and in a scene file
//! (file:line:column at the offending key); the gradient update is refused
//! for models it does not cover.

use std::sync::Arc;

use haptloop_solver::flexible::BeamSpec;
use haptloop_solver::parametric::SurfaceKind;
use haptloop_solver::{
    BodySpec, ContactSurface, FingerSpec, JointKind, JointSpec, ModelBuilder, Program,
    SolverSettings, UpdateRule,
};

fn beam() -> BeamSpec {
    BeamSpec::new([0.0, 0.2], 0.05, 3)
}

fn build(f: impl Fn(&mut ModelBuilder)) -> String {
    let mut b = ModelBuilder::new();
    b.body(BodySpec::fixed("ground"));
    f(&mut b);
    match b.build() {
        Ok(_) => "built".into(),
        Err(e) => e.to_string(),
    }
}

#[test]
fn builder_errors_name_the_offender() {
    let cases: Vec<(String, &str)> = vec![
        (
            build(|b| {
                b.body(BodySpec::new("arm").flexible(beam()));
                b.joint(
                    JointSpec::new(JointKind::Revolute, "ground", "arm")
                        .named("hinge")
                        .anchors([0.0; 3], [0.1, 0.0, 0.0])
                        .axes([0.0, 0.0, 1.0], [0.0, 0.0, 1.0]),
                );
            }),
            "joint `hinge`: a `revolute` joint uses the axes of flexible body `arm`",
        ),
        (
            build(|b| {
                b.body(BodySpec::new("arm").flexible(beam()));
                b.finger(FingerSpec::rigid("thumb", "arm", [0.2, 0.0, 0.0]));
            }),
            "finger `thumb`: a rigid grasp holds the orientation of flexible body `arm`",
        ),
        (
            build(|b| {
                b.body(BodySpec::new("arm").flexible(beam()));
                b.finger(FingerSpec::point("index", "arm", [0.3, 0.0, 0.0]));
            }),
            "finger `index`: the point at x = 0.3 m of flexible body `arm` lies off its span",
        ),
        (
            build(|b| {
                b.body(
                    BodySpec::new("arm")
                        .flexible(beam())
                        .shape(haptloop_solver::Shape::Sphere { radius_m: 0.01 }),
                );
            }),
            "body `arm`: a flexible body takes part in no contact",
        ),
        (
            build(|b| {
                b.body(BodySpec::fixed("arm").flexible(beam()));
            }),
            "body `arm`: a flexible body must move",
        ),
        (
            build(|b| {
                b.body(BodySpec::new("arm").flexible(BeamSpec::new([0.1, 0.0], 0.05, 3)));
            }),
            "body `arm`: flexible `span` must be finite with x0 < x1",
        ),
        (
            build(|b| {
                b.body(BodySpec::new("arm").flexible(BeamSpec::new([0.0, 0.2], 0.05, 5)));
            }),
            "body `arm`: flexible `modes` must be 1 to 4",
        ),
        (
            build(|b| {
                b.body(BodySpec::new("ball"));
                b.joint(
                    JointSpec::new(JointKind::Rolling, "ball", "ground")
                        .named("roll")
                        .radius(0.03),
                );
            }),
            "joint `roll`: a `rolling` joint needs a `surface`",
        ),
        (
            build(|b| {
                b.body(BodySpec::new("ball"));
                b.body(BodySpec::new("table"));
                b.joint(
                    JointSpec::new(JointKind::Rolling, "ball", "table")
                        .named("roll")
                        .radius(0.03)
                        .surface(ContactSurface::new(SurfaceKind::Plane)),
                );
            }),
            "joint `roll`: a `rolling` joint rolls a moving ball (body i) on a fixed body's surface",
        ),
        (
            build(|b| {
                b.body(BodySpec::new("ball"));
                b.joint(
                    JointSpec::new(JointKind::OnSurface, "ball", "ground")
                        .named("rest")
                        .surface(ContactSurface::new(SurfaceKind::Sphere {
                            radius_m: -1.0,
                            concave: true,
                        })),
                );
            }),
            "joint `rest`: surface `radius` = -1 must be finite and > 0 m",
        ),
        (
            build(|b| {
                b.body(BodySpec::new("ball").at([0.5, 0.0, 0.0]));
                b.joint(
                    JointSpec::new(JointKind::OnSurface, "ball", "ground")
                        .named("rest")
                        .surface(ContactSurface::new(SurfaceKind::Sphere {
                            radius_m: 0.2,
                            concave: true,
                        })),
                );
            }),
            "joint `rest`: anchor i at the initial poses lies off the surface's patch",
        ),
        (
            build(|b| {
                b.body(BodySpec::new("arm"));
                b.joint(
                    JointSpec::new(JointKind::Spherical, "ground", "arm")
                        .named("ball")
                        .radius(0.1),
                );
            }),
            "joint `ball`: `surface` and `radius` belong to `on_surface` and `rolling` joints",
        ),
    ];
    for (got, want) in cases {
        assert!(got.starts_with(want), "got `{got}`, want `{want}…`");
    }
}

#[test]
fn the_gradient_update_refuses_auxiliary_columns() {
    let mut b = ModelBuilder::new();
    b.body(BodySpec::fixed("ground"));
    b.body(BodySpec::new("arm").mass(0.05).flexible(beam()));
    b.joint(JointSpec::new(JointKind::Fixed, "ground", "arm"));
    let settings = SolverSettings {
        update: UpdateRule::Gradient,
        ..SolverSettings::default()
    };
    let e = Program::new(Arc::new(b.build().unwrap()), settings).unwrap_err();
    assert!(e.to_string().contains("update = \"projected\""), "{e}");
}

#[test]
fn scene_errors_point_at_the_key() {
    let text = r#"[scene]
name = "bad"

[[body]]
name = "ground"
fixed = true

[[body]]
name = "arm"
flexible = { span = [0.0, 0.2], stiffness = -1.0 }

[[body]]
name = "ball"
position = [0.0, 0.0, 0.03]

[[joint]]
name = "roll"
kind = "rolling"
bodies = ["ball", "ground"]
surface = { type = "plane" }
radius = 0.0
"#;
    let e = haptloop_solver::scene::parse("bad.toml", text, None)
        .and_then(|l| l.compile().map(|_| ()))
        .unwrap_err();
    assert!(
        e.to_string()
            .starts_with("bad.toml:10:12: body `arm`: flexible `stiffness`"),
        "{e}"
    );
    let fixed = text.replace("stiffness = -1.0", "stiffness = 0.1");
    let e = haptloop_solver::scene::parse("bad.toml", &fixed, None)
        .and_then(|l| l.compile().map(|_| ()))
        .unwrap_err();
    assert!(
        e.to_string().starts_with(
            "bad.toml:21:10: joint `roll`: a `rolling` joint needs the ball's `radius`"
        ),
        "{e}"
    );
}
