//! `haptloop scenes`: one line per built-in scene.

use crate::scenes::{BUILTIN, DEFAULT_SCENE, resolve};
use anyhow::Result;
use std::process::ExitCode;

/// Prints each built-in scene's name, size and description.
pub fn run() -> Result<ExitCode> {
    let width = BUILTIN.iter().map(|b| b.name.len()).max().unwrap_or(0);
    for b in BUILTIN {
        let scene =
            resolve(b.name).map_err(|e| anyhow::anyhow!("built-in scene is broken: {e}"))?;
        let c = &scene.compiled;
        let default = if b.name == DEFAULT_SCENE {
            " (default)"
        } else {
            ""
        };
        super::emit(&format!(
            "{:<width$} {:>3} bodies {:>4} coords {:>4} rows {} device{}  {}{default}",
            b.name,
            c.model.bodies().len(),
            c.model.n_coords(),
            c.model.n_rows(),
            c.devices.len(),
            if c.devices.len() == 1 { " " } else { "s" },
            c.description
        ));
    }
    Ok(ExitCode::SUCCESS)
}
