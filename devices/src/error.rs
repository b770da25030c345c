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
    #[error("{path}: cannot read or write it")]
    Io {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        #[source]
        source: std::io::Error,
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

impl TraceError {
    /// Reads a whole trace file; an error names the file.
    pub(crate) fn read(path: &std::path::Path) -> Result<String, Self> {
        std::fs::read_to_string(path).map_err(|source| Self::Io {
            path: path.to_owned(),
            source,
        })
    }

    pub(crate) fn parse(source_name: &str, line: usize, message: impl Into<String>) -> Self {
        Self::Parse {
            source_name: source_name.to_owned(),
            line,
            message: message.into(),
        }
    }
}
