//! Real-time thread setup: pin to a core, lock memory, prefault the stack, set
//! timer slack, request `SCHED_FIFO` — and report what the OS actually granted.
//!
//! Nothing here fails when the OS refuses a request (no `CAP_SYS_NICE`, a
//! container without `mlock`, a core outside the cgroup): the refusal is
//! recorded in [`Granted`] with its errno, and the loop runs anyway. Callers
//! print `Granted` so a user always knows what their latency figures were
//! measured under.
//!
//! The core list is taken in the *calling* thread before anything is pinned:
//! `core_affinity::get_core_ids()` returns the calling thread's current affinity
//! mask, so a list taken on an already-pinned thread would contain only its core.

use serde::{Deserialize, Serialize};
use std::thread::JoinHandle;

/// Which core the fast thread is pinned to.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum CoreChoice {
    /// The last core the process may use (default: core 0 usually takes the
    /// most interrupts and housekeeping).
    #[default]
    Last,
    /// A specific OS logical CPU number.
    Id(usize),
    /// Do not pin.
    Unpinned,
}

/// What to request for a real-time thread. Defaults: the last core this
/// process may use, `SCHED_FIFO` 80, `mlockall`, timer slack 0, a prefaulted
/// stack: the usual practice for a PREEMPT_RT control loop.
#[derive(Debug, Clone)]
pub struct ThreadConfig {
    /// Thread name (shown by `top -H`, `ps -L`).
    pub name: String,
    /// Core to pin to.
    pub core: CoreChoice,
    /// `SCHED_FIFO` priority 1–99, or `None` to stay `SCHED_OTHER`. Default 80:
    /// below the kernel's FIFO-99 `migration/N` threads, like cyclictest's `-p 80`.
    pub fifo_priority: Option<u8>,
    /// `mlockall(MCL_CURRENT | MCL_FUTURE)`: no page faults from swapped or
    /// lazily mapped memory inside the loop. Process-wide. Default true.
    pub lock_memory: bool,
    /// Stack size of the spawned thread, bytes. Default 2 MiB.
    pub stack_bytes: usize,
    /// Bytes of stack to touch before the loop starts so its pages are
    /// resident (rounded up to 64 KiB; clamped to half the stack). Default 256 KiB.
    pub prefault_stack_bytes: usize,
    /// Timer slack in ns (`PR_SET_TIMERSLACK`). Default 1: the kernel default of
    /// 50 µs shifts `SCHED_OTHER` wake-ups by that much; `SCHED_FIFO` ignores it.
    pub timer_slack_ns: Option<u64>,
}

impl Default for ThreadConfig {
    fn default() -> Self {
        ThreadConfig {
            name: "haptloop-fast".into(),
            core: CoreChoice::Last,
            fifo_priority: Some(80),
            lock_memory: true,
            stack_bytes: 2 << 20,
            prefault_stack_bytes: 256 << 10,
            timer_slack_ns: Some(1),
        }
    }
}

/// What the OS granted, read back after each request.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Granted {
    /// The core the thread is pinned to, if pinning succeeded.
    pub core: Option<usize>,
    /// True if the thread runs under `SCHED_FIFO` (read back, not assumed).
    pub fifo: bool,
    /// The `SCHED_FIFO` priority read back, if `fifo`.
    pub priority: Option<i32>,
    /// True if `mlockall` succeeded.
    pub mlock: bool,
    /// Timer slack read back with `PR_GET_TIMERSLACK` (the kernel reports 0
    /// for real-time threads, which ignore slack).
    pub timer_slack_ns: Option<u64>,
    /// Bytes of stack touched before the loop.
    pub stack_prefaulted: usize,
    /// One line per refused request, with the OS error.
    pub refusals: Vec<String>,
}

/// Why a real-time thread could not be started.
#[derive(Debug, thiserror::Error)]
pub enum SpawnError {
    /// The requested core is not one this process may run on.
    #[error("core {requested} is not available to this process (available: {available:?})")]
    CoreUnavailable {
        /// The core asked for.
        requested: usize,
        /// The cores the calling thread may use.
        available: Vec<usize>,
    },
    /// The OS could not create the thread.
    #[error("could not spawn thread `{name}`: {source}")]
    Spawn {
        /// Thread name.
        name: String,
        /// The OS error.
        source: std::io::Error,
    },
    /// The thread died during setup before reporting what it was granted.
    #[error("thread `{name}` exited during setup")]
    DiedDuringSetup {
        /// Thread name.
        name: String,
    },
}

/// A running real-time thread and what it was granted.
#[derive(Debug)]
pub struct RtThread<R> {
    /// What the OS granted the thread.
    pub granted: Granted,
    handle: JoinHandle<R>,
}

impl<R> RtThread<R> {
    /// True once the thread's function has returned (never blocks).
    pub fn is_finished(&self) -> bool {
        self.handle.is_finished()
    }

    /// Waits for the thread's function to return.
    pub fn join(self) -> std::thread::Result<R> {
        self.handle.join()
    }
}

/// The cores the *calling* thread may run on. Call before pinning anything.
pub fn available_cores() -> Vec<usize> {
    core_affinity::get_core_ids()
        .unwrap_or_default()
        .into_iter()
        .map(|c| c.id)
        .collect()
}

fn resolve_core(choice: CoreChoice) -> Result<Option<usize>, SpawnError> {
    let available = available_cores();
    match choice {
        CoreChoice::Unpinned => Ok(None),
        CoreChoice::Last => Ok(available.last().copied()),
        CoreChoice::Id(id) if available.contains(&id) => Ok(Some(id)),
        CoreChoice::Id(id) => Err(SpawnError::CoreUnavailable {
            requested: id,
            available,
        }),
    }
}

/// Spawns a thread, applies `config` on it, waits until it reports what was
/// granted, then lets it run `f`. The core list is resolved here, in the
/// caller's thread.
pub fn spawn_rt<F, R>(config: ThreadConfig, f: F) -> Result<RtThread<R>, SpawnError>
where
    F: FnOnce(&Granted) -> R + Send + 'static,
    R: Send + 'static,
{
    let core = resolve_core(config.core)?;
    let (tx, rx) = crossbeam::channel::bounded::<Granted>(1);
    let name = config.name.clone();
    let handle = std::thread::Builder::new()
        .name(name.clone())
        .stack_size(config.stack_bytes)
        .spawn(move || {
            let granted = prepare_current(&config, core);
            let _ = tx.send(granted.clone());
            f(&granted)
        })
        .map_err(|source| SpawnError::Spawn {
            name: name.clone(),
            source,
        })?;
    let granted = rx
        .recv()
        .map_err(|_| SpawnError::DiedDuringSetup { name })?;
    Ok(RtThread { granted, handle })
}

fn errno_text() -> String {
    std::io::Error::last_os_error().to_string()
}

/// Applies `config` to the current thread (pinned to `core` if given) and
/// reports what was granted. Used by [`spawn_rt`]; public so a caller that owns
/// its thread can prepare it too.
pub fn prepare_current(config: &ThreadConfig, core: Option<usize>) -> Granted {
    let mut g = Granted::default();
    if let Some(id) = core {
        if core_affinity::set_for_current(core_affinity::CoreId { id }) {
            g.core = Some(id);
        } else {
            g.refusals.push(format!("pin to core {id}: refused"));
        }
    }
    if config.lock_memory {
        // SAFETY: plain syscall with constant flags.
        if unsafe { libc::mlockall(libc::MCL_CURRENT | libc::MCL_FUTURE) } == 0 {
            g.mlock = true;
        } else {
            g.refusals.push(format!("mlockall: {}", errno_text()));
        }
    }
    let chunks = config
        .prefault_stack_bytes
        .min(config.stack_bytes / 2)
        .div_ceil(PREFAULT_CHUNK);
    if chunks > 0 {
        prefault_stack(chunks);
        g.stack_prefaulted = chunks * PREFAULT_CHUNK;
    }
    if let Some(slack) = config.timer_slack_ns {
        // SAFETY: PR_SET_TIMERSLACK takes one integer argument.
        if unsafe { libc::prctl(libc::PR_SET_TIMERSLACK, slack as libc::c_ulong) } != 0 {
            g.refusals
                .push(format!("timer slack {slack} ns: {}", errno_text()));
        }
    }
    if let Some(prio) = config.fifo_priority {
        let param = libc::sched_param {
            sched_priority: i32::from(prio.clamp(1, 99)),
        };
        // SAFETY: `param` is a valid sched_param; pthread_self() is this thread.
        let rc =
            unsafe { libc::pthread_setschedparam(libc::pthread_self(), libc::SCHED_FIFO, &param) };
        if rc != 0 {
            g.refusals.push(format!(
                "SCHED_FIFO priority {prio}: {}",
                std::io::Error::from_raw_os_error(rc)
            ));
        }
    }
    let (policy, prio) = current_policy();
    g.fifo = policy == libc::SCHED_FIFO;
    g.priority = g.fifo.then_some(prio);
    // SAFETY: PR_GET_TIMERSLACK takes no argument and returns the slack.
    let slack = unsafe { libc::prctl(libc::PR_GET_TIMERSLACK) };
    g.timer_slack_ns = u64::try_from(slack).ok();
    g
}

fn current_policy() -> (i32, i32) {
    let mut policy = 0;
    let mut param = libc::sched_param { sched_priority: 0 };
    // SAFETY: both out-pointers are valid for writes.
    unsafe { libc::pthread_getschedparam(libc::pthread_self(), &mut policy, &mut param) };
    (policy, param.sched_priority)
}

const PREFAULT_CHUNK: usize = 64 << 10;

/// Touches `chunks` × 64 KiB of stack, one write per page, so those pages are
/// resident (and locked, after `mlockall`) before the loop needs them.
#[inline(never)]
fn prefault_stack(chunks: usize) {
    let mut buf = [0u8; PREFAULT_CHUNK];
    for i in (0..PREFAULT_CHUNK).step_by(4096) {
        // SAFETY: `i` is in bounds; a volatile write keeps the touch from being
        // optimised away.
        unsafe { std::ptr::write_volatile(buf.as_mut_ptr().add(i), 1) };
    }
    std::hint::black_box(&buf);
    if chunks > 1 {
        prefault_stack(chunks - 1);
    }
}

/// Per-thread resource usage (`getrusage(RUSAGE_THREAD)`): page faults and
/// context switches, to show the loop took no faults and one voluntary switch
/// per tick. A syscall: read it before and after a loop, never inside.
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct ThreadUsage {
    /// Minor page faults.
    pub minor_faults: u64,
    /// Major page faults.
    pub major_faults: u64,
    /// Voluntary context switches (sleeps).
    pub voluntary_switches: u64,
    /// Involuntary context switches (preemptions).
    pub involuntary_switches: u64,
}

impl ThreadUsage {
    /// The calling thread's usage so far.
    pub fn now() -> Self {
        // SAFETY: an all-zero rusage is a valid value of this plain C struct.
        let mut ru: libc::rusage = unsafe { std::mem::zeroed() };
        // SAFETY: `ru` is valid for writes; RUSAGE_THREAD is supported on Linux.
        unsafe { libc::getrusage(libc::RUSAGE_THREAD, &mut ru) };
        ThreadUsage {
            minor_faults: ru.ru_minflt as u64,
            major_faults: ru.ru_majflt as u64,
            voluntary_switches: ru.ru_nvcsw as u64,
            involuntary_switches: ru.ru_nivcsw as u64,
        }
    }

    /// Usage accumulated since `earlier`.
    pub fn since(self, earlier: ThreadUsage) -> ThreadUsage {
        ThreadUsage {
            minor_faults: self.minor_faults.saturating_sub(earlier.minor_faults),
            major_faults: self.major_faults.saturating_sub(earlier.major_faults),
            voluntary_switches: self
                .voluntary_switches
                .saturating_sub(earlier.voluntary_switches),
            involuntary_switches: self
                .involuntary_switches
                .saturating_sub(earlier.involuntary_switches),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unavailable_core_is_a_clear_error() {
        let cfg = ThreadConfig {
            core: CoreChoice::Id(4096),
            ..ThreadConfig::default()
        };
        let err = spawn_rt(cfg, |_| ()).unwrap_err();
        let text = err.to_string();
        assert!(text.contains("core 4096"), "{text}");
        assert!(text.contains("available"), "{text}");
    }

    #[test]
    fn refusals_are_reported_not_fatal() {
        // Ask for everything except FIFO (tests must not starve the harness);
        // whatever the OS grants, the thread runs and reports consistently.
        let cfg = ThreadConfig {
            fifo_priority: None,
            lock_memory: false,
            ..ThreadConfig::default()
        };
        let last = available_cores().last().copied();
        let t = spawn_rt(cfg, |g| g.core).unwrap();
        assert_eq!(t.granted.core, last);
        assert!(!t.granted.fifo);
        assert_eq!(t.granted.priority, None);
        assert_eq!(t.granted.stack_prefaulted, 256 << 10);
        assert_eq!(t.granted.timer_slack_ns, Some(1));
        assert_eq!(t.join().unwrap(), last);
    }

    #[test]
    fn usage_counts_voluntary_switches() {
        let before = ThreadUsage::now();
        std::thread::sleep(std::time::Duration::from_millis(1));
        let d = ThreadUsage::now().since(before);
        assert!(d.voluntary_switches >= 1, "{d:?}");
    }
}
