//! Reading input files (meshes, OBJ material libraries, external glTF buffers): only regular
//! files, and never more bytes than asked for, by the rule of [`vlf_runtime::regular`], which
//! every crate of the pipeline reads its inputs by (re-exported here for the importers' callers).
//!
//! Before a file is read whole, two checks, so that a multi-gigabyte file that is not a mesh is
//! refused at once instead of after reading all of it ([`read_checked`]): its first bytes
//! ([`PREFIX`] of them) are read and judged (a mesh's by its format: the GLB header and chunks,
//! the `{` of glTF JSON, OBJ text; a material library's as text), and then its size is compared
//! with the memory the process may use ([`memory::budget`]).

use crate::memory;
use crate::params::human_bytes;
use std::io::{self, Read};
use std::path::Path;

pub use vlf_runtime::regular::{NotARegularFile, check_regular_file, read_regular_file};

/// How the importers fetch a file a mesh refers to: its path, and the most bytes wanted of it.
pub(super) type ReadFile<'a> = dyn Fn(&Path, u64) -> io::Result<Vec<u8>> + 'a;

/// How [`super::import_bytes`]' callers and [`super::import_path`] fetch a file a mesh refers
/// to: its path, the most bytes wanted of it, and what its first bytes must look like.
pub(super) type Fetch<'a> = dyn Fn(&Path, u64, Expect) -> io::Result<Vec<u8>> + 'a;

/// How many first bytes of a file are read and judged before the rest: the 64 KiB the format of
/// a file of unknown extension is sniffed from, and one more to tell that the file goes on.
pub(super) const PREFIX: usize = 64 * 1024 + 1;

/// What the first bytes of a file a mesh refers to must look like.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Expect {
    /// Text (an OBJ material library): UTF-8 without NUL bytes.
    Text,
    /// Anything (an external glTF buffer).
    Bytes,
}

impl Expect {
    /// `Err` (of kind [`io::ErrorKind::InvalidData`]) if `prefix`, the first bytes of a file of
    /// `size` bytes, is not what is expected.
    pub(super) fn check(self, prefix: &[u8], size: u64) -> io::Result<()> {
        match self {
            Expect::Bytes => Ok(()),
            Expect::Text => match not_text(prefix, size) {
                None => Ok(()),
                Some(why) => Err(io::Error::new(io::ErrorKind::InvalidData, format!("its first bytes are {why}"))),
            },
        }
    }
}

/// Why `prefix`, the first bytes of a file of `size` bytes, is not text: "not UTF-8 text (invalid
/// byte on line 4)", "not text (a NUL byte on line 1)". A character cut by the end of a prefix
/// shorter than its file is not held against it.
pub(super) fn not_text(prefix: &[u8], size: u64) -> Option<String> {
    let line = |at: usize| 1 + prefix[..at].iter().filter(|&&b| b == b'\n').count();
    let valid = match std::str::from_utf8(prefix) {
        Ok(_) => prefix.len(),
        Err(e) if e.error_len().is_none() && (prefix.len() as u64) < size => e.valid_up_to(),
        Err(e) => return Some(format!("not UTF-8 text (invalid byte on line {})", line(e.valid_up_to()))),
    };
    let nul = prefix[..valid].iter().position(|&b| b == 0)?;
    Some(format!("not text (a NUL byte on line {})", line(nul)))
}

/// Why [`read_checked`] did not return a file's bytes: it could not be read (or is too large
/// for memory), or its first bytes were refused by the check it was given.
pub(super) enum Refused<E> {
    Read(io::Error),
    Check(E),
}

/// Reads at most `limit` bytes of the regular file at `path`, judging it before reading it
/// whole: `check` is given its first bytes (the whole file, or its first [`PREFIX`] bytes) and
/// its size; then the bytes to read are compared with [`memory::budget`], and more than it allows
/// are an error of kind [`io::ErrorKind::OutOfMemory`] naming the size and the budget.
pub(super) fn read_checked<E>(
    path: &Path,
    limit: u64,
    check: impl FnOnce(&[u8], u64) -> Result<(), E>,
) -> Result<Vec<u8>, Refused<E>> {
    let (file, meta) = vlf_runtime::regular::open_regular_file(path).map_err(Refused::Read)?;
    let size = meta.len().min(limit);
    // Never more than the size checked, should the file grow meanwhile.
    let mut file = file.take(size);
    let mut bytes = Vec::new();
    (&mut file).take(PREFIX as u64).read_to_end(&mut bytes).map_err(Refused::Read)?;
    check(&bytes, meta.len()).map_err(Refused::Check)?;
    let (budget, why) = memory::budget();
    if size > budget {
        return Err(Refused::Read(io::Error::new(
            io::ErrorKind::OutOfMemory,
            format!(
                "it is {} ({size} bytes), more than the {} of memory it may be read into ({why})",
                human_bytes(size),
                human_bytes(budget)
            ),
        )));
    }
    let rest = usize::try_from(size).unwrap_or(usize::MAX).saturating_sub(bytes.len());
    bytes.try_reserve_exact(rest).map_err(|_| {
        Refused::Read(io::Error::new(io::ErrorKind::OutOfMemory, format!("cannot allocate {size} bytes to read it")))
    })?;
    file.read_to_end(&mut bytes).map_err(Refused::Read)?;
    Ok(bytes)
}

/// Reads a file a mesh refers to by [`read_checked`], its first bytes judged by `expect`.
pub(super) fn read_referenced(path: &Path, limit: u64, expect: Expect) -> io::Result<Vec<u8>> {
    read_checked(path, limit, |prefix, size| expect.check(prefix, size)).map_err(|refused| match refused {
        Refused::Read(e) | Refused::Check(e) => e,
    })
}
