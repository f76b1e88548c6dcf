//! The memory a bake's tile grids need against what this process can still use, checked before
//! the directions are baked: a grid too fine for the machine is refused in one line instead of
//! by the allocator's abort midway (whose temporary files would stay behind).
//!
//! A thread baking a direction touches about 12 bytes a tile (the counting sort's two arrays of
//! tile starts and the direction's TILES entries), and about 12 more a tile stay in flight for
//! each of its directions queued to the writer (the TILES entries of up to two chunks ahead, and
//! the one being sent): about 24 bytes a tile on each thread in all. The buffers are reserved
//! with more room than they touch (the blocks' words are reserved at one per tile and more), so
//! against an address-space limit (`ulimit -v`) a thread needs about 56 bytes a tile.

use crate::error::BakeError;
use crate::params::human_bytes;

/// Bytes of memory a bake touches per tile of one direction, per thread.
pub const TOUCHED_PER_TILE: u64 = 24;

/// Bytes of address space a bake reserves per tile of one direction, per thread.
pub const RESERVED_PER_TILE: u64 = 56;

/// `Err` if baking `tiles × tiles` grids on `threads` threads needs more memory than this
/// process can use (as far as the operating system tells: Linux's `/proc`; elsewhere nothing is
/// checked, and a failed allocation is still an error, not an abort).
pub fn check(tiles: u32, threads: usize) -> Result<(), BakeError> {
    let grid = tiles as u64 * tiles as u64 * threads.max(1) as u64;
    let limits = [(TOUCHED_PER_TILE, available_memory()), (RESERVED_PER_TILE, available_address_space())];
    for (per_tile, available) in limits {
        let need = grid.saturating_mul(per_tile);
        if let Some(available) = available
            && need > available
        {
            return Err(BakeError::NotEnoughMemory {
                tiles,
                threads: threads.max(1),
                per_tile,
                need: human_bytes(need),
                available: human_bytes(available),
            });
        }
    }
    Ok(())
}

/// The bytes this process can still allocate, as far as the operating system tells (Linux's
/// `/proc`): the memory available without swapping, and under an address-space limit
/// (`ulimit -v`) the room left in it, whichever is less. `None` where nothing is known. For checks
/// of a piece of work's memory before it starts, as [`check`] does for the tile grids.
pub fn available() -> Option<u64> {
    match (available_memory(), available_address_space()) {
        (Some(m), Some(a)) => Some(m.min(a)),
        (m, a) => m.or(a),
    }
}

/// The value in kB of the line of `/proc` file `text` that starts with `key`, in bytes.
fn kb_field(text: &str, key: &str) -> Option<u64> {
    let line = text.lines().find(|l| l.starts_with(key))?;
    let kb: u64 = line[key.len()..].split_whitespace().next()?.parse().ok()?;
    Some(kb.saturating_mul(1024))
}

/// The memory the system can give without swapping (`MemAvailable`).
fn available_memory() -> Option<u64> {
    kb_field(&std::fs::read_to_string("/proc/meminfo").ok()?, "MemAvailable:")
}

/// The address space this process may still map: its soft limit (`ulimit -v`) less what it maps
/// now; `None` without a limit.
fn available_address_space() -> Option<u64> {
    let limits = std::fs::read_to_string("/proc/self/limits").ok()?;
    let line = limits.lines().find(|l| l.starts_with("Max address space"))?;
    let soft: u64 = line["Max address space".len()..].split_whitespace().next()?.parse().ok()?;
    let mapped = kb_field(&std::fs::read_to_string("/proc/self/status").ok()?, "VmSize:")?;
    Some(soft.saturating_sub(mapped))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn proc_fields_are_read_in_bytes() {
        let meminfo = "MemTotal:       24000000 kB\nMemAvailable:   22863076 kB\n";
        assert_eq!(kb_field(meminfo, "MemAvailable:"), Some(22_863_076 * 1024));
        assert_eq!(kb_field(meminfo, "MemFree:"), None);
    }

    #[test]
    fn a_grid_past_any_machine_is_refused_by_its_numbers() {
        // 65,536² tiles on 2 threads: about 206 GB touched, 481 GB reserved.
        if available_memory().is_some() {
            let e = check(65_536, 2).expect_err("no machine running these tests has 206 GB free");
            let text = e.to_string();
            assert!(text.contains("65536 × 65536 tiles on 2 thread(s)") && text.contains("lower --tiles"), "{text}");
        }
        check(16, 2).expect("a small grid fits");
    }
}
