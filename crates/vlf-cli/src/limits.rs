//! What the machine has, checked before the work that would need more: the free space of the file
//! system an output goes to, and the memory a picture needs. A command that cannot fit refuses at
//! once with one line naming both numbers, instead of filling the disk, failing an allocation with
//! an abort, or being killed by the kernel after minutes of work.

use anyhow::{Result, bail};
use std::path::Path;
use vlf_bake::atomic::parent_dir;
use vlf_bake::disk::free_space;
use vlf_bake::params::human_bytes;

/// Refuses an output of `needed` bytes (at most, if `at_most`) at `path` that the file system of
/// its directory has no room for, or that the process's file size limit (`ulimit -f`) forbids.
/// `what` names the output (`the rays file`). An existing device or FIFO (`/dev/null`) takes any
/// size; a directory that does not exist is left for the write to report.
pub fn check_disk(path: &Path, needed: u64, at_most: bool, what: &str) -> Result<()> {
    if crate::values::is_special_file(path) {
        return Ok(());
    }
    let dir = parent_dir(path);
    let needs = if at_most { "needs up to" } else { "needs" };
    if let Some(free) = free_space(&dir)
        && needed > free
    {
        bail!(
            "{what} {needs} {} but the file system of {} has {} free",
            human_bytes(needed),
            dir.display(),
            human_bytes(free)
        );
    }
    if let Some(limit) = file_size_limit()
        && needed > limit
    {
        bail!(
            "{what} {needs} {} but this process may not write files over {} (ulimit -f)",
            human_bytes(needed),
            human_bytes(limit)
        );
    }
    Ok(())
}

/// Refuses outputs whose directory cannot take a new file: one that does not exist, a file where
/// it should be, no permission to write, a read-only file system, a path that is a directory.
/// Creating (and at once removing) a file there is the one honest test. `outputs` pair each
/// path with its flag (`-o/--output`). An existing device or FIFO (`/dev/null`) is left alone.
pub fn check_writable(outputs: &[(&str, &Path)]) -> Result<()> {
    for (flag, path) in outputs {
        if crate::values::is_special_file(path) {
            continue;
        }
        if path.is_dir() {
            bail!("cannot write {flag} {}: it is a directory", path.display());
        }
        let dir = parent_dir(path);
        let probe = dir.join(format!(".vlf-bake-write-test-{}.tmp", std::process::id()));
        match std::fs::OpenOptions::new().write(true).create_new(true).open(&probe) {
            Ok(_) => {
                let _ = std::fs::remove_file(&probe);
            }
            Err(e) => bail!("cannot write {flag} {}: cannot create a file in {}: {e}", path.display(), dir.display()),
        }
    }
    Ok(())
}

/// Refuses outputs that exist and are neither a regular file nor a directory (a device, FIFO or
/// socket: `/dev/null`, `/dev/full`), for the outputs that must be files: fields and shards, made
/// in a temporary file with positioned writes and renamed into place, and reports. Checked before
/// the work, so that `bake -o /dev/null` does not import and choose parameters for seconds only to
/// be refused by the write. (A directory is [`check_writable`]'s to refuse.)
pub fn check_regular_outputs(outputs: &[(&str, &Path)]) -> Result<()> {
    for (flag, path) in outputs {
        if let Ok(meta) = std::fs::metadata(path)
            && !meta.is_dir()
            && let Err(e) = vlf_runtime::regular::check_regular_file(&meta)
        {
            bail!("cannot write {flag} {}: {e}; give the path of a file", path.display());
        }
    }
    Ok(())
}

/// Refuses to go on if `needed` bytes of memory are more than the budget of
/// [`vlf_bake::memory::budget`] (the one rule of every up-front memory check). `what` names the
/// work and its parts (`a 20000×20000 picture (framebuffer 16.4 GiB, …)`).
pub fn check_memory(needed: u64, what: &str) -> Result<()> {
    let (budget, why) = vlf_bake::memory::budget();
    if needed > budget {
        bail!("{what} needs {} of memory, but {} may be used ({why})", human_bytes(needed), human_bytes(budget));
    }
    Ok(())
}

/// The soft file size limit (`ulimit -f`), if there is one.
fn file_size_limit() -> Option<u64> {
    #[cfg(unix)]
    {
        rustix::process::getrlimit(rustix::process::Resource::Fsize).current
    }
    #[cfg(not(unix))]
    {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn outputs_larger_than_the_free_space_are_refused_naming_both() {
        let dir = std::env::temp_dir();
        let free = free_space(&dir).expect("statvfs of the temporary directory");
        let path = dir.join("out.bin");
        assert!(check_disk(&path, 1, false, "the file").is_ok());
        let e = check_disk(&path, free.saturating_add(1 << 30), false, "the file").unwrap_err().to_string();
        assert!(e.starts_with("the file needs ") && e.contains(" free"), "{e}");
        assert!(e.contains(&format!("the file system of {} has", dir.display())), "{e}");
        // A device takes anything.
        #[cfg(unix)]
        assert!(check_disk(Path::new("/dev/null"), u64::MAX, false, "the file").is_ok());
    }
}
