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
pub mod limits;
pub mod magnitudes;
mod no_effect;
mod placed;
mod polygon;
mod schedule;
mod semantic;
mod settings;
pub mod spec;
mod validate;
mod write;

pub use compile::{CompiledScene, DeviceDecl, FingerDecl, HandDecl, HandPath};
pub use compile_semantic::HoldDecl;
pub use design_flags::{DesignFlagDecl, DesignFlagSection, design_switch, with_switches};
pub use error::SceneError;
pub use flags::Flagged;
pub use placed::BodyPose;
pub use schedule::{ScheduleAction, ScheduleDecl, ScheduleSection, SemanticMode};
pub use settings::SceneSettings;
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

/// Largest scene file [`load`] reads: 4 MiB. The largest built-in scene is
/// 0.28 MB; a 4 MiB four-bar with 130 000 hand waypoints peaks at 156 MB
/// resident through `haptloop run` (measured; a 53 MB file of 3 M waypoints
/// reached 2.4 GB). A longer hand path belongs in a hand `trace` file, which
/// is read line by line.
pub const MAX_SCENE_BYTES: u64 = 4 << 20;

/// Reads, parses and validates the scene file at `path` (at most
/// [`MAX_SCENE_BYTES`]; a larger file, or a pipe or device that delivers
/// more, is refused with its size).
pub fn load(path: &Path) -> Result<LoadedScene, SceneError> {
    let file = path.display().to_string();
    let text = read_limited(path, MAX_SCENE_BYTES)
        .map_err(|e| SceneError::whole_file(&file, format!("cannot read the scene file: {e}")))?;
    parse(&file, &text, path.parent())
}

/// The text of `path`, refused past `limit` bytes: a regular file by its
/// size before reading, anything else (a pipe, `/dev/zero`) when the read
/// reaches one byte past the limit.
fn read_limited(path: &Path, limit: u64) -> std::io::Result<String> {
    use std::io::Read;
    let too_large = |size: String| {
        std::io::Error::other(format!(
            "{size}; a scene file may be at most {} MiB",
            limit >> 20
        ))
    };
    let file = std::fs::File::open(path)?;
    let meta = file.metadata()?;
    if meta.is_dir() {
        return Err(std::io::Error::other("it is a directory"));
    }
    if meta.is_file() && meta.len() > limit {
        return Err(too_large(format!(
            "it is {:.1} MB ({} bytes)",
            meta.len() as f64 / 1e6,
            meta.len()
        )));
    }
    let mut bytes = Vec::new();
    file.take(limit + 1).read_to_end(&mut bytes)?;
    if bytes.len() as u64 > limit {
        return Err(too_large(format!("it holds more than {} MiB", limit >> 20)));
    }
    String::from_utf8(bytes)
        .map_err(|e| std::io::Error::other(format!("it is not UTF-8 text ({e})")))
}
