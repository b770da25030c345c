//! What a live viewer may read while a session runs (`haptloop run
//! --live`), and nothing else: the slow loop's newest [`LiveFrame`] (built
//! from the fast loop's snapshot, off the fast thread), the reporter's
//! newest [`FingerFrame`] (from the trace samples it drains), and the
//! [`Pointer`] of each virtual device. Each frame goes through its own
//! lock-free mailbox (`rt::exchange::mailbox`): the viewer never blocks
//! either loop, and the fast loop's tick does not know it exists.

use super::semantic::Event;
use super::track::{FingerSample, TrackSample};
use haptloop_devices::{Mount, Pointer};
use haptloop_rt::exchange::{MailboxReader, MailboxWriter};
use std::sync::Arc;

/// The slow loop's newest picture of the mechanism.
#[derive(Debug, Clone, Default)]
pub struct LiveFrame {
    /// Session time of the snapshot it was built from, s.
    pub t_s: f64,
    /// Poses, contacts and violation, as [`super::BodyTrack`] keeps them.
    pub sample: TrackSample,
    /// Every semantic event so far.
    pub events: Vec<Event>,
}

/// The reporter's newest finger figures.
#[derive(Debug, Clone, Default)]
pub struct FingerFrame {
    /// Session time of the tick, s.
    pub t_s: f64,
    /// Every finger, model order.
    pub fingers: Vec<FingerSample>,
}

/// A virtual device's pointer and how its frame sits in the scene.
#[derive(Debug, Clone)]
pub struct LivePointer {
    /// Device name.
    pub device: String,
    /// What the page moves.
    pub pointer: Pointer,
    /// Device frame ↔ scene frame (registered).
    pub mount: Mount,
}

/// The viewer's ends of the live exchange.
pub struct LiveSources {
    /// Frames from the slow loop.
    pub frames: MailboxReader<LiveFrame>,
    /// Finger figures from the reporter.
    pub fingers: MailboxReader<FingerFrame>,
    /// One per virtual device.
    pub pointers: Vec<LivePointer>,
}

/// The session's ends of the live exchange.
pub(super) struct LiveSinks {
    pub frames: MailboxWriter<LiveFrame>,
    pub fingers: MailboxWriter<FingerFrame>,
}

/// Called once when a live session's loops are about to start, with the
/// viewer's ends of the exchange (it starts the viewer's thread).
#[derive(Clone)]
pub struct LiveHook(pub Arc<dyn Fn(LiveSources) + Send + Sync>);

impl std::fmt::Debug for LiveHook {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("LiveHook")
    }
}

/// A connected pair of ends.
pub(super) fn exchange(pointers: Vec<LivePointer>) -> (LiveSinks, LiveSources) {
    let (frames_tx, frames_rx) = haptloop_rt::exchange::mailbox(LiveFrame::default);
    let (fingers_tx, fingers_rx) = haptloop_rt::exchange::mailbox(FingerFrame::default);
    (
        LiveSinks {
            frames: frames_tx,
            fingers: fingers_tx,
        },
        LiveSources {
            frames: frames_rx,
            fingers: fingers_rx,
            pointers,
        },
    )
}
