//! The four-bar driven into its toggle.

use haptloop::scenes::Scene;
use haptloop_solver::TickOutcome;

use super::edit::{edited, set_waypoints};
use super::harness::{case, check_recovered, drive_with, options};

/// The four-bar's transmission at `q`: how fast the crank and the rocker
/// move (their centres) against the coupler's centre along the linkage's
/// one freedom (the null vector of the joint rows' C_q). At a toggle one of
/// the two stands still while the coupler moves: this goes to 0.
fn four_bar_transmission(scene: &Scene, q: &[f64]) -> f64 {
    let model = &scene.compiled.joints_only;
    let mut ev = haptloop_solver::Evaluation::new(model);
    ev.evaluate(model, q, &[]).unwrap();
    let j = ev.jacobian().to_dense();
    let e = (j.transpose() * &j).symmetric_eigen();
    let k = e.eigenvalues.imin();
    let n = e.eigenvectors.column(k);
    let speed = |name: &str| {
        let (_, off) = model
            .layout()
            .moving_bodies()
            .find(|(id, _)| model.bodies()[id.index()].name == name)
            .unwrap();
        (n[off].powi(2) + n[off + 1].powi(2) + n[off + 2].powi(2)).sqrt()
    };
    speed("crank").min(speed("rocker")) / speed("coupler")
}

/// The four-bar driven into its toggle: the hand pulls the coupler 0.2 m
/// out along each direction of its circle's plane in turn (far beyond the
/// linkage's reach), so the linkage runs to the ends of its range, where it
/// locks (this spatial linkage is not Grashof: its range ends at toggle
/// poses, where the joint rows lose rank). The conditioning of the joint
/// rows' C_q falls by the factor asserted below, and the loop is back
/// within 1 µm 0.5 s after the hand returns.
#[test]
fn the_four_bar_toggle() {
    let u = [0.045194, -0.997943, -0.045474];
    let v = [0.556809, 0.062958, -0.828251];
    let at = |d: [f64; 3], s: f64| [d[0] * s, d[1] * s, d[2] * s];
    let mut path = vec![[0.0, 0.0, 0.0, 0.0]];
    let mut t = 0.2;
    for d in [at(u, 0.2), at(u, -0.2), at(v, 0.2), at(v, -0.2)] {
        path.push([t, 0.0, 0.0, 0.0]);
        path.push([t + 0.3, d[0], d[1], d[2]]);
        path.push([t + 0.6, d[0], d[1], d[2]]);
        path.push([t + 0.9, 0.0, 0.0, 0.0]);
        t += 1.0;
    }
    let end = t - 0.1;
    let scene = edited("four-bar", |s| set_waypoints(s, 0, &path));
    let mut c = case("four-bar toggle".into(), scene, options(end + 1.0));
    c.disturbance_end_s = end;
    c.settle_s = 0.5;
    c.expect_failures = true;
    let (mut first, mut least) = (f64::NAN, f64::INFINITY);
    let o = drive_with(&c, &mut |k, p| {
        // Only configurations a tick held (a failed tick's q is not one).
        let r = p.last_report();
        if k % 10 == 0 && r.status == TickOutcome::Ok && r.max_violation_m <= 1e-4 {
            let r = four_bar_transmission(&c.scene, p.q());
            if k == 0 {
                first = r;
            }
            least = least.min(r);
        }
    });
    let o = check_recovered(&c, o);
    eprintln!("four-bar toggle: transmission {least:e} (start {first:e}); {o:?}");
    assert!(
        least < 0.05 * first,
        "the toggle was not reached: transmission {least:e} against {first:e} at the start"
    );
    // The fast loop cannot hold the linkage while the hand yanks it into
    // the toggle: those ticks fail as counted, named failures (force cut,
    // the slow loop re-places it), none after the settle window.
    let kinds: Vec<&str> = o.failure_kinds.iter().map(|(k, _)| *k).collect();
    assert!(
        kinds
            .iter()
            .all(|k| ["diverged_violation", "violation_beyond_broken"].contains(k)),
        "{o:?}"
    );
    assert_eq!(
        o.failure_kinds.iter().map(|(_, n)| n).sum::<u64>(),
        o.failed
    );
}
