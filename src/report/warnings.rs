//! The warnings of a session's report: forces the user was meant to feel
//! and the device could not render (its workspace stops, the peak-force
//! clamp, the motors' saturation, the thermal cut), and a replay that did
//! not reproduce its recording. Each names the device, how often, and what
//! to change.

use crate::session::SessionOutcome;

/// The warnings of `o`, in device order (empty when there is none).
pub fn of(o: &SessionOutcome) -> Vec<String> {
    let share = |n: u64| format!("{n} of {} ticks", o.stats.ticks.max(n));
    let mut out = Vec::new();
    for d in &o.device_limits {
        let who = format!("device `{}` ({})", d.device, d.model);
        if d.outside_workspace > 0 {
            out.push(format!(
                "{who} sat at a workspace stop on {}: the hand's path leaves the arm's \
                 workspace, so the arm was held by its mechanical stop, not by the scene \
                 (`haptloop check` names the hand's path and the workspace; change the path or \
                 the device's `scale`)",
                share(d.outside_workspace)
            ));
        }
        if d.peak_clamp > 0 || d.motor_saturation > 0 {
            let n = d.peak_clamp.max(d.motor_saturation);
            out.push(format!(
                "{who} saturated on {}: the solver asked for more than the {} N peak force \
                 ({} ticks clamped by the safety layer, {} with a motor torque at its limit), \
                 so the user felt less than the scene's force",
                share(n),
                d.peak_force_n,
                d.peak_clamp,
                d.motor_saturation
            ));
        }
        if d.thermal_cut > 0 {
            out.push(format!(
                "{who} was cut by its thermal model on {}: the force was held to the {} N \
                 continuous rating, whatever the scene asked",
                share(d.thermal_cut),
                d.continuous_force_n
            ));
        }
        if let Some(r) = d.replay
            && r.diverged > 0
        {
            out.push(format!(
                "{who}: the replay sent a force that differs from the recording's on {} of {} \
                 ticks compared, first at t = {} s (up to {:.3e} N): the trace is not this \
                 session's recording (another scene's, an edited one, or other flags)",
                r.diverged,
                r.compared,
                r.first_divergence.map_or(f64::NAN, |t| t.as_secs_f64()),
                r.max_difference_n
            ));
        }
    }
    out
}
