//! Shard files (`formats/vlf-shard.md`): the part of a field that one machine of a build farm
//! bakes. A shard is the field's container (header, section table, BLAKE3 per section) with its
//! own magic, so it can never be opened as a field; its first section is a SHARD record saying
//! which directions it holds and of which bake, then come the field's shared sections, then the
//! per-direction sections restricted to its directions.

use crate::layout::SectionEntry;

// The shard's on-disk constants live with the rest of the layout; re-exported here, where a
// reader of `formats/vlf-shard.md` looks for them.
pub use crate::layout::{SHARD_MAGIC, ShardRecord};
pub use crate::section::{PER_DIRECTION_KINDS, SHARD_KIND, is_per_direction};

/// The directions `⌊K·l/N⌋ .. ⌊(K+1)·l/N⌋` of shard `K` of `N` (`formats/vlf-shard.md` §2):
/// contiguous, in index order, covering `0..l` exactly once over `K = 0..N`.
pub fn shard_directions(index: u32, count: u32, direction_count: u32) -> std::ops::Range<u32> {
    let at = |k: u32| (k as u64 * direction_count as u64 / count.max(1) as u64) as u32;
    at(index)..at(index + 1)
}

/// BLAKE3 over the table entries of the shared sections, in table order: what every shard of
/// one bake must agree on (`formats/vlf-shard.md` §3).
pub fn shared_hash<'a>(shared: impl IntoIterator<Item = &'a SectionEntry>) -> [u8; 32] {
    let mut h = blake3::Hasher::new();
    h.update(b"VLF-SHARED\0");
    for e in shared {
        h.update(&e.kind.to_le_bytes());
        h.update(&e.element_size.to_le_bytes());
        h.update(&e.raw_length.to_le_bytes());
        h.update(&e.raw_hash);
    }
    *h.finalize().as_bytes()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Any split covers every direction exactly once, in order, with sizes differing by at most one.
    #[test]
    fn shard_ranges_partition_the_directions() {
        for l in [1u32, 3, 9, 129, 2049] {
            for n in 1..=9u32 {
                let ranges: Vec<_> = (0..n).map(|k| shard_directions(k, n, l)).collect();
                assert_eq!(ranges[0].start, 0);
                assert_eq!(ranges[n as usize - 1].end, l);
                for w in ranges.windows(2) {
                    assert_eq!(w[0].end, w[1].start);
                }
                let sizes: Vec<u32> = ranges.iter().map(|r| r.len() as u32).collect();
                assert!(sizes.iter().max().unwrap() - sizes.iter().min().unwrap() <= 1, "{l} in {n}: {sizes:?}");
            }
        }
    }
}
