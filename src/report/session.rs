//! The end-of-session text report.

use super::probe::granted_lines;
use super::summary::Summary;
use super::units;
use crate::session::Stage;
use haptloop_rt::probe::Percentiles;
use std::fmt::Write as _;

fn row(out: &mut String, label: &str, p: &Percentiles) {
    let us = |ns: u64| ns as f64 / 1e3;
    let _ = writeln!(
        out,
        "  {label:<16} {:>9.1} {:>9.1} {:>9.1} {:>9.1} {:>10.1}",
        us(p.p50),
        us(p.p99),
        us(p.p999),
        us(p.p9999),
        us(p.max)
    );
}

/// The report printed when a session ends; `fingers` lists (finger name,
/// device model) in model order.
pub fn render(s: &Summary, fingers: &[(String, String)]) -> String {
    let mut out = String::new();
    header_lines(&mut out, s);
    timing_table(&mut out, s);
    accuracy_lines(&mut out, s, fingers);
    design_lines(&mut out, s);
    safety_lines(&mut out, s);
    if let Some(c) = &s.contact {
        contact_lines(&mut out, c);
    }
    if let Some(sem) = &s.semantic {
        super::semantic::lines(&mut out, sem);
    }
    reference_line(&mut out, s);
    let _ = write!(
        out,
        "slow loop: {} re-projections ({} recoveries, {} not converged); programs swapped in: {}; \
         trace samples dropped: {}; wall clock {:.2} s",
        s.slow_loop.reprojections,
        s.slow_loop.recoveries,
        s.slow_loop.placements_not_converged,
        s.programs_swapped,
        s.trace_dropped,
        s.wall_clock_s
    );
    out
}

/// The run line, the device grant and the assembly.
fn header_lines(out: &mut String, s: &Summary) {
    let mode = if s.deterministic {
        "deterministic (mock clock)"
    } else {
        "real time"
    };
    let _ = writeln!(
        out,
        "haptloop run {}: {:.1} s at {} Hz, {mode}, {} AL iteration{} per tick{}",
        s.scene,
        s.seconds,
        s.rate_hz,
        s.iterations,
        if s.iterations == 1 { "" } else { "s" },
        if s.stopped_early {
            " — stopped early"
        } else {
            ""
        }
    );
    if !s.coordinates.is_empty() {
        let _ = writeln!(
            out,
            "fast-loop coordinates: {}; joint ticks run as augmented ticks: {}",
            s.coordinates, s.joint_fallbacks
        );
    }
    if let Some(g) = &s.granted {
        let _ = writeln!(out, "{}", granted_lines(g));
    }
    match &s.assembly {
        Some(a) => {
            let _ = writeln!(
                out,
                "assembly (Newton-KKT placement): {} after {} iteration{}, residual {:.2e} m",
                a.status,
                a.iterations,
                if a.iterations == 1 { "" } else { "s" },
                a.residual_m
            );
        }
        None => {
            let _ = writeln!(
                out,
                "assembly: skipped (--no-assembly): started from the file's configuration"
            );
        }
    }
}

/// The latency table: lateness, compute, read → write, the stages, and the
/// ticks and misses under it.
fn timing_table(out: &mut String, s: &Summary) {
    let _ = writeln!(
        out,
        "\n  {:<16} {:>9} {:>9} {:>9} {:>9} {:>10}   (µs)",
        "", "p50", "p99", "p99.9", "p99.99", "max"
    );
    if let Some(lateness) = &s.lateness_ns {
        row(out, "lateness", lateness);
    }
    row(out, "compute", &s.compute_ns);
    if let Some(r2w) = &s.read_to_write_ns {
        row(out, "read → write", r2w);
    }
    for stage in Stage::ALL {
        row(
            out,
            &format!("  {}", stage.label()),
            &s.stages_ns.get(stage),
        );
    }
    row(out, "tick w/o device", &s.stages_ns.tick_without_device);
    let _ = writeln!(out);
    let _ = writeln!(
        out,
        "ticks: {} of {} slots; misses: {} late, {} overrun, {} skipped",
        s.ticks,
        s.ticks + s.misses.skipped,
        s.misses.late,
        s.misses.overrun,
        s.misses.skipped
    );
    if let Some(line) = s.stalls.line() {
        let _ = writeln!(out, "{line}");
    }
}

/// Constraint violation, finger tracking and the force on each finger.
fn accuracy_lines(out: &mut String, s: &Summary, fingers: &[(String, String)]) {
    let v = &s.violation;
    if v.ticks_measured == 0 || v.rows == 0 {
        let _ = writeln!(out, "constraint violation: {}", v.verdict);
    } else {
        let tol = v.tolerance.map_or(String::new(), |t| {
            format!("scene tolerance {t:.0e} m on translational rows: ")
        });
        let _ = writeln!(
            out,
            "constraint violation: max {}, {}; RMS {} ({tol}{})",
            units::sci(v.max, "m"),
            units::sci(v.max_rad, "rad"),
            units::sci(v.rms, "m"),
            v.verdict
        );
    }
    if s.tracking_m.max.is_nan() {
        let why = if s.force_n.is_empty() {
            "none: the scene has no fingers"
        } else if s.ticks == 0 {
            "not measured (no tick ran)"
        } else {
            "not measured (no tick succeeded)"
        };
        let _ = writeln!(out, "finger tracking error: {why}");
    } else {
        let _ = writeln!(
            out,
            "finger tracking error: max {:.2} mm, RMS {:.2} mm",
            s.tracking_m.max * 1e3,
            s.tracking_m.rms * 1e3
        );
    }
    for (name, dev) in fingers {
        let Some(f) = s.force_n.get(name) else {
            continue;
        };
        let _ = writeln!(
            out,
            "force on {name} ({dev}): mean {:.3} N, max {:.3} N rendered (solver asked up to {:.3} N)",
            f.mean, f.max, f.commanded_max
        );
    }
}

/// Force cuts, failures, faults and device events; energy, warnings and the
/// replay's verdict.
fn safety_lines(out: &mut String, s: &Summary) {
    let kinds = if s.safety.failure_kinds.is_empty() {
        String::new()
    } else {
        let k: Vec<String> = s
            .safety
            .failure_kinds
            .iter()
            .map(|(k, n)| format!("{k} × {n}"))
            .collect();
        format!(" ({})", k.join(", "))
    };
    let _ = writeln!(
        out,
        "safety: {} force cuts by the session, {} miss streaks, {} solver failures{kinds}; faults: {}",
        s.safety.force_cuts, s.safety.miss_streaks, s.safety.solver_failures, s.faults
    );
    for e in &s.safety.device_events {
        let _ = writeln!(out, "  {}: {} × {}", e.device, e.event, e.count);
    }
    if let Some(e) = &s.energy {
        let _ = writeln!(out, "{}", e.line());
    }
    for w in &s.warnings {
        let _ = writeln!(out, "WARNING: {w}");
    }
    if let Some(r) = &s.replay {
        let _ = writeln!(out, "replay: {}", r.verdict);
    }
}

/// The contact block: penetration, active rows, programs, witness latency.
fn contact_lines(out: &mut String, c: &super::summary::Contact) {
    let _ = writeln!(
        out,
        "contact: max penetration {} (exact, per slow-loop snapshot: {}; witness rows, per tick: {}; \
         scene tolerance {}: {}); up to {} rows active, {} pairs tracked",
        units::mm(c.max_penetration_m),
        units::mm(c.max_penetration_exact_m),
        units::mm(c.max_penetration_rows_m),
        units::mm(c.tolerance_m),
        c.verdict,
        c.max_active,
        c.max_tracked_pairs
    );
    // Mean and max only over programs that were built (or reused).
    let timed = |n: u64, what: &str, mean: f64, max: f64| {
        if n == 0 {
            format!("none {what}")
        } else {
            format!("{n} {what}: mean {mean:.0} µs, max {max:.0} µs")
        }
    };
    let built = c.structure_changes - c.reused;
    let _ = writeln!(
        out,
        "  {} witness changes, {} tables, {} new programs ({}; {}), \
         {} backups, {} expansions, {} in-tick activations ({} ticks at the limit)",
        c.witness_changes,
        c.witness_tables,
        c.structure_changes,
        timed(built, "built", c.build_us_mean, c.build_us_max),
        timed(c.reused, "reused", c.reuse_us_mean, c.reuse_us_max),
        c.backups,
        c.expansions,
        c.activations,
        c.activation_limit_ticks
    );
    let latency = if c.updates == 0 {
        "no latency to measure".to_string()
    } else {
        format!(
            "latency mean {:.1} ticks, max {} ticks",
            c.latency_ticks_mean, c.latency_ticks_max
        )
    };
    let _ = writeln!(
        out,
        "  witness → fast loop: {} updates, {latency}; slow-loop contact cycle mean {}, max {}",
        c.updates,
        units::or_not_measured(c.cycle_us_mean, 0, "µs"),
        units::or_not_measured(c.cycle_us_max, 0, "µs")
    );
    let _ = writeln!(out, "  {}", speed_limit_line(c));
    if c.backups_held > 0 {
        let _ = writeln!(
            out,
            "  {} cycles held a penetration beyond the tolerance without a backup: \
             backups in a row did not clear it (held up to 10 × the tolerance at most)",
            c.backups_held
        );
    }
    if c.stale_stopped_ticks > 0 {
        let _ = writeln!(
            out,
            "  slow loop late: the witness rows were too old to move any body in {} ticks \
             (the most motion asked of rows since their snapshot: {:.1} ticks at the limit)",
            c.stale_stopped_ticks, c.max_witness_age_ticks
        );
    }
}

/// The fast loop's force against the converged reference.
fn reference_line(out: &mut String, s: &Summary) {
    let r = &s.reference;
    if let Some(why) = &r.missing {
        let _ = writeln!(out, "force error against the converged reference: {why}");
        return;
    }
    let skipped = if r.not_compared.is_empty() {
        String::new()
    } else {
        let k: Vec<String> = r
            .not_compared
            .iter()
            .map(|(k, n)| format!("{k} × {n}"))
            .collect();
        format!("; not compared: {}", k.join(", "))
    };
    let relative = if r.force_error_relative.max.is_finite() {
        format!(
            "{:.1e} and {:.1e} of the force",
            r.force_error_relative.max, r.force_error_relative.rms
        )
    } else {
        format!("the reference force is {:.2e} N", r.force_n.max)
    };
    let _ = writeln!(
        out,
        "force error against the converged reference ({} of {} sampled ticks, one in {}): \
         max {}, RMS {} ({relative}); configuration within {}{skipped}",
        r.compared,
        r.samples,
        r.every_ticks,
        units::sci(r.force_error_n.max, "N"),
        units::sci(r.force_error_n.rms, "N"),
        units::sci(r.configuration_error_m.max, "m"),
    );
}

/// How the design variables and objectives moved, one line each.
fn design_lines(out: &mut String, s: &Summary) {
    if !s.design.is_empty() {
        let _ = writeln!(out, "design variables (m): start → end [min, max]");
        for (name, d) in &s.design {
            let _ = writeln!(
                out,
                "  {name:<24} {:>10.5} → {:>10.5}  [{:.5}, {:.5}]",
                d.start, d.end, d.min, d.max
            );
        }
    }
    if !s.joint_torques.is_empty() {
        let _ = writeln!(
            out,
            "joint torques (N·m; N on a slider), a motor's on each axis: start → end [min, max]"
        );
        for (name, d) in &s.joint_torques {
            let _ = writeln!(
                out,
                "  {name:<24} {:>10.4} → {:>10.4}  [{:.4}, {:.4}]",
                d.start, d.end, d.min, d.max
            );
        }
    }
    if !s.objectives.is_empty() {
        let _ = writeln!(out, "objectives: start → end [min, max]");
        for (name, o) in &s.objectives {
            let v = &o.value;
            let _ = writeln!(
                out,
                "  {name:<24} {:>10.4e} → {:>10.4e}  [{:.4e}, {:.4e}]  ({}, weight {})",
                v.start, v.end, v.min, v.max, o.kind, o.weight
            );
        }
    }
}

/// The contact speed limit and what it cost: `contact_distance` per slow
/// cycle bounds every shaped body's motion, so a small contact distance
/// makes a fingertip lag its device, in free air too.
fn speed_limit_line(c: &super::summary::Contact) -> String {
    let head = format!(
        "contact speed limit {:.3} m/s (contact_distance per 5 ms slow-loop cycle)",
        c.speed_limit_m_per_s
    );
    if c.speed_limited_ticks == 0 {
        format!("{head}: never reached")
    } else {
        format!(
            "{head}: held a body back in {} ticks; the largest finger tracking error then {:.2} mm \
             (raise [solver] contact_distance for faster motion)",
            c.speed_limited_ticks,
            c.speed_limit_lag_max_m * 1e3
        )
    }
}
