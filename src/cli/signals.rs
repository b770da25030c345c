//! Ctrl-C, SIGTERM and SIGHUP.
//!
//! * Before any session's loops have started (a big scene is still being
//!   built: no device has been driven), the first signal exits at once with
//!   status 130 and gives back the output directory it had claimed.
//! * Once a session has started, the first signal asks the fast loop to stop
//!   at its next tick boundary (motors off); the run then writes everything
//!   and exits with status 130.
//! * A second signal aborts: the command writes `summary.json` of what ran
//!   and nothing more, removes its lock and unfinished files and exits with
//!   status 130. If it has not done so within [`ABORT_GRACE`] (a loop that
//!   does not stop), the handler cleans the directory up itself and exits.

use super::output;
use haptloop_rt::schedule::StopFlag;
use std::sync::atomic::{AtomicBool, AtomicU32, Ordering};
use std::time::Duration;

/// How long a second signal waits for the command to write its summary and
/// exit on its own before the handler exits for it.
pub const ABORT_GRACE: Duration = Duration::from_secs(5);

/// Exit status of a command stopped by a signal (128 + SIGINT, whichever of
/// the three signals it was).
pub const EXIT_SIGNAL: u8 = 130;

static SIGNALS: AtomicU32 = AtomicU32::new(0);
static ABORTING: AtomicBool = AtomicBool::new(false);

/// True once a second signal asked to abort: write `summary.json` and stop.
pub fn aborting() -> bool {
    ABORTING.load(Ordering::Acquire)
}

/// Installs the handler; the flag it returns is the first signal's stop.
pub fn install() -> anyhow::Result<StopFlag> {
    let stop = StopFlag::new();
    let flag = stop.clone();
    ctrlc::set_handler(move || {
        let n = SIGNALS.fetch_add(1, Ordering::AcqRel) + 1;
        if !crate::session::started() {
            eprintln!("\nhaptloop: interrupted before the session started");
            output::abandon_claim();
            std::process::exit(i32::from(EXIT_SIGNAL));
        }
        if n == 1 {
            eprintln!(
                "\nhaptloop: stopping at the next tick boundary; what ran is still reported \
                 and written (signal again to abort: a run then writes summary.json only)"
            );
            flag.request();
            return;
        }
        if ABORTING.swap(true, Ordering::AcqRel) {
            return;
        }
        flag.request();
        eprintln!("\nhaptloop: aborting: writing summary.json of what ran, nothing else");
        // The command exits by itself once summary.json is written; a loop
        // that never stops must not keep the process alive.
        std::thread::sleep(ABORT_GRACE);
        eprintln!(
            "haptloop: the run did not stop within {} s; exiting without its files",
            ABORT_GRACE.as_secs()
        );
        output::abandon_claim();
        std::process::exit(i32::from(EXIT_SIGNAL));
    })?;
    Ok(stop)
}
