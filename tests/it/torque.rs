//! §5.2's joint torque end to end: a scene names a joint (`report_torque`),
//! a deterministic session reports the torque a motor on its axis would
//! need, in `trace.csv` and `summary.json`, against the closed form of a
//! pendulum held still under gravity.

use haptloop::report::summary::Summary;
use haptloop::scenes::check_loaded;
use haptloop::session::{self, Plan, SessionOptions};
use haptloop_rt::schedule::StopFlag;
use haptloop_solver::scene;

/// A 0.2 kg arm, centre of mass 0.1 m from its hinge (axis world y),
/// 0.6 rad below horizontal toward +x, held still at its tip by the hand.
const PENDULUM: &str = r#"
[scene]
name = "pendulum-torque"
gravity = [0.0, 0.0, -9.81]

[[device]]
name = "right"
model = "phantom-premium-1.5"

[[body]]
name = "ground"
fixed = true

[[body]]
name = "arm"
position = [0.08253356149096783, 0.0, -0.05646424733950354]
orientation = [0.955336489125606, 0.0, 0.29552020666133955, 0.0]
mass = 0.2
inertia = [6.666666666666668e-4, 6.666666666666668e-4, 1e-6]

[[joint]]
name = "hinge"
kind = "revolute"
bodies = ["ground", "arm"]
anchors = [[0.0, 0.0, 0.0], [-0.1, 0.0, 0.0]]
axes = [[0.0, 1.0, 0.0], [0.0, 1.0, 0.0]]
report_torque = true

[[finger]]
name = "tip"
device = "right"
body = "arm"
point = [0.05, 0.0, 0.0]
"#;

/// The arm's centre of mass is at l (cos φ, 0, −sin φ), φ below horizontal;
/// gravity turns it about +y by m g l cos φ, so the hinge's motor must
/// apply −m g l cos φ. The arm hangs on a simulated hand whose grip sags
/// under the load (φ settles at 0.62 rad in about a second); at the end of
/// 3 s the trace's column agrees with the closed form at the angle the
/// trace shows to 1e-4 (the encoder's counts still twitch the arm by
/// 1e-8 rad, and Eq. 7 sees those accelerations: a few 1e-6), and the
/// summary's last value is the trace's.
#[test]
fn a_named_joints_motor_torque_reaches_trace_csv_and_summary_json() {
    let loaded = scene::parse("pendulum-torque.toml", PENDULUM, None).unwrap();
    let scene = check_loaded(loaded).unwrap();
    let dir = std::env::temp_dir().join(format!("haptloop-torque-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let options = SessionOptions {
        seconds: 3.0,
        deterministic: true,
        out_dir: Some(dir.clone()),
        ..SessionOptions::default()
    };
    let plan = Plan::new(&scene, &options).unwrap();
    let o = session::run(&scene, plan, &StopFlag::new(), &mut |_| {}).unwrap();
    let s = Summary::of(&o);
    let csv = std::fs::read_to_string(dir.join("trace.csv")).unwrap();
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let last: Vec<f64> = lines
        .last()
        .unwrap()
        .split(',')
        .enumerate()
        .map(|(k, v)| if k == 1 { 0.0 } else { v.parse().unwrap() })
        .collect();
    // Where the arm hangs at the end (the hand's grip sags under the load):
    // the tip, 0.15 m from the hinge, gives its angle below horizontal.
    let phi = (-last[col("position_z_m")]).atan2(last[col("position_x_m")]);
    assert!((phi - 0.6).abs() < 0.1, "the arm hangs at {phi} rad");
    let (m, l) = (0.2, 0.1);
    let expected = -m * 9.81 * l * phi.cos();
    let v = last[col("torque_hinge_nm")];
    assert!(
        (v - expected).abs() < 1e-4 * expected.abs(),
        "trace {v} vs {expected}"
    );
    let t = &s.joint_torques["hinge"];
    assert_eq!(t.end, v, "summary.json's last value is the trace's");
    let _ = std::fs::remove_dir_all(&dir);
}
