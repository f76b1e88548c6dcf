//! Atomic writes: every file this crate and the command line write (fields, packed fields,
//! shards, cache entries, reports, pictures, ray and hit files) goes to a locked temporary file
//! beside its path and is renamed over it, and the leftovers of killed writers are cleaned up.
//!
//! Every temporary file a live [`AtomicFile`] holds is listed in a process-wide registry, so that
//! a program interrupted by a signal can remove them all before it exits
//! ([`remove_live_temp_files`]; the command line's SIGINT and SIGTERM handler calls it).

use std::collections::BTreeSet;
use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::{Mutex, MutexGuard};
use std::time::Duration;

/// The temporary files of the live [`AtomicFile`]s of this process, and whether the process is
/// being interrupted (after which no temporary file is created or renamed into place).
struct Registry {
    live: BTreeSet<PathBuf>,
    interrupted: bool,
}

static REGISTRY: Mutex<Registry> = Mutex::new(Registry { live: BTreeSet::new(), interrupted: false });

/// The registry, whatever a thread that panicked while holding it left (a set of paths stays a
/// set of paths).
fn registry() -> MutexGuard<'static, Registry> {
    REGISTRY.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// The error of a write asked for, or committed, after [`remove_live_temp_files`] ran.
fn interrupted() -> io::Error {
    io::Error::new(io::ErrorKind::Interrupted, "interrupted: temporary files were removed")
}

/// Removes the temporary file of every live [`AtomicFile`] of this process and stops any from
/// being created or committed afterwards; returns the paths it removed. For a process that is
/// about to exit on a signal (the command line's SIGINT and SIGTERM handler), or on a failure it
/// cannot unwind from: the outputs keep their previous contents, and no temporary file is left
/// for a later write to clean up. A commit running at the same time either finishes its rename
/// first (its path then holds the new file, complete) or fails: never half of each.
///
/// Call it from an ordinary thread, not from a signal handler (it locks a mutex and allocates).
pub fn remove_live_temp_files() -> Vec<PathBuf> {
    let mut registry = registry();
    registry.interrupted = true;
    let live = std::mem::take(&mut registry.live);
    live.into_iter().filter(|path| std::fs::remove_file(path).is_ok()).collect()
}

/// The registration of one temporary file: removed from the registry when dropped.
struct Live(PathBuf);

impl Live {
    fn register(path: &Path) -> io::Result<Live> {
        let mut registry = registry();
        if registry.interrupted {
            return Err(interrupted());
        }
        registry.live.insert(path.to_path_buf());
        Ok(Live(path.to_path_buf()))
    }
}

impl Drop for Live {
    fn drop(&mut self) {
        registry().live.remove(&self.0);
    }
}

/// The directory that will hold `path`.
pub fn parent_dir(path: &Path) -> PathBuf {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

/// A file being written next to its final path: a temporary file `.NAME.XXXXXX.tmp` in the same
/// directory (`XXXXXX` six random letters and digits), renamed over the path by
/// [`AtomicFile::commit`] after it is flushed and synced, after which the directory is synced too.
/// Dropped without a commit (an error, a panic), it is removed.
///
/// A process killed while writing (`SIGKILL`, a crash, a power cut) leaves the path untouched and
/// the temporary file beside it. The writer holds an exclusive advisory lock (`flock`) on its
/// temporary file, which the kernel releases when the process dies, so a later write of the same
/// path can tell a leftover from a file being written: [`remove_stale_temp_files`] removes the
/// leftovers that nobody holds locked and that are older than [`STALE_TEMP_AGE`].
pub struct AtomicFile {
    tmp: tempfile::NamedTempFile,
    path: PathBuf,
    /// Listed in the registry from creation to the rename or the drop (declared after `tmp`, so a
    /// dropped file is removed before it leaves the registry).
    live: Live,
}

/// How old an unlocked temporary file must be before a later write of the same path removes it.
/// The lock decides; the age only covers the instant between a writer creating its temporary
/// file and locking it.
pub const STALE_TEMP_AGE: Duration = Duration::from_secs(60);

/// Length of the random part of a temporary file's name.
const TEMP_RANDOM_LEN: usize = 6;

/// The file type of an existing path that is not a regular file (a device, FIFO or socket), which
/// must be written in place, never replaced by a rename.
fn special_file(path: &Path) -> Option<std::fs::FileType> {
    std::fs::metadata(path).ok().map(|m| m.file_type()).filter(|t| !t.is_file() && !t.is_dir())
}

/// The prefix of the temporary files that write `path`: `.NAME.`.
fn temp_prefix(path: &Path) -> String {
    let name = path.file_name().map_or("field".into(), |n| n.to_string_lossy().into_owned());
    format!(".{name}.")
}

impl AtomicFile {
    /// Starts writing `path`, first removing stale temporary files that killed writers of the same
    /// path left behind. Refuses a path that exists and is not a regular file: a directory, or a
    /// device or FIFO (renaming over it would replace the device node, and a field needs
    /// positioned writes).
    pub fn create(path: &Path) -> io::Result<AtomicFile> {
        if special_file(path).is_some() {
            return Err(io::Error::new(
                io::ErrorKind::InvalidInput,
                format!("{} is not a regular file (a device or FIFO); write the field to a file path", path.display()),
            ));
        }
        if path.is_dir() {
            return Err(io::Error::new(
                io::ErrorKind::IsADirectory,
                "the path is a directory; give the path of a file, such as DIR/scene.vlf",
            ));
        }
        remove_stale_temp_files(path);
        let prefix = temp_prefix(path);
        let mut builder = tempfile::Builder::new();
        builder.prefix(&prefix).suffix(".tmp").rand_bytes(TEMP_RANDOM_LEN);
        // A new file's usual permissions (0666 less the umask), not tempfile's private 0600.
        #[cfg(unix)]
        builder.permissions(std::os::unix::fs::PermissionsExt::from_mode(0o666));
        if registry().interrupted {
            return Err(interrupted());
        }
        let tmp = builder.tempfile_in(parent_dir(path))?;
        // Marks the file as being written for as long as this process lives. Where the file
        // system has no locks, nothing is marked, and no leftover is ever removed as stale.
        try_lock(tmp.as_file());
        // Refused if an interruption came between the check above and now: `tmp` is removed.
        let live = Live::register(tmp.path())?;
        Ok(AtomicFile { tmp, path: path.to_path_buf(), live })
    }

    pub fn file(&self) -> &File {
        self.tmp.as_file()
    }

    /// The temporary file's path (in the destination directory), for checks before the commit.
    pub fn temp_path(&self) -> &Path {
        self.tmp.path()
    }

    /// Syncs the file and renames it over the path, then syncs the directory. Fails, leaving the
    /// path as it was, once [`remove_live_temp_files`] has run.
    pub fn commit(self) -> io::Result<()> {
        let AtomicFile { tmp, path, live } = self;
        tmp.as_file().sync_all()?;
        {
            // The rename and the registry change under one lock: an interruption sees either a
            // live temporary file (and removes it) or a renamed one (and leaves the path alone).
            let mut registry = registry();
            if registry.interrupted {
                return Err(interrupted());
            }
            tmp.persist(&path).map_err(|e| e.error)?;
            registry.live.remove(&live.0);
        }
        drop(live);
        // Makes the rename durable. Some file systems refuse to sync a directory; the rename has
        // happened either way.
        if let Ok(d) = File::open(parent_dir(&path)) {
            let _ = d.sync_all();
        }
        Ok(())
    }
}

/// Removes the temporary files (`.NAME.XXXXXX.tmp`, see [`AtomicFile`]) that writers of `path`
/// killed before they could clean up left in its directory: regular files that no process holds
/// locked and that were last modified at least [`STALE_TEMP_AGE`] ago. Returns how many it removed.
/// Never fails: a file it cannot inspect, lock or remove is left alone.
pub fn remove_stale_temp_files(path: &Path) -> usize {
    let prefix = temp_prefix(path);
    let Ok(entries) = std::fs::read_dir(parent_dir(path)) else { return 0 };
    let mut removed = 0;
    for entry in entries.flatten() {
        let name = entry.file_name();
        let Some(random) = name.to_str().and_then(|n| n.strip_prefix(&prefix)?.strip_suffix(".tmp")) else {
            continue;
        };
        if random.len() == TEMP_RANDOM_LEN
            && random.bytes().all(|b| b.is_ascii_alphanumeric())
            && remove_if_stale(&entry.path()).unwrap_or(false)
        {
            removed += 1;
        }
    }
    removed
}

/// Takes an exclusive advisory lock (`flock`) on `file` without waiting, held until every handle
/// of this open file is closed (or the process dies). False if another holds it, or the platform or
/// file system has no such locks.
fn try_lock(file: &File) -> bool {
    #[cfg(unix)]
    {
        rustix::fs::flock(file, rustix::fs::FlockOperation::NonBlockingLockExclusive).is_ok()
    }
    #[cfg(not(unix))]
    {
        let _ = file;
        false
    }
}

/// Removes `candidate` if it is a regular file, old enough, and unlocked (its writer is gone).
fn remove_if_stale(candidate: &Path) -> io::Result<bool> {
    let meta = std::fs::symlink_metadata(candidate)?;
    if !meta.file_type().is_file() || meta.modified()?.elapsed().unwrap_or_default() < STALE_TEMP_AGE {
        return Ok(false);
    }
    let file = File::open(candidate)?;
    if !try_lock(&file) {
        return Ok(false);
    }
    // The name still leads to the file we locked (nobody replaced it in between).
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        let (now, held) = (std::fs::symlink_metadata(candidate)?, file.metadata()?);
        if (now.dev(), now.ino()) != (held.dev(), held.ino()) {
            return Ok(false);
        }
    }
    std::fs::remove_file(candidate)?;
    Ok(true)
}

/// Writes a file atomically through a buffered writer (see [`AtomicFile`]). A path that exists
/// and is not a regular file (`/dev/null`, a FIFO, `/dev/stdout`) is written in place instead:
/// replacing a device node by a rename would break it for every other program.
pub fn write_atomically<T>(path: &Path, write: impl FnOnce(&mut BufWriter<&File>) -> io::Result<T>) -> io::Result<T> {
    if special_file(path).is_some() {
        let file = File::options().write(true).open(path)?;
        let mut w = BufWriter::with_capacity(1 << 20, &file);
        let value = write(&mut w)?;
        w.flush()?;
        return Ok(value);
    }
    let tmp = AtomicFile::create(path)?;
    let value = {
        let mut w = BufWriter::with_capacity(1 << 20, tmp.file());
        let value = write(&mut w)?;
        w.flush()?;
        value
    };
    tmp.commit()?;
    Ok(value)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn listed(path: &Path) -> bool {
        registry().live.contains(path)
    }

    /// A temporary file is listed from its creation to its rename or its removal. (Interrupting
    /// is tested in `tests/interrupt.rs`, a process of its own: it stops every later write.)
    #[test]
    fn live_temporary_files_are_listed_until_committed_or_dropped() {
        let dir = tempfile::tempdir().unwrap();
        let committed = AtomicFile::create(&dir.path().join("a.bin")).unwrap();
        let dropped = AtomicFile::create(&dir.path().join("b.bin")).unwrap();
        let (a, b) = (committed.temp_path().to_path_buf(), dropped.temp_path().to_path_buf());
        assert!(listed(&a) && listed(&b));
        committed.commit().unwrap();
        drop(dropped);
        assert!(!listed(&a) && !listed(&b));
        assert!(dir.path().join("a.bin").exists() && !b.exists());
    }
}
