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

/// `Ok` if `meta` is a regular file's, the only kind a field can be mapped from; else why not.
pub(crate) fn regular_file(meta: &std::fs::Metadata) -> std::io::Result<()> {
    if meta.is_file() {
        return Ok(());
    }
    let (kind, what) = if meta.is_dir() {
        (std::io::ErrorKind::IsADirectory, "it is a directory")
    } else {
        (
            std::io::ErrorKind::InvalidInput,
            "it is not a regular file (a pipe, socket or device cannot be mapped: read it into memory instead)",
        )
    };
    Err(std::io::Error::new(kind, what))
}
