//! The probe's text report.

use haptloop_rt::probe::{Percentiles, ProbeConfig, ProbeReport};
use haptloop_rt::thread::Granted;
use std::fmt::Write as _;

/// The line printed before the probe starts.
pub fn banner(c: &ProbeConfig) -> String {
    format!(
        "haptloop probe: {} Hz, {:.1} s scheduler + {:.1} s bare reference in 1 s blocks, \
         spin {} µs, synthetic load {} µs per tick",
        c.rate_hz,
        c.duration.as_secs_f64(),
        c.duration.as_secs_f64(),
        c.spin.as_micros(),
        c.load.as_micros()
    )
}

/// What the OS granted, in one line, plus one line per refusal.
pub fn granted_lines(g: &Granted) -> String {
    let mut s = format!(
        "granted: core {}, {}, mlockall {}, timer slack {}, stack prefaulted {} KiB",
        g.core.map_or("unpinned".to_string(), |c| c.to_string()),
        g.priority
            .map_or("SCHED_OTHER".to_string(), |p| format!("SCHED_FIFO {p}")),
        if g.mlock { "yes" } else { "no" },
        g.timer_slack_ns
            .map_or("?".to_string(), |n| format!("{n} ns")),
        g.stack_prefaulted / 1024
    );
    for r in &g.refusals {
        let _ = write!(s, "\nrefused: {r}");
    }
    s
}

fn row(out: &mut String, label: &str, ticks: u64, missed: Option<u64>, p: &Percentiles) {
    let us = |ns: u64| ns as f64 / 1e3;
    let missed = missed.map_or("-".to_string(), |m| m.to_string());
    let _ = writeln!(
        out,
        "  {label:<20} {ticks:>9} {missed:>7} {:>9.1} {:>9.1} {:>9.1} {:>9.1} {:>10.1}",
        us(p.p50),
        us(p.p99),
        us(p.p999),
        us(p.p9999),
        us(p.max)
    );
}

/// The full probe report.
pub fn render(r: &ProbeReport) -> String {
    let mut out = String::new();
    let _ = writeln!(out, "{}", granted_lines(&r.granted));
    let _ = writeln!(
        out,
        "\n  {:<20} {:>9} {:>7} {:>9} {:>9} {:>9} {:>9} {:>10}   (µs)",
        "", "ticks", "missed", "p50", "p99", "p99.9", "p99.99", "max"
    );
    row(
        &mut out,
        "lateness scheduler",
        r.ticks,
        Some(r.missed),
        &r.lateness_ns,
    );
    row(
        &mut out,
        "lateness reference",
        r.reference.ticks,
        Some(r.reference.missed),
        &r.reference.lateness_ns,
    );
    row(&mut out, "compute", r.ticks, None, &r.compute_ns);
    row(
        &mut out,
        "period",
        r.ticks.saturating_sub(1),
        None,
        &r.period_ns,
    );
    let _ = writeln!(
        out,
        "\nmisses: {} late, {} overrun, {} skipped slots (of {} slots at {} Hz over {:.1} s)",
        r.misses.late,
        r.misses.overrun,
        r.misses.skipped,
        r.ticks + r.misses.skipped,
        r.rate_hz,
        r.seconds
    );
    match r.ratio_p999 {
        Some(x) => {
            let _ = writeln!(out, "lateness p99.9 scheduler / reference: {x:.2}");
        }
        None => {
            let _ = writeln!(
                out,
                "lateness p99.9 scheduler / reference: n/a (reference p99.9 is 0)"
            );
        }
    }
    let _ = write!(
        out,
        "probe thread: {} minor / {} major page faults, {} voluntary / {} involuntary context switches",
        r.usage.minor_faults,
        r.usage.major_faults,
        r.usage.voluntary_switches,
        r.usage.involuntary_switches
    );
    out
}
