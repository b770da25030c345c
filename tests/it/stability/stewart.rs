//! The Stewart platform through its singular pose (its legs bottoming out
//! there) and at its stroke limits.

use haptloop::scenes::{BUILTIN, Scene};
use haptloop_solver::TickOutcome;
use nalgebra::{Matrix6, Vector3};
use toml::{Table, Value};

use super::edit::{builtin, edited, set_waypoints, tables};
use super::harness::{Outcome, assert_recovers, case, check_recovered, drive_with, options};

/// The smallest over the largest singular value of C_q at `q` over the
/// joint rows that hold there: every equality (quaternion norms included)
/// and every limit at its bound (within 1 µm): 0 at a singular pose of
/// the mechanism as it is held.
fn joint_conditioning(scene: &Scene, q: &[f64]) -> f64 {
    use haptloop_solver::Sense;
    let model = &scene.compiled.joints_only;
    let mut ev = haptloop_solver::Evaluation::new(model);
    ev.evaluate(model, q, &[]).unwrap();
    let j = ev.jacobian().to_dense();
    let held: Vec<usize> = model
        .rows()
        .iter()
        .enumerate()
        .filter(|(i, r)| match r.sense {
            Sense::Equality => true,
            Sense::Inequality => ev.values()[*i] <= 1e-6,
            Sense::Friction => false,
        })
        .map(|(i, _)| i)
        .collect();
    let sv = j.select_rows(held.iter()).singular_values();
    sv.min() / sv.max()
}

/// The Stewart platform's legs as lines, from the scene file's own numbers
/// (not the solver's): the base attachment points (joints `base{i}`, on
/// the fixed base at the origin) and the platform's (joints `top{i}`, in
/// the platform's frame), placed by the platform's pose in q.
struct StewartLegs {
    base: [Vector3<f64>; 6],
    top: [Vector3<f64>; 6],
    /// The platform's offset in q.
    platform: usize,
    /// Moments are divided by this (the platform's radius), m, so that the
    /// wrench matrix holds numbers of one kind.
    radius_m: f64,
}

impl StewartLegs {
    fn of(scene: &Scene) -> Self {
        let text = BUILTIN.iter().find(|b| b.name == "stewart").unwrap().text;
        let mut t: Table = text.parse().unwrap();
        let base = tables(&mut t, "body").next().unwrap();
        // The base is fixed at the origin, unrotated: its anchors are
        // scene coordinates.
        assert_eq!(base.get("fixed").and_then(Value::as_bool), Some(true));
        let numbers = |k: &str| -> Vec<f64> {
            base[k]
                .as_array()
                .unwrap()
                .iter()
                .map(|x| x.as_float().unwrap())
                .collect()
        };
        assert_eq!(numbers("position"), [0.0; 3]);
        assert_eq!(numbers("orientation"), [1.0, 0.0, 0.0, 0.0]);
        let mut anchor = |joint: String, k: usize| {
            let j = tables(&mut t, "joint")
                .find(|j| j.get("name").and_then(Value::as_str) == Some(&joint))
                .unwrap();
            let a = j["anchors"].as_array().unwrap()[k].as_array().unwrap();
            Vector3::from_iterator(a.iter().map(|x| x.as_float().unwrap()))
        };
        let base = std::array::from_fn(|i| anchor(format!("base{i}"), 0));
        let top: [Vector3<f64>; 6] = std::array::from_fn(|i| anchor(format!("top{i}"), 1));
        let model = &scene.compiled.model;
        let (_, platform) = model
            .layout()
            .moving_bodies()
            .find(|(id, _)| model.bodies()[id.index()].name == "platform")
            .unwrap();
        let radius_m = top.iter().map(|a| a.norm()).sum::<f64>() / 6.0;
        StewartLegs {
            base,
            top,
            platform,
            radius_m,
        }
    }

    /// Leg i at `q`: (base point, platform point relative to the
    /// platform's centre, platform point), m.
    fn leg(&self, q: &[f64], i: usize) -> (Vector3<f64>, Vector3<f64>, Vector3<f64>) {
        let o = self.platform;
        let x = Vector3::new(q[o], q[o + 1], q[o + 2]);
        let r = haptloop_solver::rotation::rotation_wxyz([q[o + 3], q[o + 4], q[o + 5], q[o + 6]])
            .unwrap();
        let arm = r * self.top[i];
        (self.base[i], arm, x + arm)
    }

    /// Leg i's length (base attachment to platform attachment) at `q`, m.
    fn length(&self, q: &[f64], i: usize) -> f64 {
        let (b, _, p) = self.leg(q, i);
        (p - b).norm()
    }

    /// σ_min/σ_max of the platform's wrench Jacobian at `q`: row i the
    /// Plücker coordinates of leg i's line, its unit direction u_i and its
    /// moment about the platform's centre (r_i × u_i)/radius. A leg,
    /// spherical at the platform, can only push or pull along its line, so
    /// this is 0 exactly where some wrench on the platform is one no leg
    /// force can balance: a Gough–Stewart singular pose.
    fn conditioning(&self, q: &[f64]) -> f64 {
        let mut w = Matrix6::zeros();
        for i in 0..6 {
            let (b, arm, p) = self.leg(q, i);
            let u = (p - b).normalize();
            let m = arm.cross(&u) / self.radius_m;
            w.fixed_view_mut::<1, 3>(i, 0).copy_from(&u.transpose());
            w.fixed_view_mut::<1, 3>(i, 3).copy_from(&m.transpose());
        }
        let sv = w.singular_values();
        sv.min() / sv.max()
    }
}

/// What a run through the Stewart platform's singular pose showed.
#[derive(Debug)]
struct SingularRun {
    /// σ_min/σ_max of the legs' wrench matrix at the first tick, at the
    /// tick closest to singular, and that tick and the platform's height
    /// there (m; the base attachment points are at 0).
    wrench_first: f64,
    wrench_least: f64,
    least_tick: u64,
    least_z_m: f64,
    /// σ_min/σ_max of the rows the solver held (equalities, limits at their
    /// bounds): at the first tick and the least over the run.
    rows_first: f64,
    rows_least: f64,
    /// The last tick whose violation exceeded the scene's tolerance or
    /// that failed (None: none did).
    last_bad_tick: Option<u64>,
}

/// The hand's path through the Stewart platform's singular pose: the
/// platform down 12 cm into the plane of the base attachment points over
/// 1 s, held there 0.3 s, 1 cm further (below it) and back, held 0.3 s, and
/// up again over 1 s; the hand leaves the singular pose at 2 s. The arm's
/// workspace box reaches 9.55 cm below its home pose, so every device
/// metre is two scene metres (the hand moves 6.5 cm). Each slider's stroke
/// limits become `[lower[i], 0.04]`.
fn stewart_through_its_base_plane(t: &mut Table, lower: [f64; 6]) {
    for j in tables(t, "joint") {
        let Some(i) = j
            .get("name")
            .and_then(Value::as_str)
            .and_then(|n| n.strip_prefix("slider"))
        else {
            continue;
        };
        let i: usize = i.parse().unwrap();
        j.insert(
            "limits".into(),
            Value::Array(vec![Value::Float(lower[i]), Value::Float(0.04)]),
        );
    }
    tables(t, "device")
        .next()
        .unwrap()
        .insert("scale".into(), Value::Float(2.0));
    set_waypoints(
        t,
        0,
        &[
            [0.0, 0.0, 0.0, 0.0],
            [0.2, 0.0, 0.0, 0.0],
            [1.2, 0.0, 0.0, -0.12],
            [1.5, 0.0, 0.0, -0.12],
            [1.6, 0.0, 0.0, -0.13],
            [1.7, 0.0, 0.0, -0.12],
            [2.0, 0.0, 0.0, -0.12],
            [3.0, 0.0, 0.0, 0.0],
        ],
    );
}

/// Runs the Stewart platform through its base plane with the sliders'
/// lower stroke limits at `lower`, measuring the singularity as it goes,
/// and asserts what every case of the matrix asserts (`check_recovered`),
/// back within tolerance `settle_s` after the hand leaves the singular
/// pose (at 2 s, tick 2000), and that it went through a singular pose.
fn drive_stewart_singular(
    name: &str,
    lower: [f64; 6],
    settle_s: f64,
    may_fail: bool,
) -> (Outcome, SingularRun) {
    let scene = edited("stewart", |t| stewart_through_its_base_plane(t, lower));
    let legs = StewartLegs::of(&scene);
    let mut c = case(name.into(), scene, options(4.0));
    c.disturbance_end_s = 2.0;
    c.settle_s = settle_s;
    c.may_fail = may_fail;
    let tol = c.scene.compiled.settings.violation_tolerance.unwrap();
    let mut s = SingularRun {
        wrench_first: f64::NAN,
        wrench_least: f64::INFINITY,
        least_tick: 0,
        least_z_m: f64::NAN,
        rows_first: f64::NAN,
        rows_least: f64::INFINITY,
        last_bad_tick: None,
    };
    let o = drive_with(&c, &mut |k, p| {
        let w = legs.conditioning(p.q());
        if k == 0 {
            s.wrench_first = w;
        }
        if w < s.wrench_least {
            (s.wrench_least, s.least_tick) = (w, k);
            s.least_z_m = p.q()[legs.platform + 2];
        }
        // (A failed tick is one of these too; `check_recovered` counts
        // them after the settle window.)
        let r = p.last_report();
        if r.status != TickOutcome::Ok || r.max_violation_m > tol {
            s.last_bad_tick = Some(k);
        }
        // Only configurations a tick held; every tick near the pose.
        if (k % 10 == 0 || w < 1e-2) && r.status == TickOutcome::Ok && r.max_violation_m <= 1e-4 {
            let j = joint_conditioning(&c.scene, p.q());
            if k == 0 {
                s.rows_first = j;
            }
            s.rows_least = s.rows_least.min(j);
        }
    });
    eprintln!("{name}: {s:?}; {o:?}");
    let o = check_recovered(&c, o);
    assert_eq!(
        o.failure_kinds.iter().map(|(_, n)| n).sum::<u64>(),
        o.failed,
        "{name}: {o:?}"
    );
    // Over the tolerance at any tick: the report says so, never "kept".
    if o.violation_max_m > tol {
        assert!(
            o.verdict.contains("EXCEEDED") && !o.verdict.contains("kept"),
            "{name}: {}",
            o.verdict
        );
    }
    // Measured independently of the solver: the run went through a
    // singular pose, from a well-conditioned start.
    assert!(s.wrench_first > 0.1, "{name}: {s:?}");
    assert!(
        s.wrench_least < 1e-3 && s.least_z_m.abs() < 1e-4,
        "{name}: the singular pose was not reached: {s:?}"
    );
    (o, s)
}

/// The Stewart platform lowered into the plane of its base attachment
/// points, through it and back (`stewart_through_its_base_plane`). There
/// all six leg lines lie in one plane, so their Plücker coordinates span
/// rank 3 and no leg force can hold a vertical force or a tilt: the classic
/// Gough–Stewart singularity. The legs must shorten from 13.3 cm to 5.7 cm
/// for it, beyond the scene's −4 cm stroke, so the lower stroke limits are
/// widened to −10 cm. The legs are unactuated: the rows the solver holds
/// (each leg a U-P-S chain with six freedoms of its own) keep their rank,
/// conditioning 3.3e-2 at the start and 1.4e-2 at the least, and the
/// singularity is the one the legs have as struts: measured from q and the
/// scene file's anchors (`StewartLegs`), independently of the solver, the
/// legs' wrench matrix falls from σ_min/σ_max 0.286 at the start to 1.8e-4
/// at the closest tick (tick 1197, the platform 14 µm below the plane).
/// The loop holds the mechanism within its 0.1 mm tolerance at every tick
/// (6.9e-7 m at most), no tick fails, the motors' force reaches 0.513 of
/// the arm's peak, and |e|² stays within 9e-6 of 1.
#[test]
fn the_stewart_singular_pose() {
    let (o, s) = drive_stewart_singular("stewart singular pose", [-0.10; 6], 0.5, false);
    assert_eq!(o.failed, 0, "{o:?}");
    assert!(o.violation_max_m <= 1e-4, "{o:?}");
    assert_eq!(s.last_bad_tick, None, "{s:?}");
}

/// The stroke limits of `the_stewart_singular_pose` with each leg's lower
/// limit `by` off its length in the base plane: `by` = 0, the six legs
/// reach their stops together at the singular pose and act there as
/// locked struts, so the rows the solver holds lose rank as well.
fn stewart_legs_bottoming_out(by: f64) -> [f64; 6] {
    let stewart = builtin("stewart");
    let legs = StewartLegs::of(&stewart);
    let q0 = stewart.compiled.model.q0();
    let mut flat = q0.to_vec();
    flat[legs.platform + 2] = 0.0;
    std::array::from_fn(|i| legs.length(&flat, i) - legs.length(q0, i) + by)
}

/// The same, with the legs bottoming out in the base plane: there the six
/// limits become active together at a pose where the legs' lines are
/// coplanar, and the held rows lose rank (conditioning 3.3e-2 → 2.6e-9).
/// The passage is chaotic: the solver asks for up to 17× the arm's peak
/// force (the safety layer clamps it), and whether ticks fail or the
/// violation merely exceeds the tolerance depends on the limits' last bits.
/// With the limits exactly at the in-plane lengths two ticks fail
/// (`force_solve`, counted, the report says FAILED TICKS, not "kept"), the
/// violation reaches 0.107 mm, and the last tick over the tolerance is
/// tick 1759, before the hand leaves the pose at 2 s.
#[test]
fn the_stewart_legs_bottoming_out_in_the_singular_pose() {
    let (o, s) = drive_stewart_singular(
        "stewart legs bottoming out",
        stewart_legs_bottoming_out(0.0),
        1.0,
        true,
    );
    assert!(
        s.rows_least < 1e-6,
        "the held rows did not lose rank: {s:?}"
    );
    assert!(o.violation_max_m <= 5e-3, "{o:?}");
    assert!(s.last_bad_tick.is_none_or(|k| k < 3000), "{s:?}");
}

/// Each lower limit 1 nm below the in-plane length: beside the singular
/// pose (1.8 s) the fast loop falls into a period-5 cycle — each Gauss–Newton
/// step halves the platform's height (4.8 → 2.4 → 1.2 → 0.6 mm, Newton at a
/// singular root) and the active limits throw it back — with violations
/// 3.6e-4, 7.6e-5, 1.9e-5, 4.7e-6, 6.6e-5 m and no failed tick. The slow loop
/// looks every 5 ticks, the cycle's own period; it used to land on the
/// 6.6e-5 m tick each time, under its 1e-4 m threshold, and never
/// re-projected, so the platform stayed jammed to the end of the run. Now
/// each snapshot carries the largest violation since the slow loop's last
/// look (`Snapshot::peak_violation_m`), the re-projection fires, and the
/// platform is back within tolerance before the hand leaves the pose (tick
/// 2121 of 4000); the run's verdict is `EXCEEDED`, never `kept`.
#[test]
fn the_stewart_legs_bottoming_out_1_nm_short() {
    let (o, s) = drive_stewart_singular(
        "stewart legs bottoming out, 1 nm short",
        stewart_legs_bottoming_out(-1e-9),
        1.0,
        true,
    );
    assert!(s.wrench_least < 1e-4 * s.wrench_first, "{s:?}");
    assert!(o.violation_max_m > 1e-4, "the cycle was not reached: {o:?}");
    assert_eq!(o.verdict, "EXCEEDED", "{o:?}");
    assert!(
        s.last_bad_tick.is_some_and(|k| k < 2500),
        "still jammed after the hand left the pose: {s:?}"
    );
    assert!(o.violation_after_m <= 1e-6, "{o:?}");
}

/// KNOWN BUG (issue 11), reproduced: with the limits 10 nm short the same
/// period-5 cycle does not clear even with the slow loop re-projecting on
/// the largest violation since its last look (0.65 mm to the end of the
/// run), and 1 pm short every tick fails (`force_solve`, counted) from
/// 2.2 s on. The fast loop's step at a rank-deficient set of active limits
/// is what needs fixing.
#[test]
#[ignore = "known bug: a period-5 jam at the Stewart singular pose when six active limits lose rank"]
fn the_stewart_legs_bottoming_out_10_nm_short() {
    let (o, s) = drive_stewart_singular(
        "stewart legs bottoming out, 10 nm short",
        stewart_legs_bottoming_out(-1e-8),
        1.0,
        true,
    );
    assert!(
        s.last_bad_tick.is_some_and(|k| k < 2500) && o.violation_after_m <= 1e-6,
        "jammed: {s:?} {o:?}"
    );
}

/// The Stewart platform lifted into all six stroke limits at once (6 s of
/// its own path): more active rows than the platform has freedoms.
#[test]
fn the_stewart_platform_at_its_stroke_limits() {
    assert_recovers(&case(
        "stewart limits".into(),
        builtin("stewart"),
        options(6.0),
    ));
}
