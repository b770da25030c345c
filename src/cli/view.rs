//! `haptloop view RUN_DIR`: writes `RUN_DIR/view.html` from a run's files.

use super::output::write_atomic;
use anyhow::Result;
use clap::Args;
use std::path::PathBuf;
use std::process::ExitCode;

/// Flags of `haptloop view`.
#[derive(Debug, Args)]
pub struct ViewArgs {
    /// A run folder written by `haptloop run` (scene.json, bodies.csv,
    /// fingers.csv, contacts.csv, trace.csv, summary.json).
    pub run_dir: PathBuf,
}

/// Writes the page and says where it is.
pub fn run(args: &ViewArgs) -> Result<ExitCode> {
    match crate::view::write_page(&args.run_dir, write_atomic) {
        Ok(path) => {
            super::emit(&format!(
                "wrote {}: open it in a browser (one file: no server, no network)",
                path.display()
            ));
            Ok(ExitCode::SUCCESS)
        }
        Err(e) => {
            eprintln!("haptloop view: {e:#}");
            Ok(ExitCode::from(1))
        }
    }
}
