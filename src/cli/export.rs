//! `haptloop export mjcf SCENE`: a scene as a MuJoCo model
//! (`crate::export::mjcf`), the one `benches/peers/` compares against.

use super::output::{check_writable, write_atomic};
use super::values;
use crate::export::mjcf::{self, Options, Stiffness};
use crate::scenes::resolve;
use anyhow::Result;
use clap::{Args, Subcommand};
use std::path::PathBuf;
use std::process::ExitCode;

/// Flags of `haptloop export`.
#[derive(Debug, Args)]
pub struct ExportArgs {
    #[command(subcommand)]
    format: Format,
}

#[derive(Debug, Subcommand)]
enum Format {
    /// MuJoCo's MJCF: the shallowest kinematic tree, loops closed by
    /// `connect`/`weld` equalities, a mocap body per finger.
    ///
    /// Which joints form the tree and how each loop is closed, and what is
    /// refused (contact, design variables, joint kinds MuJoCo has no exact
    /// counterpart for), is in benches/peers/README.md.
    Mjcf(MjcfArgs),
}

/// Flags of `haptloop export mjcf`.
#[derive(Debug, Args)]
pub struct MjcfArgs {
    /// A built-in scene (see `haptloop scenes`), a generated one
    /// (`lattice-8x32`) or a scene file (TOML).
    pub scene: String,
    /// Write the MJCF to FILE (default: standard output).
    #[arg(long, short, value_name = "FILE")]
    pub out: Option<PathBuf>,
    /// Write what the export decided (tree, closures, every joint in body
    /// frames, each finger's start and hand path) as JSON to FILE.
    #[arg(long, value_name = "FILE")]
    pub meta: Option<PathBuf>,
    /// Keep JOINT out of the tree and close it as an equality (repeatable;
    /// spherical, revolute or fixed joints).
    #[arg(long, value_name = "JOINT")]
    pub cut: Vec<String>,
    /// Root a component without a fixed body at BODY instead of at the body
    /// that gives the shallowest tree.
    #[arg(long, value_name = "BODY")]
    pub root: Option<String>,
    /// Close every revolute loop with two `connect`s, even where the tree
    /// keeps its axes parallel and one would do.
    #[arg(long)]
    pub two_connects: bool,
    /// Damping on every tree joint (≥ 0; default none, as in the scene).
    #[arg(long, value_parser = values::non_negative)]
    pub damping: Option<f64>,
    /// Loop and limit `solref` in timesteps (> 0; default 2, the stiffest
    /// MuJoCo recommends), or `default` for MuJoCo's own.
    #[arg(long, value_name = "STEPS|default", value_parser = stiffness)]
    pub solref: Option<Stiffness>,
}

fn stiffness(s: &str) -> Result<Stiffness, String> {
    if s == "default" {
        return Ok(Stiffness::Default);
    }
    values::positive(s).map(Stiffness::Timesteps)
}

/// Writes the MJCF (and its metadata).
pub fn run(args: &ExportArgs) -> Result<ExitCode> {
    let Format::Mjcf(a) = &args.format;
    let scene = match resolve(&a.scene) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("{e}");
            return Ok(ExitCode::from(1));
        }
    };
    for path in [&a.out, &a.meta].into_iter().flatten() {
        check_writable(path)?;
    }
    let options = Options {
        cut: a.cut.clone(),
        root: a.root.clone(),
        two_connects: a.two_connects,
        damping: a.damping.unwrap_or(0.0),
        stiffness: a.solref.unwrap_or(Stiffness::Timesteps(2.0)),
        rate_hz: None,
    };
    let export = match mjcf::export(&scene, &options) {
        Ok(e) => e,
        Err(e) => {
            eprintln!("{}: {e:#}", a.scene);
            return Ok(ExitCode::from(1));
        }
    };
    match &a.out {
        Some(path) => write_atomic(path, export.xml.as_bytes())?,
        None => {
            // A closed stdout (`| head`) is not an error.
            use std::io::Write;
            let _ = std::io::stdout().lock().write_all(export.xml.as_bytes());
        }
    }
    if let Some(path) = &a.meta {
        let json = serde_json::to_string_pretty(&export.meta)? + "\n";
        write_atomic(path, json.as_bytes())?;
    }
    Ok(ExitCode::SUCCESS)
}
