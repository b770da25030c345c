//! Reports: the probe's and the session's text reports, `summary.json`, and
//! the SVG plots.

pub mod figure;
pub mod plots;
pub mod probe;
pub mod scene_plot;
pub mod semantic;
pub mod session;
pub mod summary;
