//! Reports: the probe's and the session's text reports, `summary.json`, the
//! SVG plots, and the sweep's table and files.

pub mod figure;
pub mod limits;
pub mod plots;
pub mod probe;
pub mod scene_plot;
pub mod semantic;
pub mod session;
pub mod summary;
pub mod sweep;
pub mod units;
pub mod warnings;
