//! Nelson & Cohen's figures as built-in scenes, each checked against
//! something computed independently of the solver: the assembly residual,
//! the degrees of freedom from the rank of the joints' Jacobian (an SVD),
//! and a closed-form position (slider-crank, Cardan, four-bar, 3-RUS leg,
//! rhombus), with angles read from the bodies' poses.

use std::f64::consts::PI;
use std::sync::Arc;
use std::time::Duration;

use haptloop::scenes::resolve;
use haptloop_solver::mechanisms::{self as mech};
use haptloop_solver::{
    FingerSpec, FingerTarget, Model, ModelBuilder, Placement, PlacementOptions, Program,
    SolverSettings, TickOutcome,
};
use nalgebra::{Matrix3, UnitQuaternion, Vector3};

const DT: Duration = Duration::from_millis(1);

/// max |C| over the equality rows at `q`.
fn residual(model: &Model, q: &[f64]) -> f64 {
    let mut ev = model.evaluation();
    ev.evaluate(model, q, &model.initial_targets()).unwrap();
    ev.values()[model.equality_rows()]
        .iter()
        .fold(0.0, |m, v| m.max(v.abs()))
}

/// Coordinates minus the rank of the equality rows' Jacobian at `q` (SVD,
/// singular values above 1e-9 of the largest): the mechanism's mobility.
fn dof_by_rank(model: &Model, q: &[f64]) -> usize {
    let mut ev = model.evaluation();
    ev.evaluate(model, q, &model.initial_targets()).unwrap();
    let j = ev.jacobian().to_dense();
    let rows = model.equality_rows();
    let eq = j.rows(rows.start, rows.len()).into_owned();
    let sv = eq.singular_values();
    let top = sv.max();
    let rank = sv.iter().filter(|&&s| s > 1e-9 * top).count();
    model.n_coords() - rank
}

/// The rotation of `body` at `q` relative to its pose in `model`'s q0.
fn turned(model: &Model, q: &[f64], body: &str) -> Matrix3<f64> {
    let b = model.body_id(body).unwrap();
    model.body_rotation(q, b).unwrap() * model.body_rotation(model.q0(), b).unwrap().transpose()
}

/// The angle of a relative rotation about the unit axis `axis`, unwrapped
/// against `prev`.
fn angle_about(r: &Matrix3<f64>, axis: &Vector3<f64>, prev: f64) -> f64 {
    let a = UnitQuaternion::from_matrix(r).scaled_axis().dot(axis);
    a + 2.0 * PI * ((prev - a) / (2.0 * PI)).round()
}

fn body_point(model: &Model, q: &[f64], body: &str, local: Vector3<f64>) -> Vector3<f64> {
    let b = model.body_id(body).unwrap();
    model.body_rotation(q, b).unwrap() * local + model.body_position(q, b).unwrap()
}

fn program(model: &Model) -> Program {
    Program::new(Arc::new(model.clone()), SolverSettings::default()).unwrap()
}

fn placed(model: &Model, targets: &[FingerTarget]) -> Vec<f64> {
    let mut p = Placement::analyze(model, &PlacementOptions::default()).unwrap();
    let mut q = model.q0().to_vec();
    let info = p.solve(model, &mut q, model.q0(), targets).unwrap();
    assert!(info.residual < 1e-9, "{info:?}");
    q
}

/// Fig. 12: the piston assembly is assembled, has one degree of freedom
/// (77 coordinates, rank 76), and as the hand's finger turns the flywheel
/// 1¼ turns every piston stands at r cos α + √(l² − r² sin² α), the
/// camshaft at −½ and the pump at −1 of the crank angle (gears to 1e-9 rad).
#[test]
fn fig_12_piston_slider_cranks_and_gears_follow_the_crank() {
    let scene = resolve("piston").unwrap();
    let model = &scene.compiled.model;
    assert!(residual(model, model.q0()) < 1e-12);
    assert_eq!(dof_by_rank(&scene.compiled.joints_only, model.q0()), 1);
    let mut p = program(model);
    let x = Vector3::x();
    let start = model.initial_targets()[0].position_m;
    let axis_point = Vector3::new(start.x, 0.0, 0.0);
    let (mut theta, mut cam, mut pump) = (0.0, 0.0, 0.0);
    let (mut worst_z, mut worst_gear) = (0.0f64, 0.0f64);
    let ticks = 2500;
    for k in 1..=ticks {
        let a = 2.5 * PI * k as f64 / ticks as f64;
        let t = axis_point + Vector3::new(0.0, -a.sin(), a.cos()) * mech::FLYWHEEL_M;
        let r = p.tick(&[FingerTarget::at(t)], DT);
        assert_eq!(r.status, TickOutcome::Ok, "tick {k}");
        let q = p.q();
        theta = angle_about(&turned(model, q, "crankshaft"), &x, theta);
        cam = angle_about(&turned(model, q, "camshaft"), &x, cam);
        pump = angle_about(&turned(model, q, "pump"), &x, pump);
        worst_gear = worst_gear
            .max((cam - mech::CAM_RATIO * theta).abs())
            .max((pump + theta).abs());
        for c in 0..4 {
            let b = model.body_id(&format!("piston{c}")).unwrap();
            let z = model.body_position(q, b).unwrap().z;
            let expected = mech::piston_height_m(theta + mech::PISTON_PHASES[c]);
            worst_z = worst_z.max((z - expected).abs());
        }
    }
    assert!(theta > 2.2 * PI, "the crank turned {theta} rad");
    assert!(worst_z < 1e-9, "piston height error {worst_z:e} m");
    assert!(worst_gear < 1e-9, "gear ratio error {worst_gear:e} rad");
}

/// Fig. 11: the four-bar driving a Cardan has one degree of freedom (28
/// coordinates, rank 27); turning the crank a full turn, the rocker shaft
/// turns by the four-bar's closed form and the output shaft by
/// atan(cos β tan φ₁), to what the joints' nanometre of violation allows.
#[test]
fn fig_11_four_bar_drives_the_cardan_by_its_closed_forms() {
    let scene = resolve("four-bar-cardan").unwrap();
    let model = &scene.compiled.model;
    assert!(residual(model, model.q0()) < 1e-12);
    assert_eq!(dof_by_rank(&scene.compiled.joints_only, model.q0()), 1);
    let d = mech::cardan_rocker_pivot();
    let heading = |v: Vector3<f64>| v.y.atan2(v.x);
    let c0 = heading(mech::cardan_coupler_point(mech::CARDAN_CRANK0) - d);
    let beta = mech::CARDAN_BETA;
    let s2 = Vector3::new(beta.sin(), 0.0, beta.cos());
    let mut p = program(model);
    let (mut phi1, mut phi2, mut worst, mut swing) = (0.0, 0.0, 0.0f64, 0.0f64);
    let mut viol = 0.0f64;
    let ticks = 2000;
    for k in 1..=ticks {
        let a = mech::CARDAN_CRANK0 + 2.0 * PI * k as f64 / ticks as f64;
        let t = Vector3::new(a.cos(), a.sin(), 0.0) * mech::CARDAN_LINKS_M[0];
        let rep = p.tick(&[FingerTarget::at(t)], DT);
        assert_eq!(rep.status, TickOutcome::Ok, "tick {k}");
        viol = viol
            .max(rep.max_violation_m)
            .max(rep.max_violation_rad * 0.1);
        let q = p.q();
        let tip = model.finger_point(q, haptloop_solver::FingerId(0)).unwrap();
        let c = mech::cardan_coupler_point(heading(tip));
        let want1 = heading(c - d) - c0;
        phi1 = angle_about(&turned(model, q, "shaft1"), &Vector3::z(), phi1);
        phi2 = angle_about(&turned(model, q, "shaft2"), &s2, phi2);
        let want2 = (beta.cos() * want1.tan()).atan();
        worst = worst.max((phi1 - want1).abs()).max((phi2 - want2).abs());
        swing = swing.max(want1.abs());
    }
    assert!(swing > 0.4, "the rocker swung only {swing} rad");
    // The fast loop holds the joints to a nanometre; over the 6 cm rocker at
    // the smallest transmission angle (39°) that is 3e-8 rad of rocker.
    assert!(viol < 1e-9, "joint violation {viol:e} m");
    assert!(worst < 1e-7, "closed-form error {worst:e} rad");
}

/// Figs. 2/3: the 3-RUS platform (a welded ground among its bodies) has six
/// degrees of freedom (56 coordinates, rank 50); raised or lowered 1 cm
/// level, every crank's end stands where (u + a cos α)² + (z − a sin α)² =
/// L² puts it.
#[test]
fn figs_2_3_stewart_3rsu_legs_follow_the_platform_height() {
    let scene = resolve("stewart-3rsu").unwrap();
    let model = &scene.compiled.model;
    assert!(residual(model, model.q0()) < 1e-12);
    assert_eq!(dof_by_rank(&scene.compiled.joints_only, model.q0()), 6);
    let (a, big_l) = (mech::RSU_CRANK_M, mech::RSU_ROD_M);
    let u = mech::RSU_BASE_M - mech::RSU_PLATFORM_M;
    for dz in [0.01, -0.01] {
        let mut targets = model.initial_targets();
        targets[0].position_m.z += dz;
        let q = placed(model, &targets);
        let z = mech::rsu_height_m() + dz;
        let kk = (big_l * big_l - u * u - a * a - z * z) / (2.0 * a);
        let rho = (u * u + z * z).sqrt();
        let alpha = (kk / rho).acos() - z.atan2(u);
        for k in 0..3 {
            let psi = mech::rsu_azimuth(k);
            let radial = Vector3::new(psi.cos(), psi.sin(), 0.0);
            let end = body_point(model, &q, &format!("crank{k}"), Vector3::z() * (a / 2.0));
            let want =
                radial * (mech::RSU_BASE_M + a * alpha.cos()) + Vector3::z() * a * alpha.sin();
            assert!(
                (end - want).norm() < 1e-9,
                "dz {dz}, leg {k}: crank end {end:?}, closed form {want:?}"
            );
        }
        assert!(alpha.abs() > 0.05, "the cranks turned only {alpha} rad");
    }
}

/// Figs. 6/7: the quarter tori written 5 mm apart assemble (Newton-KKT) into
/// the ring itself, the closed form the loop's symmetry gives; assembled, it
/// floats with 6 + 1 degrees of freedom; pulled apart at two opposite joints
/// by 5 mm each, it becomes the rhombus of side R√2 with that diagonal.
#[test]
fn figs_6_7_quarter_tori_assemble_into_the_ring_and_deform_as_a_rhombus() {
    let scene = resolve("quarter-torus").unwrap();
    let joints = &scene.compiled.joints_only;
    let ring = mech::quarter_torus();
    assert!(
        residual(joints, joints.q0()) > 1e-3,
        "the parts start apart"
    );
    let q = placed(joints, &[]);
    assert!(residual(joints, &q) < 1e-10);
    let worst = q
        .iter()
        .zip(ring.q0())
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(worst < 1e-9, "assembled {worst:e} from the ring");
    assert_eq!(dof_by_rank(joints, &q), 7);

    // Two fingers on opposite joints (0° and 180°), pulled apart along x.
    let r = mech::TORUS_RADIUS_M;
    let src = mech::quarter_torus_builder(0.0);
    let mut b = ModelBuilder::new();
    b.gravity(src.gravity_m_s2());
    for s in src.body_specs() {
        b.body(s.clone());
    }
    for j in src.joint_specs() {
        b.joint(j.clone());
    }
    let c = Vector3::new(1.0, 1.0, 0.0) * (2.0 * r / PI);
    let u1 = Vector3::new(r, 0.0, 0.0) - c;
    let u2 = Vector3::new(0.0, r, 0.0) - c;
    b.finger(FingerSpec::point("east", "torus0", u1.into()));
    b.finger(FingerSpec::point("west", "torus1", u2.into()));
    let model = b.build().unwrap();
    let pull = 0.005;
    let mut targets = model.initial_targets();
    targets[0].position_m.x += pull;
    targets[1].position_m.x -= pull;
    let q = placed(&model, &targets);
    let half = r + pull;
    let north = (2.0 * r * r - half * half).sqrt();
    let vertex = body_point(&model, &q, "torus0", u2);
    assert!(
        (vertex - Vector3::new(0.0, north, 0.0)).norm() < 1e-9,
        "the 90° joint at {vertex:?}, closed form (0, {north}, 0)"
    );
    let parallel = |a: &str, b: &str| (turned(&model, &q, a) - turned(&model, &q, b)).norm();
    assert!(parallel("torus0", "torus2") < 1e-9 && parallel("torus1", "torus3") < 1e-9);
    assert!(
        parallel("torus0", "torus1") > 1e-2,
        "the rhombus did not deform"
    );
}
