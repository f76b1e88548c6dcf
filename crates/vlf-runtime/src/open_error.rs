//! Why a field could not be opened.

use std::path::{Path, PathBuf};
use vlf_format::FormatError;

/// Why a field could not be opened. Each message is one self-contained line that includes the
/// underlying cause (so the cause is not repeated as a `source()`).
#[derive(Debug, thiserror::Error)]
pub enum OpenError {
    /// The file could not be opened, measured, read or mapped.
    #[error("cannot read field {path}: {error}")]
    Io {
        /// The path given to [`crate::Field::open`] or [`crate::Field::read`].
        path: PathBuf,
        /// What the operating system said.
        error: std::io::Error,
    },
    /// The file was read, but its bytes are not a valid field (or a packed one that does not
    /// decode).
    #[error("{path} is not a valid field: {error}")]
    Format {
        /// The path given to [`crate::Field::open`] or [`crate::Field::read`].
        path: PathBuf,
        /// The first fault found (one variant per fault, naming the section or header field).
        error: FormatError,
    },
    /// Bytes given to [`crate::Field::from_bytes`] are not a valid field.
    #[error("not a valid field: {0}")]
    Bytes(FormatError),
}

impl From<FormatError> for OpenError {
    fn from(e: FormatError) -> Self {
        OpenError::Bytes(e)
    }
}

impl OpenError {
    /// The error with the path of the file it is about.
    pub(crate) fn with_path(self, path: &Path) -> OpenError {
        match self {
            OpenError::Bytes(error) => OpenError::Format { path: path.to_owned(), error },
            other => other,
        }
    }
}

/// The error of opening a field at a path that is not a regular file, with what to do instead:
/// a pipe's or a device's bytes cannot be mapped, but can be read into memory and opened from
/// there. Other errors pass unchanged.
pub(crate) fn mappable(e: std::io::Error) -> std::io::Error {
    if crate::regular::NotARegularFile::of(&e).is_none() || e.kind() == std::io::ErrorKind::IsADirectory {
        return e;
    }
    std::io::Error::new(
        e.kind(),
        format!("{e}, which cannot be mapped: read its bytes into memory and open them with from_bytes"),
    )
}
