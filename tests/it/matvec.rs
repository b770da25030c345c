//! The matvec-only tick (`--force-solver matvec`) through the session, the
//! command line and the sweep: its fast loop allocates nothing while the
//! slow loop refreshes its factor beside it, `run`, `bench` and `sweep`
//! take it, contact scenes are refused by name, and its force error
//! against the converged reference is measured like every other point's.

use haptloop::scenes::resolve;
use haptloop::session::{self, Plan, SessionOptions};
use haptloop::sweep::{self, Grid, Options};
use haptloop_rt::alloc::count;
use haptloop_rt::clock::{MockClock, Nanos};
use haptloop_rt::schedule::{Periodic, RunLimit, StopFlag};
use haptloop_solver::{ForceSolver, UpdateRule};
use std::process::Command;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

fn haptloop() -> Command {
    Command::new(env!("CARGO_BIN_EXE_haptloop"))
}

fn matvec(seconds: f64) -> SessionOptions {
    SessionOptions {
        seconds,
        deterministic: true,
        force_solver: Some(ForceSolver::MATVEC),
        ..SessionOptions::default()
    }
}

/// With the slow loop on its own thread refreshing the force factor and
/// handing it over, the fast thread's ticks (adopting those factors in the
/// handover stage, conjugate gradients in the force stage) allocate
/// nothing; factors were refreshed and adopted during the counted ticks
/// and no tick failed.
#[test]
fn the_matvec_fast_loop_allocates_nothing_while_factors_arrive() {
    // Bennett: where the old cap of 4 failed 661 of 1000 ticks.
    for (name, seconds) in [("stewart", 3.0), ("bennett", 1.0)] {
        let scene = resolve(name).unwrap();
        let plan = Plan::new(&scene, &matvec(seconds)).unwrap();
        let clock = MockClock::new(Nanos(0));
        let session::Built {
            mut fast,
            mut slow,
            trace,
            ..
        } = session::build(&scene, &plan, clock.clone()).unwrap();
        let done = Arc::new(AtomicBool::new(false));
        let flag = done.clone();
        let slow_thread = std::thread::spawn(move || {
            while !flag.load(Ordering::Acquire) {
                slow.step();
                std::thread::yield_now();
            }
            slow.stats()
        });
        let (mut periodic, _iv) = Periodic::new(&plan.schedule(), clock).unwrap();
        let stop = StopFlag::new();
        periodic.run(&mut fast, RunLimit::slots(100), &stop);
        let before = fast.program().factor_adoptions();
        let chunks = (plan.ticks() - 100) / 100;
        let (_, stats) = count(|| {
            for _ in 0..chunks {
                periodic.run(&mut fast, RunLimit::slots(100), &stop);
                while trace.pop().is_some() {}
                // The mock clock runs the ticks faster than real time: give
                // the slow thread time to refresh (a small scene's 100
                // ticks take well under a millisecond).
                std::thread::sleep(Duration::from_millis(2));
            }
        });
        done.store(true, Ordering::Release);
        let slow_stats = slow_thread.join().unwrap();
        assert_eq!(
            stats.total(),
            0,
            "{name}: the fast loop allocated: {stats:?}"
        );
        assert!(slow_stats.factor_refreshes > 0, "{name}: no refresh sent");
        assert!(
            fast.program().factor_adoptions() > before,
            "{name}: no factor adopted during the counted ticks"
        );
        assert_eq!(fast.stats().solver_failures, 0, "{name}");
    }
}

/// `run` and `bench` take `--force-solver matvec[:N]`; a bad value and a
/// contact scene are refused, each naming what was wrong.
#[test]
fn the_cli_takes_the_matvec_force_solver() {
    let dir = tempfile::tempdir().unwrap();
    let o = haptloop()
        .args([
            "run",
            "bennett",
            "--deterministic",
            "--seconds",
            "0.3",
            "--quiet",
            "--force-solver",
            "matvec:8",
            "--out",
        ])
        .arg(dir.path().join("run"))
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let o = haptloop()
        .args([
            "bench",
            "bennett",
            "--ticks",
            "300",
            "--force-solver",
            "matvec",
        ])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("matvec force solver"), "{out}");

    let o = haptloop()
        .args([
            "bench",
            "bennett",
            "--ticks",
            "10",
            "--force-solver",
            "matvec:0",
        ])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("--force-solver") && err.contains("matvec:0"),
        "{err}"
    );

    // Jacobi CG (`cg:N`, the sweep's comparison) parses; a bad cap is
    // refused by name, and the projected update refuses it for want of a
    // factor.
    let o = haptloop()
        .args([
            "bench",
            "bennett",
            "--ticks",
            "10",
            "--force-solver",
            "cg:0",
        ])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("cg:0"), "{err}");
    let o = haptloop()
        .args([
            "bench",
            "bennett",
            "--ticks",
            "10",
            "--force-solver",
            "cg:8",
        ])
        .output()
        .unwrap();
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("force_solver") && err.contains("Cholesky factor"),
        "{err}"
    );

    let o = haptloop()
        .args([
            "bench",
            "box-slide",
            "--ticks",
            "10",
            "--force-solver",
            "matvec",
        ])
        .output()
        .unwrap();
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("does not cover contact") && err.contains("box-slide"),
        "{err}"
    );
}

/// A sweep with the force solver as a grid dimension: the matvec points'
/// force error is measured against the converged reference like the
/// Cholesky's. With a cap high enough for the conjugate gradients to
/// converge, the matvec force is the Cholesky force: both points' errors
/// agree to a millionth of the largest reference force.
#[test]
fn the_sweep_measures_the_matvec_points_force_error() {
    let scene = resolve("stewart").unwrap();
    let grid = Grid {
        iterations: vec![4],
        update: vec![UpdateRule::Projected],
        force_solver: vec![
            ForceSolver::Cholesky,
            ForceSolver::MATVEC,
            ForceSolver::Matvec {
                max_iterations: 200,
            },
        ],
        gain: vec![1000.0],
        rate_hz: vec![1000],
        velocity_filter_ms: vec![10.0],
    };
    let options = Options {
        seconds: 0.5,
        reference_every: Duration::from_millis(10),
        threads: 1,
        force_tolerance: 0.01,
    };
    let s = sweep::run(&scene, &grid, &options, &StopFlag::new(), &|_| {}).unwrap();
    assert_eq!(s.points.len(), 3);
    let acc: Vec<_> = s
        .points
        .iter()
        .map(|p| p.accuracy.clone().expect("every point ran"))
        .collect();
    for (p, a) in s.points.iter().zip(&acc) {
        assert!(a.reference_samples > 0, "{:?}", p.knobs);
        assert!(a.force_error_n.max.is_finite(), "{:?}", p.knobs);
        assert_eq!(a.failed_ticks, 0, "{:?}", p.knobs);
    }
    let (chol, converged) = (&acc[0], &acc[2]);
    assert!(
        (chol.force_error_n.max - converged.force_error_n.max).abs() <= 1e-6 * chol.force_max_n,
        "Cholesky {} N against matvec:200 {} N (largest force {} N)",
        chol.force_error_n.max,
        converged.force_error_n.max,
        chol.force_max_n
    );
    let csv = haptloop::report::sweep::csv(&s);
    assert!(
        csv.contains(",matvec,") && csv.contains(",matvec:200,"),
        "{csv}"
    );
}

/// The sweep's accuracy pass (the slow loop refreshing the factor every
/// 5 ms beside the fast loop, the converged reference every 10 ms) on the
/// two mechanisms where the old cap of 4 failed ticks: at the default cap
/// no matvec tick fails and its force error against the converged
/// reference is the Cholesky tick's to 1e-6 of the largest force.
#[test]
fn the_matvec_point_fails_no_tick_on_bennett_and_the_lattice() {
    let seconds = if cfg!(debug_assertions) { 0.05 } else { 0.3 };
    for name in ["bennett", "lattice"] {
        let scene = resolve(name).unwrap();
        let grid = Grid {
            iterations: vec![4],
            update: vec![UpdateRule::Projected],
            force_solver: vec![ForceSolver::Cholesky, ForceSolver::MATVEC],
            gain: vec![1000.0],
            rate_hz: vec![1000],
            velocity_filter_ms: vec![10.0],
        };
        let options = Options {
            seconds,
            reference_every: Duration::from_millis(10),
            threads: 1,
            force_tolerance: 0.01,
        };
        let s = sweep::run(&scene, &grid, &options, &StopFlag::new(), &|_| {}).unwrap();
        let acc: Vec<_> = s
            .points
            .iter()
            .map(|p| p.accuracy.clone().expect("every point ran"))
            .collect();
        for (p, a) in s.points.iter().zip(&acc) {
            assert_eq!(a.failed_ticks, 0, "{name} {:?}", p.knobs);
            assert!(a.reference_samples > 0, "{name} {:?}", p.knobs);
        }
        let (chol, mv) = (&acc[0], &acc[1]);
        assert!(
            (chol.force_error_n.max - mv.force_error_n.max).abs()
                <= 1e-6 * chol.force_max_n.max(1e-3),
            "{name}: Cholesky {} N against matvec {} N (largest force {} N)",
            chol.force_error_n.max,
            mv.force_error_n.max,
            chol.force_max_n
        );
    }
}

/// Both conjugate-gradient ticks are refused on a scene with shaped bodies
/// before the run starts, with the solver and the scene named.
#[test]
fn the_cg_ticks_refuse_contact_scenes_before_the_run() {
    for solver in ["matvec", "tree", "tree:16"] {
        let o = haptloop()
            .args([
                "run",
                "box-slide",
                "--deterministic",
                "--seconds",
                "0.1",
                "--no-files",
                "--force-solver",
                solver,
            ])
            .output()
            .unwrap();
        assert!(!o.status.success());
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            err.contains(&format!("--force-solver {solver} does not cover contact"))
                && err.contains("box-slide")
                && !err.contains("running `"),
            "{solver}: {err}"
        );
    }
}
