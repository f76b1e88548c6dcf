//! What the machine has, checked before the work that would need more: the free space of the file
//! system an output goes to, and the memory a picture needs. A command that cannot fit refuses at
//! once with one line naming both numbers, instead of filling the disk, failing an allocation with
//! an abort, or being killed by the kernel after minutes of work.

use anyhow::{Result, bail};
use std::path::Path;
use vlf_bake::atomic::parent_dir;
use vlf_bake::params::human_bytes;

/// The most memory a command may plan to use: this fraction of what the system reports available,
/// so that the rest of the machine (and the estimate's slack) keeps room.
const MEMORY_SHARE: (u64, u64) = (3, 4);

/// Where `/proc/meminfo` does not exist: the memory assumed available.
const ASSUMED_AVAILABLE: u64 = 4 << 30;

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

/// Refuses to go on if `needed` bytes of memory are more than [`memory_budget`]. `what` names the
/// work and its parts (`a 20000×20000 picture (framebuffer 16.4 GiB, …)`).
pub fn check_memory(needed: u64, what: &str) -> Result<()> {
    let (budget, why) = memory_budget();
    if needed > budget {
        bail!("{what} needs {} of memory, but {} may be used ({why})", human_bytes(needed), human_bytes(budget));
    }
    Ok(())
}

/// The memory a command may plan to use, and where that comes from: three quarters of what the
/// system has available (`MemAvailable` on Linux, else a fixed 4 GiB), and no more than the
/// process's address-space limit (`ulimit -v`) leaves.
fn memory_budget() -> (u64, String) {
    budget_of(available_memory(), address_space())
}

/// [`memory_budget`] for what the system reports: `MemAvailable`, and the address-space limit and
/// what is used of it.
fn budget_of(available: Option<u64>, address_space: Option<(u64, u64)>) -> (u64, String) {
    let (available, source) = match available {
        Some(a) => (a, "available"),
        None => (ASSUMED_AVAILABLE, "assumed available"),
    };
    let share = available / MEMORY_SHARE.1 * MEMORY_SHARE.0;
    let mut why = format!("three quarters of the {} {source}", human_bytes(available));
    let mut budget = share;
    if let Some((limit, used)) = address_space {
        let left = limit.saturating_sub(used);
        if left < budget {
            budget = left;
            why = format!("what the address-space limit of {} (ulimit -v) leaves", human_bytes(limit));
        }
    }
    (budget, why)
}

/// `MemAvailable` of `/proc/meminfo`: what can be allocated without swapping.
fn available_memory() -> Option<u64> {
    let info = std::fs::read_to_string("/proc/meminfo").ok()?;
    kilobytes_of(&info, "MemAvailable:")
}

/// The value of a `NAME: N kB` line of a `/proc` file, in bytes.
fn kilobytes_of(text: &str, name: &str) -> Option<u64> {
    let line = text.lines().find(|l| l.starts_with(name))?;
    let kb: u64 = line[name.len()..].trim().trim_end_matches("kB").trim().parse().ok()?;
    kb.checked_mul(1024)
}

/// The free space of the file system holding `dir`, for an unprivileged writer.
fn free_space(dir: &Path) -> Option<u64> {
    #[cfg(unix)]
    {
        let s = rustix::fs::statvfs(dir).ok()?;
        Some(s.f_bavail.saturating_mul(s.f_frsize))
    }
    #[cfg(not(unix))]
    {
        let _ = dir;
        None
    }
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

/// The soft address-space limit (`ulimit -v`) if there is one, and the address space the process
/// already uses (`VmSize`).
fn address_space() -> Option<(u64, u64)> {
    #[cfg(unix)]
    {
        let limit = rustix::process::getrlimit(rustix::process::Resource::As).current?;
        let used = std::fs::read_to_string("/proc/self/status").ok().and_then(|s| kilobytes_of(&s, "VmSize:"));
        Some((limit, used.unwrap_or(0)))
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
    fn proc_lines_are_read_in_bytes() {
        let info = "MemTotal:       24683652 kB\nMemFree:         1745980 kB\nMemAvailable:   22943456 kB\n";
        assert_eq!(kilobytes_of(info, "MemAvailable:"), Some(22_943_456 * 1024));
        assert_eq!(kilobytes_of(info, "VmSize:"), None);
        assert_eq!(kilobytes_of("MemAvailable: lots kB", "MemAvailable:"), None);
    }

    #[test]
    fn the_budget_is_a_share_of_what_is_available() {
        // What this machine reports (it changes from one read to the next while other processes
        // run, so only its sign is checked here).
        let (budget, why) = memory_budget();
        assert!(budget > 0, "{why}");
        // The rule, on fixed figures.
        let gib = 1u64 << 30;
        assert_eq!(budget_of(Some(20 * gib), None), (15 * gib, "three quarters of the 20.0 GiB available".into()));
        assert_eq!(budget_of(None, None).0, ASSUMED_AVAILABLE / 4 * 3);
        assert!(budget_of(None, None).1.ends_with("assumed available"));
        assert_eq!(
            budget_of(Some(20 * gib), Some((4 * gib, gib))),
            (3 * gib, "what the address-space limit of 4.0 GiB (ulimit -v) leaves".into())
        );
        assert_eq!(budget_of(Some(20 * gib), Some((64 * gib, gib))).0, 15 * gib, "a loose limit changes nothing");
    }

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
