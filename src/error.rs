//! One error type for the library: every variant renders as a single line that names what
//! went wrong and where (file and line, or file and element), so the CLI can print it as is.

use std::path::{Path, PathBuf};

#[derive(Debug, thiserror::Error)]
pub enum Error {
    #[error("{}: {source}", path.display())]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    /// A malformed input file: scene, model or shader. `at` is "line N", "element vertex #17"…
    #[error("{}: {at}: {message}", path.display())]
    Parse {
        path: PathBuf,
        at: String,
        message: String,
    },
    /// A well-formed input that asks for something impossible (NaN geometry, negative power…).
    #[error("{0}")]
    Invalid(String),
    /// What this device cannot do or hold: a binding, a dispatch or a loop budget past its
    /// limits. The input may be fine on another device; here a user can only ask for less.
    #[error("{0}")]
    DeviceLimit(String),
    #[error("{0}")]
    NoAdapter(String),
    #[error("GPU error: {0}")]
    Gpu(String),
    /// A broken invariant of lobelight itself, not of its input: a stage bound without a
    /// buffer it needs, a copy past a buffer's end. Nothing a user changes mends it.
    #[error("internal error (a bug in lobelight; please report it): {0}")]
    Internal(String),
}

pub type Result<T, E = Error> = std::result::Result<T, E>;

/// The most characters of a parse error's message, whose middle is cut past it.
pub const MESSAGE_CHARS: usize = 400;

/// `message` with its middle cut where it is longer than `MESSAGE_CHARS`, saying how much.
fn shortened(message: String) -> String {
    let count = message.chars().count();
    if count <= MESSAGE_CHARS {
        return message;
    }
    let (head, tail) = (MESSAGE_CHARS * 3 / 4, MESSAGE_CHARS / 8);
    let start: String = message.chars().take(head).collect();
    let end: String = message.chars().skip(count - tail).collect();
    format!("{start} … ({} characters cut) … {end}", count - head - tail)
}

impl Error {
    pub fn io(path: &Path, source: std::io::Error) -> Self {
        Error::Io {
            path: path.to_owned(),
            source,
        }
    }

    /// A malformed input at `at` of `path`; a message past `MESSAGE_CHARS` (a file's token
    /// echoed whole: a 50 MB line) keeps its start and end, its middle cut.
    pub fn parse(path: &Path, at: impl Into<String>, message: impl Into<String>) -> Self {
        Error::Parse {
            path: path.to_owned(),
            at: at.into(),
            message: shortened(message.into()),
        }
    }

    /// Reads the whole of `path`, refusing at once anything but a regular file (a device such
    /// as `/dev/zero` or a pipe would never end, a directory is no input).
    pub fn read_regular_file(path: &Path) -> Result<Vec<u8>, Error> {
        let meta = std::fs::metadata(path).map_err(|e| Error::io(path, e))?;
        if !meta.is_file() {
            return Err(Error::parse(
                path,
                "file type",
                "not a regular file (a directory, device or pipe)",
            ));
        }
        std::fs::read(path).map_err(|e| Error::io(path, e))
    }

    /// A broken internal invariant (`Error::Internal`).
    pub fn internal(message: impl Into<String>) -> Self {
        Error::Internal(message.into())
    }

    pub fn at_line(path: &Path, line: usize, message: impl Into<String>) -> Self {
        Self::parse(path, format!("line {line}"), message)
    }
}
