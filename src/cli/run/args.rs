//! The flags of `haptloop run` and their defaults.

use super::super::rt_args::RtArgs;
use super::super::solver_args::SolverArgs;
use super::super::values;
use crate::scenes::DEFAULT_SCENE;
use crate::session;
use clap::Args;
use std::path::PathBuf;

/// Flags of `haptloop run`.
#[derive(Debug, Args)]
pub struct RunArgs {
    /// A built-in scene (see `haptloop scenes`) or a scene file (TOML).
    #[arg(default_value = DEFAULT_SCENE)]
    pub scene: String,
    /// Session length in seconds, (0, 86400].
    #[arg(long, default_value_t = 10.0, value_parser = values::seconds)]
    pub seconds: f64,
    /// The solver flags `bench` takes too.
    #[command(flatten)]
    pub solver: SolverArgs,
    /// Run on a mock clock as fast as possible: bit-identical results across
    /// runs (every summary.json field but wall_clock_s), no real-time figures.
    #[arg(long)]
    pub deterministic: bool,
    /// Start from the scene file's configuration as written, without the
    /// Newton-KKT assembly (watch the fast loop and the slow loop pull it
    /// together).
    #[arg(long)]
    pub no_assembly: bool,
    /// Output directory (default `runs/<scene>-<UTC time>/`).
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Write no files; print the report only.
    #[arg(long, conflicts_with = "out")]
    pub no_files: bool,
    /// Record every device's trace into DIR (`<device>.trace`).
    #[arg(long, value_name = "DIR")]
    pub record: Option<PathBuf>,
    /// Replay every device from DIR (`<device>.trace`) instead of simulating.
    #[arg(long, value_name = "DIR")]
    pub replay: Option<PathBuf>,
    /// Real-time thread requests.
    #[command(flatten)]
    pub rt: RtArgs,
    /// No live status line.
    #[arg(long)]
    pub quiet: bool,
    /// Frees a design variable without editing the scene (repeatable):
    /// `<joint>.length`, `<joint>.anchor_i`, `<joint>.anchor_j` or
    /// `<fixed body>.position`.
    #[arg(long, value_name = "OWNER.VAR")]
    pub free: Vec<String>,
    /// Adds an objective (repeatable): `KIND` or `KIND:key=value,…` with the
    /// keys of `[[objective]]` (docs/scene-format.md); names need no quotes,
    /// e.g. `dexterity:chain=[base,upper,fore],point=[0.1,0,0],weight=0.01`.
    #[arg(long, value_name = "KIND:KEY=VALUE,…")]
    pub objective: Vec<String>,
    /// Switches a design variable off at a session time (repeatable):
    /// `NAME@SECONDS`, e.g. `rocker.anchor_j@2.5`; held where it is until
    /// switched on again (Nelson & Cohen's design flags; `[[design_flag]]`).
    #[arg(long, value_name = "NAME@SECONDS")]
    pub design_off: Vec<String>,
    /// Switches a design variable back on at a session time (repeatable):
    /// `NAME@SECONDS`.
    #[arg(long, value_name = "NAME@SECONDS")]
    pub design_on: Vec<String>,
    /// Serve a live 3-D view on http://127.0.0.1:PORT/ (never another
    /// interface) and stream the run to it; the run starts when the page
    /// connects. Virtual devices are dragged there with the mouse.
    #[arg(long, conflicts_with = "deterministic")]
    pub live: bool,
    /// The live view's port (0: any free one).
    #[arg(long, default_value_t = 8470, requires = "live")]
    pub port: u16,
    /// Replace every device of the scene with this model (`virtual`: moved
    /// by the mouse in the live view, its scripted hand dropped; or a
    /// PHANToM model).
    #[arg(long, value_name = "MODEL")]
    pub device: Option<String>,
    /// The semantic interaction mode at the start (Gösele & Stuerzlinger
    /// §6): `constrained` (the default: a held object's offer/binding
    /// constraints act) or `unconstrained` (they are off for the held
    /// object); `[[schedule]] mode` switches it during the run.
    #[arg(long, value_name = "MODE", value_parser = semantic_mode)]
    pub semantic_mode: Option<haptloop_solver::scene::SemanticMode>,
    /// Injects a host stall on the mock clock (repeatable, deterministic
    /// runs only): `SECONDS:PERIODS`, the tick at SECONDS is followed by the
    /// next one PERIODS periods later, as after a real stall (the scheduler
    /// skips the slots between).
    #[arg(long, value_name = "SECONDS:PERIODS", requires = "deterministic", value_parser = stall)]
    pub stall: Vec<session::Stall>,
    /// Stalls the slow loop in a deterministic run (repeatable):
    /// `SECONDS:PERIODS`, no slow-loop step (contact witnesses and
    /// programs, re-projection) for PERIODS periods after SECONDS, as when
    /// the slow thread is descheduled or a contact program takes long to
    /// build.
    #[arg(long, value_name = "SECONDS:PERIODS", requires = "deterministic", value_parser = slow_stall)]
    pub slow_stall: Vec<session::Stall>,
}

/// `--slow-stall`'s values.
fn slow_stall(s: &str) -> Result<session::Stall, String> {
    session::Stall::parse_flag("--slow-stall", s).map_err(|e| e.to_string())
}

/// `--stall`'s values.
fn stall(s: &str) -> Result<session::Stall, String> {
    session::Stall::parse(s).map_err(|e| e.to_string())
}

/// `--semantic-mode`'s values.
fn semantic_mode(s: &str) -> Result<haptloop_solver::scene::SemanticMode, String> {
    use haptloop_solver::scene::SemanticMode;
    match s {
        "constrained" => Ok(SemanticMode::Constrained),
        "unconstrained" => Ok(SemanticMode::Unconstrained),
        _ => Err(format!("`{s}`: expected `constrained` or `unconstrained`")),
    }
}

impl Default for RunArgs {
    fn default() -> Self {
        RunArgs {
            scene: DEFAULT_SCENE.into(),
            seconds: 10.0,
            solver: SolverArgs::default(),
            deterministic: false,
            no_assembly: false,
            out: None,
            no_files: false,
            record: None,
            replay: None,
            rt: RtArgs::default(),
            quiet: false,
            free: Vec::new(),
            objective: Vec::new(),
            design_off: Vec::new(),
            design_on: Vec::new(),
            live: false,
            port: 8470,
            device: None,
            semantic_mode: None,
            stall: Vec::new(),
            slow_stall: Vec::new(),
        }
    }
}
