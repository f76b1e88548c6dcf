//! The memory a bake's directions need against what this process can still use, checked before
//! the directions are baked: a grid too fine for the machine is refused in one line instead of
//! by the allocator's abort midway (whose temporary files would stay behind).
//!
//! A thread baking a direction touches about 12 bytes a tile (the counting sort's two arrays of
//! tile starts and the direction's TILES entries), and about 12 more a tile stay in flight for
//! each of its directions queued to the writer (the TILES entries of up to two chunks ahead, and
//! the one being sent): about 24 bytes a tile on each thread in all. The buffers are reserved
//! with more room than they touch (the blocks' words are reserved at one per tile and more), so
//! against an address-space limit (`ulimit -v`) a thread needs about 56 bytes a tile.
//!
//! Each triangle-tile pair of a direction (an entry, `crate::floor`) takes 40 bytes more while
//! the direction is baked: 16 where it is rasterised, 16 where it is sorted by tile and 8 for its
//! ref in the block's words. The rasterised list grows by doubling, so 56 bytes of address space.
//! Where tiles are much smaller than the triangles, these dominate.
//!
//! Every thread bakes a direction of its own at the same time (`crate::writer` hands each chunk's
//! directions to the threads, one at a time each), so the tiles and the entries count once for
//! each thread, up to the directions there are. Besides, the bake holds its field's direction
//! tables: the DIRECTIONS, ROTATIONS and LOOKUP sections (`crate::sections::parameter_bytes`, 88
//! bytes a direction, and LOOKUP's 8 twice while it is built) and a BEAMS record for each
//! direction it bakes (32), whatever its threads: 4.3 GiB for the 2²⁵ + 1 directions of the largest lattice (one triangle on one
//! tile peaked at 4.0 GiB).

use crate::error::BakeError;
use crate::params::human_bytes;
use vlf_runtime::memory::{self, Source};

/// Bytes of memory a bake touches per tile of one direction, per thread.
pub const TOUCHED_PER_TILE: u64 = 24;

/// Bytes of address space a bake reserves per tile of one direction, per thread.
pub const RESERVED_PER_TILE: u64 = 56;

/// Bytes of memory a bake touches per entry (triangle-tile pair) of the direction it bakes.
pub const TOUCHED_PER_ENTRY: u64 = 40;

/// Bytes of address space a bake reserves per entry of the direction it bakes.
pub const RESERVED_PER_ENTRY: u64 = 56;

/// `Err` if baking `directions` directions of `tiles × tiles` tiles on `threads` threads, with
/// `entries` triangle-tile pairs (at least) in the direction that makes the most
/// (`crate::floor`), and `tables` bytes of direction tables held meanwhile, needs more memory
/// than [`budget`] allows, or more address space than an address-space limit leaves (as far as
/// the operating system tells: Linux's `/proc`; a failed allocation is still an error, not an
/// abort). Each thread that has a direction to bake counts a grid and the largest direction's
/// entries. Measured on the 3,674-triangle bunny at 8,192² tiles (45 million entries or more in
/// a direction), peak resident against this figure: 3 directions, 2.8 GB on one thread against
/// 3.4 GB, 4.2–4.4 GB on two against 6.8 GB; 9 directions, 2.8–2.9 GB against 3.5 GB, 5.2–5.5 GB
/// on two against 6.9 GB, where counting one direction's entries gave 5.1 GB.
pub fn check(tiles: u32, threads: usize, directions: u64, entries: u64, tables: u64) -> Result<(), BakeError> {
    let threads = threads.max(1).min(directions.max(1).try_into().unwrap_or(usize::MAX));
    let grid = tiles as u64 * tiles as u64;
    let (budget, why) = budget();
    let address_space = memory::address_space().map(|(limit, used)| {
        let why = format!("what the address-space limit of {} (ulimit -v) leaves", human_bytes(limit));
        (limit.saturating_sub(used), why)
    });
    for ((per_tile, per_entry), (allowed, why)) in [
        ((TOUCHED_PER_TILE, TOUCHED_PER_ENTRY), Some((budget, why))),
        ((RESERVED_PER_TILE, RESERVED_PER_ENTRY), address_space),
    ]
    .into_iter()
    .filter_map(|(per, limit)| Some((per, limit?)))
    {
        let direction = grid.saturating_mul(per_tile).saturating_add(entries.saturating_mul(per_entry));
        let need = direction.saturating_mul(threads as u64).saturating_add(tables);
        if need > allowed {
            return Err(BakeError::NotEnoughMemory {
                tiles,
                threads,
                per_tile,
                per_entry,
                entries,
                tables: human_bytes(tables),
                need: human_bytes(need),
                allowed: format!("{} may be used ({why})", human_bytes(allowed)),
            });
        }
    }
    Ok(())
}

/// The most memory a piece of work may plan to use, and where that comes from (for messages):
/// [`vlf_runtime::memory::budget`], three quarters of what the system has available
/// (`MemAvailable` on Linux, else a fixed 4 GiB), and no more than the process's address-space
/// limit (`ulimit -v`) leaves. The one rule every up-front memory check uses: the tile grids
/// here, the glTF import, the command line's pictures and flattened scenes, and the runtime's
/// default cap on decoding a packed field.
pub fn budget() -> (u64, String) {
    let b = memory::budget();
    (b.bytes, why(&b))
}

/// Where a budget comes from, in words.
fn why(b: &memory::Budget) -> String {
    match b.source {
        Source::Available { available, assumed } => {
            let source = if assumed { "assumed available" } else { "available" };
            format!("three quarters of the {} {source}", human_bytes(available))
        }
        Source::AddressSpace { limit } => {
            format!("what the address-space limit of {} (ulimit -v) leaves", human_bytes(limit))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_budget_says_where_it_comes_from() {
        let (bytes, said) = budget();
        assert!(bytes > 0, "{said}");
        let gib = 1u64 << 30;
        let b = |a, l| why(&memory::budget_of(a, l));
        assert_eq!(b(Some(20 * gib), None), "three quarters of the 20.0 GiB available");
        assert_eq!(b(None, None), "three quarters of the 4.0 GiB assumed available");
        assert_eq!(
            b(Some(20 * gib), Some((4 * gib, gib))),
            "what the address-space limit of 4.0 GiB (ulimit -v) leaves"
        );
    }

    #[test]
    fn a_grid_past_any_machine_is_refused_by_its_numbers() {
        // 65,536² tiles on 2 threads: about 206 GB touched, 481 GB reserved.
        let e = check(65_536, 2, 3, 1, 0).expect_err("no machine running these tests has 206 GB free");
        let text = e.to_string();
        assert!(text.contains("65536 × 65536 tiles on 2 thread(s)") && text.contains("lower --tiles"), "{text}");
        check(16, 2, 3, 1000, 0).expect("a small grid fits");
    }

    #[test]
    fn entries_past_any_machine_are_refused_whatever_the_grid() {
        // 16² tiles, but 2⁴⁰ triangle-tile pairs in the largest direction: 40 TiB touched.
        let text = check(16, 2, 3, 1 << 40, 0).expect_err("no machine running these tests has 40 TiB free").to_string();
        assert!(text.contains("triangle-tile pairs, 1099511627776 or more in the largest direction"), "{text}");
        check(16, 2, 3, 1 << 20, 0).expect("a megabyte of pairs fits");
    }

    #[test]
    fn every_thread_with_a_direction_counts_its_entries() {
        // Entries that take 60% of the budget in one direction: one thread fits, two do not,
        // unless there is one direction only. (The budget moves while other processes run, not
        // by half.)
        let entries = budget().0 / TOUCHED_PER_ENTRY / 10 * 6;
        check(1, 1, 9, entries, 0).expect("one thread");
        check(1, 2, 1, entries, 0).expect("two threads, one direction");
        let text = check(1, 2, 9, entries, 0).expect_err("two threads, two directions at once").to_string();
        assert!(text.contains("on 2 thread(s)"), "{text}");
        let text = check(1, 8, 2, entries, 0).expect_err("eight threads, two directions").to_string();
        assert!(text.contains("on 2 thread(s)"), "{text}");
    }

    #[test]
    fn the_direction_tables_count_whatever_the_threads() {
        let text = check(1, 1, 3, 1, 1 << 50).expect_err("no machine has a PiB free").to_string();
        assert!(text.contains("its direction tables 1024.0 TiB"), "{text}");
    }
}
