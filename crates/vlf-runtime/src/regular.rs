//! Reading the files a user names (fields, meshes, rays, scene files, shards): only regular files,
//! and never more bytes than asked for. One rule for every crate of the pipeline.
//!
//! A path that is not a regular file is refused by what it is, before it is opened: reading a
//! device such as `/dev/zero` never ends (it fills memory), opening a pipe waits for a writer,
//! forever if none comes, and a directory has no bytes. The opened file is checked again, in case
//! the path was replaced in between.

use std::fs::{File, Metadata};
use std::io::{self, Read};
use std::path::Path;

/// Why a path cannot be read: it is not a regular file. Carried inside the [`io::Error`] that
/// [`check_regular_file`], [`open_regular_file`] and [`read_regular_file`] return; its text is "it
/// is a directory, not a regular file", "it is a pipe (FIFO), not a regular file", and so on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct NotARegularFile {
    /// What the path is: "a directory", "a pipe (FIFO)", "a character device", "a block
    /// device", "a socket", or "something else".
    pub what: &'static str,
}

impl std::fmt::Display for NotARegularFile {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "it is {}, not a regular file", self.what)
    }
}

impl std::error::Error for NotARegularFile {}

impl NotARegularFile {
    /// The [`NotARegularFile`] inside `e`, if that is why `e` happened.
    pub fn of(e: &io::Error) -> Option<&NotARegularFile> {
        e.get_ref().and_then(|inner| inner.downcast_ref::<NotARegularFile>())
    }
}

/// What a file that is not a regular file is, in words.
fn what_it_is(meta: &Metadata) -> &'static str {
    let t = meta.file_type();
    if t.is_dir() {
        return "a directory";
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if t.is_fifo() {
            return "a pipe (FIFO)";
        }
        if t.is_char_device() {
            return "a character device";
        }
        if t.is_block_device() {
            return "a block device";
        }
        if t.is_socket() {
            return "a socket";
        }
    }
    "something else"
}

/// `Ok` if `meta` (of a path, symbolic links followed) is a regular file's; else an error of kind
/// [`io::ErrorKind::IsADirectory`] or [`io::ErrorKind::InvalidInput`] holding a
/// [`NotARegularFile`].
pub fn check_regular_file(meta: &Metadata) -> io::Result<()> {
    if meta.is_file() {
        return Ok(());
    }
    let kind = if meta.is_dir() { io::ErrorKind::IsADirectory } else { io::ErrorKind::InvalidInput };
    Err(io::Error::new(kind, NotARegularFile { what: what_it_is(meta) }))
}

/// Opens the regular file at `path` for reading, and returns it with its metadata. Anything else
/// is refused before it is opened (and the opened file is checked again), with a
/// [`NotARegularFile`] error.
pub fn open_regular_file(path: &Path) -> io::Result<(File, Metadata)> {
    check_regular_file(&std::fs::metadata(path)?)?;
    let file = File::open(path)?;
    let meta = file.metadata()?;
    check_regular_file(&meta)?;
    Ok((file, meta))
}

/// Reads at most `limit` bytes of the regular file at `path` ([`open_regular_file`]). The buffer
/// is reserved before reading: a file larger than memory is an error of kind
/// [`io::ErrorKind::OutOfMemory`], not an abort.
pub fn read_regular_file(path: &Path, limit: u64) -> io::Result<Vec<u8>> {
    let (file, meta) = open_regular_file(path)?;
    let mut bytes = Vec::new();
    let expected = usize::try_from(meta.len().min(limit)).unwrap_or(usize::MAX);
    bytes.try_reserve_exact(expected).map_err(|_| {
        io::Error::new(io::ErrorKind::OutOfMemory, format!("cannot allocate {} bytes to read it", meta.len()))
    })?;
    file.take(limit).read_to_end(&mut bytes)?;
    Ok(bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_regular_files_are_read() {
        let dir = std::env::temp_dir();
        let e = read_regular_file(&dir, 10).unwrap_err();
        assert_eq!(e.kind(), io::ErrorKind::IsADirectory);
        assert_eq!(e.to_string(), "it is a directory, not a regular file");
        assert_eq!(NotARegularFile::of(&e), Some(&NotARegularFile { what: "a directory" }));
        #[cfg(unix)]
        {
            let e = read_regular_file(Path::new("/dev/zero"), 10).unwrap_err();
            assert_eq!(
                (e.kind(), e.to_string()),
                (io::ErrorKind::InvalidInput, "it is a character device, not a regular file".into())
            );
        }
        let path = dir.join(format!("vlf-regular-{}.bin", std::process::id()));
        std::fs::write(&path, b"0123456789").unwrap();
        assert_eq!(read_regular_file(&path, 4).unwrap(), b"0123");
        assert_eq!(read_regular_file(&path, u64::MAX).unwrap(), b"0123456789");
        std::fs::remove_file(&path).unwrap();
        assert_eq!(read_regular_file(&path, 4).unwrap_err().kind(), io::ErrorKind::NotFound);
    }
}
