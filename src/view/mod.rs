//! The viewer: a 3-D picture of every run, replayed or live.
//!
//! | file | what it does |
//! |---|---|
//! | [`scene`] | `scene.json`: bodies (shapes, or links through joint anchors), fingers, devices |
//! | [`files`] | the run files the viewer reads, and the check that a folder has them |
//! | [`data`] | a run folder → the page's data (poses, fingers, contacts, plots, events) |
//! | [`html`] | the self-contained `view.html` (assets in `src/view/assets/`, three.js vendored) |
//! | [`live`] | `run --live`: the page and a WebSocket on 127.0.0.1, fed from the slow loop |
//!
//! Nothing here is reachable from the fast loop: a live session's frames
//! come through mailboxes the slow loop and the reporter write
//! (`session::live`).

pub mod data;
pub mod files;
pub mod html;
pub mod live;
pub mod scene;

pub use data::PageData;
pub use scene::SceneInfo;

use anyhow::{Context, Result};
use std::path::{Path, PathBuf};

/// Reads the run folder `dir` and writes `dir/view.html` (whole or not at
/// all, through `write`); returns its path.
pub fn write_page(dir: &Path, write: impl FnOnce(&Path, &[u8]) -> Result<()>) -> Result<PathBuf> {
    let data = PageData::read(dir)?;
    let page = html::page(&data)?;
    let path = dir.join("view.html");
    write(&path, page.as_bytes()).with_context(|| format!("writing {}", path.display()))?;
    Ok(path)
}
