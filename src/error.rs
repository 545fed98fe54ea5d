//! Typed errors. Every variant names what the user should change: the config key (with its
//! line and column when we can find it), the command-line flag, or the file.

use std::path::{Path, PathBuf};

/// Everything that can go wrong. All of them map to exit code 2 in the binary.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// The TOML text does not parse, or a key is unknown or has the wrong type.
    #[error("{path}:{line}:{column}: {message}")]
    Toml {
        path: String,
        line: usize,
        column: usize,
        message: String,
    },

    /// A value parsed but is not allowed.
    #[error("{location}`{key}` = {value} is not allowed: {allowed}")]
    Invalid {
        /// `file:line:column: ` or `file: ` or empty.
        location: String,
        key: String,
        value: String,
        allowed: String,
    },

    /// A command-line value that does not parse or is out of range.
    #[error("{flag} {value:?}: {message}")]
    Flag {
        flag: String,
        value: String,
        message: String,
    },

    #[error("cannot read {}: {source}", path.display())]
    Read { path: PathBuf, source: std::io::Error },

    #[error("cannot write {}: {source}", path.display())]
    Write { path: PathBuf, source: std::io::Error },

    /// A malformed row in a camera path file or another data file.
    #[error("{}:{line}: {message}", path.display())]
    DataFile {
        path: PathBuf,
        line: usize,
        message: String,
    },

    /// A value that would have been written as NaN or infinity. This is a bug guard: it
    /// should never fire, and if it does no output file is touched.
    #[error("internal error: {what} is not finite ({value}); no file was written")]
    NonFinite { what: String, value: f64 },

    /// Anything else, with a sentence that says what to do.
    #[error("{0}")]
    Other(String),
}

impl Error {
    pub fn read(path: &Path, source: std::io::Error) -> Self {
        Error::Read {
            path: path.to_path_buf(),
            source,
        }
    }

    pub fn write(path: &Path, source: std::io::Error) -> Self {
        Error::Write {
            path: path.to_path_buf(),
            source,
        }
    }

    pub fn flag(flag: &str, value: &str, message: impl Into<String>) -> Self {
        Error::Flag {
            flag: flag.to_string(),
            value: value.to_string(),
            message: message.into(),
        }
    }
}

pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Refuse to let a non-finite number reach an output file.
pub fn ensure_finite(what: &str, value: f64) -> Result<f64> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(Error::NonFinite {
            what: what.to_string(),
            value,
        })
    }
}
