//! Set-up time errors of the crate (construction, configuration, files).
//! Fast-path problems are `Copy` values instead: [`crate::DeviceFault`],
//! [`crate::FaultKind`].

use std::path::PathBuf;

/// Building or configuring a device failed.
#[derive(Debug, thiserror::Error)]
pub enum DeviceError {
    /// The scene named a model this crate does not simulate.
    #[error("unknown device model `{name}`; known models: {known}")]
    UnknownModel {
        /// The name given.
        name: String,
        /// Comma-separated list of known names.
        known: String,
    },
    /// A configuration value is out of range.
    #[error("invalid {what}: {value} ({reason})")]
    InvalidConfig {
        /// Which field.
        what: &'static str,
        /// The offending value, printed.
        value: String,
        /// What was expected.
        reason: &'static str,
    },
    /// The fault schedule is full.
    #[error("fault schedule full ({capacity} faults); inject fewer")]
    FaultScheduleFull {
        /// Capacity of the schedule.
        capacity: usize,
    },
}

/// Reading or writing a trace file (device trace or hand trace) failed.
#[derive(Debug, thiserror::Error)]
pub enum TraceError {
    /// The file could not be read or written.
    #[error("{path}: cannot {action} it: {reason}", path = path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// `read` or `write`.
        action: &'static str,
        /// The operating system's reason. Said in the message, so it is not
        /// also a `source` (a chain would print it twice).
        reason: std::io::Error,
    },
    /// The file is larger than a trace of its kind may be.
    #[error("{path}: {size}; {what} may be at most {limit}", path = path.display())]
    TooLarge {
        /// The file.
        path: PathBuf,
        /// What kind of file (`a device trace`, `a hand trace`).
        what: &'static str,
        /// Its size as far as it is known (`is 53.0 MB (53 000 000 bytes)`,
        /// `holds more than 64 MiB`).
        size: String,
        /// The limit, in words.
        limit: String,
    },
    /// A line could not be parsed.
    #[error("{source_name}:{line}: {message}")]
    Parse {
        /// File name (or other label) of the text.
        source_name: String,
        /// 1-based line number.
        line: usize,
        /// What was wrong and what was expected.
        message: String,
    },
    /// Writing to an in-memory or other writer failed.
    #[error("writing trace: {0}")]
    Write(#[from] std::io::Error),
}

/// Characters of a quotation in a message, at most (escapes included).
const QUOTE_CHARS: usize = 60;

/// `text` as a message quotes it: at most [`QUOTE_CHARS`] characters as
/// printed (control characters escaped, `…` where it was clipped), so a
/// binary file never floods the terminal or sends it escape codes.
pub fn quote(text: &str) -> String {
    let mut out = String::new();
    for c in text.chars() {
        let shown: String = if c.is_control() {
            c.escape_default().collect()
        } else {
            c.to_string()
        };
        if out.chars().count() + shown.chars().count() > QUOTE_CHARS {
            out.push('…');
            break;
        }
        out.push_str(&shown);
    }
    out
}

/// A byte count in words: `53.0 MB (53 000 000 bytes)`.
pub fn size_in_words(bytes: u64) -> String {
    let digits = bytes.to_string();
    let mut grouped = String::new();
    for (i, c) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i).is_multiple_of(3) {
            grouped.push(' ');
        }
        grouped.push(c);
    }
    if bytes < 1_000_000 {
        format!("{grouped} bytes")
    } else {
        format!("{:.1} MB ({grouped} bytes)", bytes as f64 / 1e6)
    }
}

/// Opens `path` for a streaming read of at most `limit` bytes: a regular
/// file larger than that is refused at once with its size; anything else
/// (a pipe, `/dev/zero`) is read through a reader that stops one byte past
/// the limit, and [`check_not_truncated`] refuses it then.
pub(crate) fn open_limited(
    path: &std::path::Path,
    what: &'static str,
    limit: u64,
) -> Result<std::io::Take<std::io::BufReader<std::fs::File>>, TraceError> {
    use std::io::Read;
    let io = |reason| TraceError::Io {
        path: path.to_owned(),
        action: "read",
        reason,
    };
    let file = std::fs::File::open(path).map_err(io)?;
    let meta = file.metadata().map_err(io)?;
    if meta.is_dir() {
        return Err(io(std::io::Error::other("it is a directory")));
    }
    if meta.is_file() && meta.len() > limit {
        return Err(TraceError::TooLarge {
            path: path.to_owned(),
            what,
            size: format!("is {}", size_in_words(meta.len())),
            limit: limit_in_words(limit),
        });
    }
    Ok(std::io::BufReader::new(file).take(limit + 1))
}

/// Refuses a limited read that reached past its limit (see
/// [`open_limited`]): `remaining` is what its `Take` had left at the end.
pub(crate) fn check_not_truncated(
    path: &std::path::Path,
    what: &'static str,
    limit: u64,
    remaining: u64,
) -> Result<(), TraceError> {
    if remaining == 0 {
        return Err(TraceError::TooLarge {
            path: path.to_owned(),
            what,
            size: format!("holds more than {}", limit_in_words(limit)),
            limit: limit_in_words(limit),
        });
    }
    Ok(())
}

/// A limit in MiB (`64 MiB`).
fn limit_in_words(limit: u64) -> String {
    format!("{} MiB", limit >> 20)
}

/// Longest line a trace may have, bytes: a device-trace row is under 400.
pub const MAX_LINE_BYTES: usize = 4096;

/// Reads the next line (without its `\n` or `\r\n`) into `line`; `Ok(false)`
/// at the end. A line longer than [`MAX_LINE_BYTES`] (a binary file) or not
/// UTF-8 is an error naming the line, quoting its start only.
pub(crate) fn next_line(
    reader: &mut impl std::io::BufRead,
    bytes: &mut Vec<u8>,
    line: &mut String,
    source_name: &str,
    number: usize,
) -> Result<bool, TraceError> {
    bytes.clear();
    line.clear();
    let io = |reason| TraceError::Io {
        path: source_name.into(),
        action: "read",
        reason,
    };
    loop {
        let buf = reader.fill_buf().map_err(io)?;
        if buf.is_empty() {
            if bytes.is_empty() {
                return Ok(false);
            }
            break;
        }
        let (take, done) = match buf.iter().position(|&b| b == b'\n') {
            Some(i) => (i + 1, true),
            None => (buf.len(), false),
        };
        let room = MAX_LINE_BYTES + 2 - bytes.len();
        bytes.extend_from_slice(&buf[..take.min(room)]);
        reader.consume(take);
        if bytes.len() > MAX_LINE_BYTES + 1 {
            return Err(TraceError::parse(
                source_name,
                number,
                format!(
                    "the line is longer than {MAX_LINE_BYTES} bytes (not a trace file?): `{}`",
                    quote(&String::from_utf8_lossy(&bytes[..bytes.len().min(200)]))
                ),
            ));
        }
        if done {
            break;
        }
    }
    if bytes.last() == Some(&b'\n') {
        bytes.pop();
    }
    if bytes.last() == Some(&b'\r') {
        bytes.pop();
    }
    match std::str::from_utf8(bytes) {
        Ok(s) => line.push_str(s),
        Err(_) => {
            return Err(TraceError::parse(
                source_name,
                number,
                format!(
                    "not text (invalid UTF-8): `{}`",
                    quote(&String::from_utf8_lossy(bytes))
                ),
            ));
        }
    }
    Ok(true)
}

impl TraceError {
    /// An I/O error on `path` while doing `action` (`read`, `write`).
    pub(crate) fn io(path: &std::path::Path, action: &'static str, reason: std::io::Error) -> Self {
        Self::Io {
            path: path.to_owned(),
            action,
            reason,
        }
    }

    pub(crate) fn parse(source_name: &str, line: usize, message: impl Into<String>) -> Self {
        Self::Parse {
            source_name: source_name.to_owned(),
            line,
            message: message.into(),
        }
    }
}
