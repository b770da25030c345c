//! `haptloop run --live`: the viewer page and its WebSocket on
//! 127.0.0.1 (never another interface), on one thread of its own.
//!
//! ```text
//!  slow loop ──LiveFrame──► mailbox ─┐
//!  reporter ──FingerFrame─► mailbox ─┼─► viewer thread ──JSON frames, ≤ 60 a second──► page(s)
//!  virtual devices' Pointers ◄───────┘◄── {"type":"pointer","device","target"} ◄── mouse
//! ```
//!
//! The thread never blocks a loop: it polls the mailboxes (lock-free), and
//! a pointer move is one atomic store the device reads on its next tick.
//! `GET /` serves the page (the same `view.html` a run writes, with the
//! scene and no samples), `GET /ws` upgrades to the WebSocket (tungstenite).

mod frame;
mod http;

use super::data::PageData;
use super::scene::SceneInfo;
use crate::session::{LiveHook, LiveSources};
use anyhow::{Context, Result, bail};
use std::net::{SocketAddr, TcpListener};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;

/// What the viewer thread did.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct LiveStats {
    /// Page requests served.
    pub pages: u64,
    /// WebSocket viewers connected.
    pub viewers: u64,
    /// Frames sent (to all viewers).
    pub frames: u64,
    /// Pointer moves received, per virtual device: (name, count).
    pub pointer_moves: Vec<(String, u64)>,
    /// Messages from a page that were not understood (ignored).
    pub bad_messages: u64,
}

/// The live viewer (see the module docs).
pub struct LiveServer {
    addr: SocketAddr,
    listener: Arc<Mutex<Option<TcpListener>>>,
    done: Arc<AtomicBool>,
    connected: Arc<AtomicBool>,
    thread: Arc<Mutex<Option<JoinHandle<LiveStats>>>>,
}

impl LiveServer {
    /// Listens on 127.0.0.1:`port` (0: any free port). A port in use is an
    /// error that says so and what to do.
    pub fn bind(port: u16) -> Result<LiveServer> {
        let listener = match TcpListener::bind(("127.0.0.1", port)) {
            Ok(l) => l,
            Err(e) if e.kind() == std::io::ErrorKind::AddrInUse => bail!(
                "--port {port}: 127.0.0.1:{port} is already in use (another `haptloop run --live`?); pass another --port, or --port 0 for any free one"
            ),
            Err(e) => {
                return Err(e)
                    .with_context(|| format!("--port {port}: listening on 127.0.0.1:{port}"));
            }
        };
        let addr = listener.local_addr()?;
        listener.set_nonblocking(true)?;
        Ok(LiveServer {
            addr,
            listener: Arc::new(Mutex::new(Some(listener))),
            done: Arc::new(AtomicBool::new(false)),
            connected: Arc::new(AtomicBool::new(false)),
            thread: Arc::new(Mutex::new(None)),
        })
    }

    /// The page's address.
    pub fn url(&self) -> String {
        format!("http://{}/", self.addr)
    }

    /// The session's hook: starts the viewer thread with the page for
    /// `info` when the loops are about to start, and waits until a page
    /// has connected (the clock starts then; Ctrl-C quits while waiting).
    pub fn hook(&self, info: SceneInfo) -> Result<LiveHook> {
        let moving = (0..info.bodies.len())
            .filter(|&k| !info.bodies[k].fixed)
            .collect();
        let page = super::html::page(&PageData {
            scene: Some(info),
            live: true,
            moving,
            ..PageData::default()
        })?;
        let page = Arc::new(page);
        let (listener, done, thread) = (
            self.listener.clone(),
            self.done.clone(),
            self.thread.clone(),
        );
        let connected = self.connected.clone();
        Ok(LiveHook(Arc::new(move |sources: LiveSources| {
            let Some(l) = listener.lock().ok().and_then(|mut l| l.take()) else {
                return;
            };
            let (page, done, seen) = (page.clone(), done.clone(), connected.clone());
            let handle = std::thread::Builder::new()
                .name("haptloop-view".into())
                .spawn(move || http::serve(l, &page, sources, &done, &seen));
            let started = handle.is_ok();
            if let (Ok(h), Ok(mut slot)) = (handle, thread.lock()) {
                *slot = Some(h);
            }
            while started && !connected.load(Ordering::Acquire) {
                std::thread::sleep(std::time::Duration::from_millis(20));
            }
        })))
    }

    /// Tells the viewers the session ended, stops the thread and returns
    /// what it did.
    pub fn finish(self) -> LiveStats {
        self.done.store(true, Ordering::Release);
        let handle = self.thread.lock().ok().and_then(|mut t| t.take());
        handle.and_then(|h| h.join().ok()).unwrap_or_default()
    }
}
