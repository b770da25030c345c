//! The files of a run's directory: summary.json, the histograms, the
//! plots, the view's data and page.

use super::super::output::{produce_atomic, write_atomic};
use crate::report::{plots, scene_plot, summary::Summary};
use crate::scenes::Scene;
use crate::session;
use crate::view::{self, SceneInfo};
use anyhow::Result;
use std::path::Path;

/// Writes the run's files into `dir` (summary.json only when aborting).
pub(super) fn write_files(
    dir: &Path,
    scene: &Scene,
    o: &session::SessionOutcome,
    summary: &Summary,
) -> Result<()> {
    let write = |name: &str, text: String| write_atomic(&dir.join(name), text.as_bytes());
    write(
        "summary.json",
        serde_json::to_string_pretty(summary)? + "\n",
    )?;
    if super::super::signals::aborting() {
        super::super::emit(&format!(
            "wrote {}/: summary.json, trace.csv (aborted: nothing else)",
            dir.display()
        ));
        return Ok(());
    }
    // On the mock clock (deterministic mode) there is no lateness and no
    // device-to-motor time to record: those files are not written, and
    // compute.hgrm holds the monotonic clock's whole tick instead.
    let timing_files = if o.plan.deterministic {
        write(
            "compute.hgrm",
            o.stats.stages.tick.percentile_distribution(1000.0),
        )?;
        "compute.hgrm (µs, monotonic clock)"
    } else {
        write(
            "lateness.hgrm",
            o.histograms.lateness.percentile_distribution(1000.0),
        )?;
        write(
            "compute.hgrm",
            o.histograms.compute.percentile_distribution(1000.0),
        )?;
        write(
            "read-to-write.hgrm",
            o.stats.read_to_write.percentile_distribution(1000.0),
        )?;
        "lateness.hgrm, compute.hgrm, read-to-write.hgrm (µs)"
    };
    produce_atomic(&dir.join("latency.svg"), |p| plots::latency(p, o))?;
    produce_atomic(&dir.join("force.svg"), |p| plots::force(p, o))?;
    let mut extra = String::new();
    // No empty plots: a scene without joint rows has no violation to draw.
    if o.joint_rows > 0 {
        produce_atomic(&dir.join("violation.svg"), |p| plots::violation(p, o))?;
        extra += ", violation.svg";
    }
    if o.track.bodies.iter().any(|b| b.shape.is_some()) {
        produce_atomic(&dir.join("contact.svg"), |p| {
            scene_plot::contact(p, &o.plan.scene, &o.track)
        })?;
        extra += ", contact.svg";
    }
    // Joint torques alone (the last columns) are not plotted.
    if o.recorder.design_names.len() > o.recorder.design_torques {
        produce_atomic(&dir.join("design.svg"), |p| plots::design(p, o))?;
        extra += ", design.svg";
    }
    for (name, text) in view::files::contents(&SceneInfo::of(scene), o)? {
        write(name, text)?;
    }
    view::write_page(dir, write_atomic)?;
    extra += ", scene.json, bodies.csv, fingers.csv, contacts.csv, view.html";
    super::super::emit(&format!(
        "wrote {}/: summary.json, trace.csv, {timing_files}, latency.svg, force.svg{extra}",
        dir.display()
    ));
    Ok(())
}
