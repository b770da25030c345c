//! The solver flags `run` and `bench` share: one declaration, flattened
//! into both (`#[command(flatten)]`), so they cannot drift apart.

use super::values;
use crate::session::SessionOptions;
use clap::Args;
use haptloop_rt::schedule::{MAX_RATE_HZ, MIN_RATE_HZ};
use std::time::Duration;

/// The fast loop's solver settings from the command line; each unset flag
/// leaves the scene's value, else the solver's default.
#[derive(Debug, Clone, Default, PartialEq, Args)]
pub struct SolverArgs {
    /// Fast-loop rate in Hz (100–20000); default: the scene's, else 1000.
    #[arg(long, value_parser = clap::value_parser!(u32).range(i64::from(MIN_RATE_HZ)..=i64::from(MAX_RATE_HZ)))]
    pub rate: Option<u32>,
    /// Augmented-Lagrangian iterations per tick (1–10000): more is more
    /// accurate and costs more per tick. Default: the scene's, else the
    /// solver's.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=10_000))]
    pub iterations: Option<u32>,
    /// Update rule of the fast loop: `projected` (Gauss–Newton with the
    /// force solve's factor; the default) or `gradient` (Nelson & Cohen
    /// Eq. 1–3).
    #[arg(long, value_name = "RULE", value_parser = values::update_rule)]
    pub update: Option<haptloop_solver::UpdateRule>,
    /// Eq. 7 solver: `cholesky` (a numeric factorisation a tick; the
    /// default) or `matvec` (experimental: no factorisation in the tick,
    /// conjugate gradients preconditioned by a factor the slow loop
    /// refreshes, a solve that reaches the cap redone with a factorisation;
    /// not for contact; measured slower than `cholesky` on every mechanism,
    /// BENCHMARKS.md), `matvec:N` to cap its iterations at N (default 64),
    /// `tree` (experimental: no full factor, conjugate gradients
    /// preconditioned by a spanning tree of the mechanism; not for contact;
    /// measured slower than `cholesky` on meshes, BENCHMARKS.md), `tree:N`
    /// to cap its iterations a solve at N (default 500), `multilevel` and
    /// `multilevel:N` (experimental: conjugate gradients preconditioned by
    /// an aggregation V-cycle; not for contact), `cg:N`
    /// (Jacobi-preconditioned, gradient update only).
    #[arg(long, value_name = "SOLVER", value_parser = values::force_solver)]
    pub force_solver: Option<haptloop_solver::ForceSolver>,
    /// The fast loop's coordinates: `augmented` (every body's seven
    /// coordinates, every joint a set of rows; the default), `joint` (the
    /// tick in joint coordinates: quasi-static mechanisms with point
    /// fingers, no contact, limits or torque outputs; refused with the
    /// reason otherwise) or `auto` (joint where it applies). Default: the
    /// scene's `[solver] coordinates`, else `augmented`.
    #[arg(long, value_name = "COORDS", value_parser = values::coordinates)]
    pub coordinates: Option<haptloop_solver::Coordinates>,
    /// Constraint gain K of the fast update (finite, > 0). Default: the
    /// scene's, else the solver's.
    #[arg(long, value_parser = values::positive)]
    pub gain: Option<f64>,
    /// Time constant of the low-pass filter on the velocities behind the
    /// Eq. 7 inertial force, ms (0 turns it off). Default: the scene's, else
    /// 10 ms: encoder quantisation makes unfiltered accelerations buzz.
    #[arg(long, value_name = "MS", value_parser = values::filter_ms)]
    pub velocity_filter_ms: Option<f64>,
}

impl SolverArgs {
    /// Writes every flag into `options` (an unset flag writes `None`: the
    /// scene's value, else the solver's).
    pub fn apply(&self, options: &mut SessionOptions) {
        options.rate_hz = self.rate;
        options.iterations = self.iterations;
        options.update = self.update;
        options.force_solver = self.force_solver;
        options.coordinates = self.coordinates;
        options.gain = self.gain;
        options.velocity_filter = self
            .velocity_filter_ms
            .map(|ms| Duration::from_secs_f64(ms / 1000.0));
    }
}

#[cfg(test)]
mod tests {
    use super::super::{Cli, Command, bench, run};
    use super::SolverArgs;
    use clap::Parser;
    use haptloop_solver::{Coordinates, ForceSolver, UpdateRule};
    use std::time::Duration;

    /// Every solver flag, set away from its default.
    const FLAGS: [&str; 14] = [
        "--rate",
        "500",
        "--iterations",
        "3",
        "--update",
        "gradient",
        "--force-solver",
        "matvec:8",
        "--coordinates",
        "joint",
        "--gain",
        "2.5",
        "--velocity-filter-ms",
        "4",
    ];

    fn parse(sub: &str, flags: &[&str]) -> Command {
        let argv = ["haptloop", sub, "four-bar"]
            .into_iter()
            .chain(flags.iter().copied());
        Cli::try_parse_from(argv)
            .unwrap_or_else(|e| panic!("`{sub}` refused {flags:?}: {e}"))
            .command
            .expect("a subcommand")
    }

    fn run_args(flags: &[&str]) -> run::RunArgs {
        match parse("run", flags) {
            Command::Run(a) => a,
            other => panic!("parsed as {other:?}"),
        }
    }

    fn bench_args(flags: &[&str]) -> bench::BenchArgs {
        match parse("bench", flags) {
            Command::Bench(a) => a,
            other => panic!("parsed as {other:?}"),
        }
    }

    #[test]
    fn run_and_bench_accept_and_apply_the_same_solver_flags() {
        let (r, b) = (run_args(&FLAGS), bench_args(&FLAGS));
        let written = SolverArgs {
            rate: Some(500),
            iterations: Some(3),
            update: Some(UpdateRule::Gradient),
            force_solver: Some(ForceSolver::Matvec { max_iterations: 8 }),
            coordinates: Some(Coordinates::Joint),
            gain: Some(2.5),
            velocity_filter_ms: Some(4.0),
        };
        assert_eq!(r.solver, written);
        assert_eq!(b.solver, written);
        // What each subcommand hands the session.
        let ro = run::session_options(&r, None);
        let bo = bench::bench_options(&b.solver, 500, 2.0);
        for o in [&ro, &bo] {
            assert_eq!(o.rate_hz, Some(500));
            assert_eq!(o.iterations, Some(3));
            assert_eq!(o.update, Some(UpdateRule::Gradient));
            assert_eq!(
                o.force_solver,
                Some(ForceSolver::Matvec { max_iterations: 8 })
            );
            assert_eq!(o.coordinates, Some(Coordinates::Joint));
            assert_eq!(o.gain, Some(2.5));
            assert_eq!(o.velocity_filter, Some(Duration::from_millis(4)));
        }
        // The rest of each subcommand's options is its own.
        assert!(bo.deterministic && !ro.deterministic);
        assert_eq!((ro.seconds, bo.seconds), (10.0, 2.0));
    }

    #[test]
    fn unset_solver_flags_leave_the_scene_its_settings_in_both() {
        let (r, b) = (run_args(&[]), bench_args(&[]));
        assert_eq!(r.solver, SolverArgs::default());
        assert_eq!(b.solver, SolverArgs::default());
        let ro = run::session_options(&r, None);
        // bench resolves the rate before the session (the scene's, else 1000).
        let bo = bench::bench_options(&b.solver, 1000, 5.0);
        assert_eq!((ro.rate_hz, bo.rate_hz), (None, Some(1000)));
        for o in [&ro, &bo] {
            assert_eq!(o.iterations, None);
            assert_eq!(o.update, None);
            assert_eq!(o.force_solver, None);
            assert_eq!(o.coordinates, None);
            assert_eq!(o.gain, None);
            assert_eq!(o.velocity_filter, None);
        }
    }

    #[test]
    fn a_bad_solver_flag_is_refused_by_both_naming_it() {
        for sub in ["run", "bench"] {
            for (flag, value) in [
                ("--rate", "50"),
                ("--gain", "-1"),
                ("--force-solver", "matvec:0"),
                ("--coordinates", "polar"),
            ] {
                let arg = format!("{flag}={value}");
                let err = Cli::try_parse_from(["haptloop", sub, "four-bar", arg.as_str()])
                    .expect_err("refused");
                assert!(err.to_string().contains(flag), "{sub} {flag}: {err}");
            }
        }
    }
}
