//! What a piece of work may plan to allocate, as the operating system tells it: the one rule of
//! every up-front memory check in the project. It lives here because opening a packed field
//! decodes it into memory ([`crate::OpenOptions::max_unpacked_bytes`]); the baker's checks and
//! the command line's use it through `vlf_bake::memory`.

/// The most memory a piece of work may plan to use, and where that figure comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Budget {
    /// The bytes.
    pub bytes: u64,
    /// Where they come from.
    pub source: Source,
}

/// Where a [`Budget`] comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Source {
    /// Three quarters of what is available.
    Available {
        /// What the system reports available (`MemAvailable` on Linux), else a fixed 4 GiB.
        available: u64,
        /// Whether the system reported nothing, so that `available` is the fixed 4 GiB.
        assumed: bool,
    },
    /// What the process's address-space limit (`ulimit -v`) leaves, where that is less.
    AddressSpace {
        /// The limit, in bytes.
        limit: u64,
    },
}

impl Budget {
    /// Whether the figure is the system's own, not the 4 GiB assumed where it reports nothing.
    pub fn is_reported(&self) -> bool {
        !matches!(self.source, Source::Available { assumed: true, .. })
    }
}

/// Three quarters of what the system has available (`MemAvailable` on Linux, else a fixed 4 GiB),
/// and no more than the process's address-space limit (`ulimit -v`) leaves. Reads `/proc` each
/// time: what is available changes while other processes run.
pub fn budget() -> Budget {
    budget_of(available_memory(), address_space())
}

/// The share of what the system reports available that [`budget`] plans on.
const MEMORY_SHARE: (u64, u64) = (3, 4);

/// Where `/proc/meminfo` does not exist: the memory assumed available.
pub const ASSUMED_AVAILABLE: u64 = 4 << 30;

/// [`budget`] for what the system reports: `MemAvailable`, and the address-space limit and what
/// is used of it.
pub fn budget_of(available: Option<u64>, address_space: Option<(u64, u64)>) -> Budget {
    let (available, assumed) = match available {
        Some(a) => (a, false),
        None => (ASSUMED_AVAILABLE, true),
    };
    let share = available / MEMORY_SHARE.1 * MEMORY_SHARE.0;
    let mut budget = Budget { bytes: share, source: Source::Available { available, assumed } };
    if let Some((limit, used)) = address_space {
        let left = limit.saturating_sub(used);
        if left < budget.bytes {
            budget = Budget { bytes: left, source: Source::AddressSpace { limit } };
        }
    }
    budget
}

/// `MemAvailable` of `/proc/meminfo`: what can be allocated without swapping.
fn available_memory() -> Option<u64> {
    kilobytes_of(&std::fs::read_to_string("/proc/meminfo").ok()?, "MemAvailable:")
}

/// The soft address-space limit (`ulimit -v`) if there is one, and the address space the process
/// already uses (`VmSize`), from `/proc/self/limits` and `/proc/self/status`.
pub fn address_space() -> Option<(u64, u64)> {
    let limits = std::fs::read_to_string("/proc/self/limits").ok()?;
    let line = limits.lines().find(|l| l.starts_with("Max address space"))?;
    let limit: u64 = line["Max address space".len()..].split_whitespace().next()?.parse().ok()?;
    let used = std::fs::read_to_string("/proc/self/status").ok().and_then(|s| kilobytes_of(&s, "VmSize:"));
    Some((limit, used.unwrap_or(0)))
}

/// The value of a `NAME: N kB` line of a `/proc` file, in bytes.
fn kilobytes_of(text: &str, name: &str) -> Option<u64> {
    let line = text.lines().find(|l| l.starts_with(name))?;
    let kb: u64 = line[name.len()..].trim().trim_end_matches("kB").trim().parse().ok()?;
    kb.checked_mul(1024)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn proc_lines_are_read_in_bytes() {
        let meminfo = "MemTotal:       24000000 kB\nMemAvailable:   22863076 kB\n";
        assert_eq!(kilobytes_of(meminfo, "MemAvailable:"), Some(22_863_076 * 1024));
        assert_eq!(kilobytes_of(meminfo, "MemFree:"), None);
        let info = "MemTotal:       24683652 kB\nMemFree:         1745980 kB\nMemAvailable:   22943456 kB\n";
        assert_eq!(kilobytes_of(info, "MemAvailable:"), Some(22_943_456 * 1024));
        assert_eq!(kilobytes_of(info, "VmSize:"), None);
        assert_eq!(kilobytes_of("MemAvailable: lots kB", "MemAvailable:"), None);
    }

    #[test]
    fn the_budget_is_a_share_of_what_is_available() {
        // What this machine reports changes from one read to the next while other processes run,
        // so only its sign is checked here.
        assert!(budget().bytes > 0);
        let gib = 1u64 << 30;
        let available = |a, assumed| Source::Available { available: a, assumed };
        assert_eq!(budget_of(Some(20 * gib), None), Budget { bytes: 15 * gib, source: available(20 * gib, false) });
        let assumed = budget_of(None, None);
        assert_eq!(assumed, Budget { bytes: ASSUMED_AVAILABLE / 4 * 3, source: available(ASSUMED_AVAILABLE, true) });
        assert!(!assumed.is_reported() && budget_of(Some(gib), None).is_reported());
        let limited = budget_of(Some(20 * gib), Some((4 * gib, gib)));
        assert_eq!(limited, Budget { bytes: 3 * gib, source: Source::AddressSpace { limit: 4 * gib } });
        assert!(limited.is_reported() && budget_of(None, Some((2 * gib, 0))).is_reported());
        assert_eq!(budget_of(Some(20 * gib), Some((64 * gib, gib))).bytes, 15 * gib, "a loose limit changes nothing");
    }
}
