//! The package's exceptions, and the mapping from the runtime's and the baker's errors.

use pyo3::PyErr;
use pyo3::create_exception;
use pyo3::exceptions::{
    PyFileNotFoundError, PyIsADirectoryError, PyMemoryError, PyOSError, PyPermissionError, PyRuntimeError, PyValueError,
};
use std::io;
use vlf_runtime::{FormatError, OpenError};

create_exception!(
    vlf,
    FieldError,
    PyValueError,
    "The bytes are not a valid visibility field (damaged, truncated, or not a field at all), or a packed field is over the size limit."
);
create_exception!(
    vlf,
    BakeError,
    PyRuntimeError,
    "A bake failed: the mesh cannot be imported or the parameters cannot be met."
);

/// An I/O error as Python's own exception of its kind (`FileNotFoundError`, `PermissionError`,
/// `IsADirectoryError`, else `OSError`), with `message`.
pub fn io_error(kind: io::ErrorKind, message: String) -> PyErr {
    match kind {
        io::ErrorKind::NotFound => PyFileNotFoundError::new_err(message),
        io::ErrorKind::IsADirectory => PyIsADirectoryError::new_err(message),
        io::ErrorKind::PermissionDenied => PyPermissionError::new_err(message),
        _ => PyOSError::new_err(message),
    }
}

/// A failed open: a missing or unreadable file is an `OSError` of its kind, a bad field a
/// `FieldError`, memory a `MemoryError`.
pub fn open_error(e: OpenError) -> PyErr {
    match &e {
        OpenError::Io { error, .. } => io_error(error.kind(), e.to_string()),
        OpenError::Format { error: FormatError::OutOfMemory { .. }, .. }
        | OpenError::Bytes(FormatError::OutOfMemory { .. }) => PyMemoryError::new_err(e.to_string()),
        _ => FieldError::new_err(e.to_string()),
    }
}

/// A `ValueError` with `message`.
pub fn value_error(message: impl Into<String>) -> PyErr {
    PyValueError::new_err(message.into())
}
