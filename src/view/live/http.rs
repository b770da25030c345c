//! The viewer thread: accepts connections (the page, or a WebSocket),
//! sends frames, takes pointer moves. Polls; never blocks a loop.

use super::LiveStats;
use super::frame;
use crate::session::LiveSources;
use std::io::{ErrorKind, Read, Write};
use std::net::{TcpListener, TcpStream};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};
use tungstenite::{Message, WebSocket};

/// Frames at most this often: a display's rate.
const FRAME_EVERY: Duration = Duration::from_millis(16);
/// How long the thread sleeps between polls.
const POLL: Duration = Duration::from_millis(4);

/// Serves until `done`, then tells every viewer the session ended; sets
/// `connected` when the first viewer's WebSocket is open.
pub fn serve(
    listener: TcpListener,
    page: &str,
    mut sources: LiveSources,
    done: &AtomicBool,
    connected: &AtomicBool,
) -> LiveStats {
    let mut stats = LiveStats {
        pointer_moves: sources
            .pointers
            .iter()
            .map(|p| (p.device.clone(), 0))
            .collect(),
        ..LiveStats::default()
    };
    let mut viewers: Vec<WebSocket<TcpStream>> = Vec::new();
    let mut last = Instant::now();
    let mut events_sent = usize::MAX;
    loop {
        let finishing = done.load(Ordering::Acquire);
        while let Ok((stream, _)) = listener.accept() {
            if let Some(ws) = connect(stream, page, &mut stats) {
                viewers.push(ws);
                stats.viewers += 1;
                connected.store(true, Ordering::Release);
                events_sent = usize::MAX;
            }
        }
        for ws in &mut viewers {
            loop {
                match ws.read() {
                    Ok(Message::Text(t)) => match frame::apply(t.as_str(), &sources.pointers) {
                        Some(k) => stats.pointer_moves[k].1 += 1,
                        None => stats.bad_messages += 1,
                    },
                    Ok(_) => {}
                    Err(_) => break,
                }
            }
        }
        let fresh = sources.frames.refresh() | sources.fingers.refresh();
        if (fresh && last.elapsed() >= FRAME_EVERY) || finishing {
            last = Instant::now();
            let bodies = sources.frames.latest().clone();
            let fingers = sources.fingers.latest();
            let with_events = bodies.events.len() != events_sent;
            events_sent = bodies.events.len();
            let text = frame::encode(&bodies, fingers, with_events);
            viewers.retain_mut(|ws| send(ws, &text));
            stats.frames += 1;
        }
        if finishing {
            viewers.retain_mut(|ws| send(ws, r#"{"type":"end"}"#));
            for ws in &mut viewers {
                let _ = ws.close(None);
                let _ = ws.flush();
            }
            return stats;
        }
        std::thread::sleep(POLL);
    }
}

/// Sends (or queues) a text message; false when the viewer is gone.
fn send(ws: &mut WebSocket<TcpStream>, text: &str) -> bool {
    match ws.send(Message::text(text)) {
        Ok(()) => true,
        Err(tungstenite::Error::Io(e)) if e.kind() == ErrorKind::WouldBlock => true,
        Err(_) => false,
    }
}

/// Reads a new connection's request: `GET /ws` with an upgrade becomes a
/// viewer; `GET /` gets the page; anything else a 404. Never a panic.
fn connect(stream: TcpStream, page: &str, stats: &mut LiveStats) -> Option<WebSocket<TcpStream>> {
    stream.set_nonblocking(false).ok()?;
    stream.set_read_timeout(Some(Duration::from_secs(2))).ok()?;
    let mut buf = [0u8; 4096];
    let mut n = 0;
    // Peek until the request's headers are complete (the handshake reads
    // them again itself).
    for _ in 0..50 {
        n = stream.peek(&mut buf).ok()?;
        if n == 0 || buf[..n].windows(4).any(|w| w == b"\r\n\r\n") || n == buf.len() {
            break;
        }
        std::thread::sleep(Duration::from_millis(2));
    }
    let head = String::from_utf8_lossy(&buf[..n]).to_ascii_lowercase();
    let path = head.split_whitespace().nth(1).unwrap_or("").to_owned();
    if path == "/ws" && head.contains("upgrade: websocket") {
        let ws = tungstenite::accept(stream).ok()?;
        ws.get_ref().set_nonblocking(true).ok()?;
        return Some(ws);
    }
    let mut stream = stream;
    // Consume the request before answering.
    let _ = stream.read(&mut buf[..n.max(1)]);
    let reply = if path == "/" || path == "/index.html" || path == "/view.html" {
        stats.pages += 1;
        format!(
            "HTTP/1.1 200 OK\r\nContent-Type: text/html; charset=utf-8\r\nContent-Length: {}\r\nCache-Control: no-store\r\nConnection: close\r\n\r\n{page}",
            page.len()
        )
    } else {
        let body = "not found: the live view is at /";
        format!(
            "HTTP/1.1 404 Not Found\r\nContent-Type: text/plain\r\nContent-Length: {}\r\nConnection: close\r\n\r\n{body}",
            body.len()
        )
    };
    let _ = stream.write_all(reply.as_bytes());
    let _ = stream.flush();
    None
}
