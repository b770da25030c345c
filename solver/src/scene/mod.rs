//! Scene files (TOML, `docs/scene-format.md`): load, validate, compile.
//!
//! ```text
//!  text ──toml+serde──► spec::SceneFile (typed, every value Spanned)
//!       ──validate────► LoadedScene      (devices, hands, wiring, areas, labels, holds checked)
//!       ──compile─────► CompiledScene    (Model via ModelBuilder; builder errors mapped to spans)
//! ```
//!
//! Every error is a [`SceneError`] naming the file, line and column and what
//! was expected: unknown keys, wrong types and lengths, missing keys and
//! duplicate keys come from the TOML layer; names, references, non-finite
//! numbers, degenerate axes, fingers on fixed bodies, label-order cycles and
//! the rest from the checks here and in the model builder.

mod compile;
mod compile_semantic;
mod design_flags;
mod error;
mod flags;
mod gear;
mod polygon;
mod semantic;
pub mod spec;
mod validate;
mod write;

pub use compile::{CompiledScene, DeviceDecl, FingerDecl, HandDecl, HandPath, SceneSettings};
pub use compile_semantic::HoldDecl;
pub use design_flags::{DesignFlagDecl, DesignFlagSection, design_switch, with_switches};
pub use error::SceneError;
pub use flags::Flagged;
pub use write::mechanism_tables;

use std::ops::Range;
use std::path::{Path, PathBuf};

/// A parsed and validated scene file, with its text kept for error messages.
#[derive(Debug, Clone)]
pub struct LoadedScene {
    /// The file name used in messages.
    pub file: String,
    /// The file's text.
    pub text: String,
    /// The typed contents.
    pub spec: spec::SceneFile,
    /// Directory that relative paths in the file (hand traces) resolve against.
    pub dir: Option<PathBuf>,
}

impl LoadedScene {
    /// An error at `span` of this file.
    pub fn error_at(&self, span: Range<usize>, message: impl Into<String>) -> SceneError {
        SceneError::at(&self.file, &self.text, span, message)
    }
}

/// Parses and validates `text`; `file` names it in errors, `dir` resolves its
/// relative paths.
pub fn parse(file: &str, text: &str, dir: Option<&Path>) -> Result<LoadedScene, SceneError> {
    let spec: spec::SceneFile = toml::from_str(text).map_err(|e| {
        SceneError::at(
            file,
            text,
            e.span().unwrap_or(0..0),
            e.message().to_string(),
        )
    })?;
    validate::Checker { file, text }.scene(&spec)?;
    Ok(LoadedScene {
        file: file.to_string(),
        text: text.to_string(),
        spec,
        dir: dir.map(Path::to_path_buf),
    })
}

/// Reads, parses and validates the scene file at `path`.
pub fn load(path: &Path) -> Result<LoadedScene, SceneError> {
    let file = path.display().to_string();
    let text = std::fs::read_to_string(path)
        .map_err(|e| SceneError::whole_file(&file, format!("cannot read the scene file: {e}")))?;
    parse(&file, &text, path.parent())
}
